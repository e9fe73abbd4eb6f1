"""Stepping, motors, dead time, placement, perception units and bad input of the world."""

import math

import mujoco
import numpy as np
import pytest

from robocup_gym.sim.engines.mujoco.world import SimulationDivergedError, World
from robocup_gym.sim.vision import VisionConfig
from robocup_gym.types import AgentCommand


@pytest.fixture(scope="module")
def world():
    return World([0], vision=VisionConfig(noise=False), seed=1)


def fresh(w: World) -> World:
    w.reset(seed=1)
    w.place_robot(0, -1.0, 0.0, heading_deg=0.0)
    w.place_ball((5.0, 5.0))
    return w


def test_velocity_command_moves_joint_at_commanded_speed_after_dead_time(world):
    w = fresh(world)
    i = w.robots[0].effector_names.index("he1")
    w.step({0: {"he1": 2.0}})
    assert abs(w.joint_angles_deg(0)[i]) < 0.05  # one cycle of dead time
    w.step()
    w.step()
    # acted for two cycles: 2 rad/s * 0.04 s = 4.58 deg
    assert w.joint_angles_deg(0)[i] == pytest.approx(math.degrees(0.08), abs=0.3)
    assert w.joint_velocities(0)[i] == pytest.approx(2.0, abs=0.05)


def test_zero_dead_time_acts_immediately():
    w = World([0], dead_time_cycles=0, vision=VisionConfig(noise=False))
    w.place_robot(0, -1.0, 0.0)
    i = w.robots[0].effector_names.index("he1")
    w.step({0: {"he1": 2.0}})
    assert w.joint_angles_deg(0)[i] > 1.0


def test_over_speed_is_clipped_to_max_speed(world):
    w = fresh(world)
    w.step({0: {"he1": 100.0}})
    w.step()
    assert w.robots[0].targets[0] == pytest.approx(6.13954, abs=1e-4)
    w.step()
    assert w.joint_velocities(0)[0] == pytest.approx(6.13954, abs=0.1)


def test_a_joint_driven_into_its_stop_bounces_and_takes_commands_only_inside():
    """ODE's stops (reference §2.4, §8.3): fully elastic, so a motor pushing into a stop makes the
    joint rattle against it (one cycle beyond, one cycle inside); a command that arrives while
    the joint is at or beyond the stop is ignored (the old target stays), one that arrives while
    it is inside is taken and drives it away."""
    w = World([0], dead_time_cycles=0, vision=VisionConfig(noise=False))
    w.place_robot(0, -1.0, 0.0)
    i = w.robots[0].effector_names.index("he2")  # range ±45 deg, 6 rad/s = 6.9 deg per cycle
    angles = []
    for _ in range(20):
        w.step({0: {"he2": 6.0}})
        angles.append(w.joint_angles_deg(0)[i])
    tail = np.array(angles[-8:])
    assert np.all(np.abs(tail - 45.0) < 7.5)
    assert np.all(np.diff(tail > 45.0) != 0), f"no rattle against the stop: {tail}"
    if w.joint_angles_deg(0)[i] < 45.0:
        w.step({0: {"he2": 6.0}})
    assert w.joint_angles_deg(0)[i] > 45.0
    w.step({0: {"he2": -3.0}})  # at the stop: ignored
    assert w.robots[0].targets[i] == pytest.approx(6.0)
    inside = w.joint_angles_deg(0)[i]
    assert inside < 45.0  # bounced back in
    w.step({0: {"he2": -3.0}})  # inside: taken
    assert w.robots[0].targets[i] == pytest.approx(-3.0)
    w.step()
    assert w.joint_angles_deg(0)[i] < inside - 3.0
    assert w.joint_velocities(0)[i] == pytest.approx(-3.0, abs=0.05)


def test_a_motor_that_could_not_follow_does_not_catch_up():
    """ODE's motor has no memory of the angle it was asked to reach: motion lost while it is
    saturated or at a stop is never made up afterwards (the creep compensation restarts)."""
    w = World([0], dead_time_cycles=0, vision=VisionConfig(noise=False))
    w.place_robot(0, -1.0, 0.0)
    i = w.robots[0].effector_names.index("rae4")  # range −1…90 deg
    for _ in range(20):  # into the 90 deg stop and rattling there
        w.step({0: {"rae4": 6.0}})
    while w.joint_angles_deg(0)[i] >= 90.0:
        w.step({0: {"rae4": 6.0}})
    held = w.joint_angles_deg(0)[i]  # bounced back inside, short of where 6 rad/s would be
    for _ in range(10):  # hold here: the motor stops the joint where it is
        w.step({0: {"rae4": 0.0}})
        assert w.joint_angles_deg(0)[i] == pytest.approx(held, abs=0.02)


def test_nan_command_names_the_joint(world):
    w = fresh(world)
    with pytest.raises(ValueError, match="rle3"):
        w.step({0: {"rle3": float("nan")}})
    arr = np.zeros(22)
    arr[w.robots[0].effector_names.index("lae2")] = np.inf
    with pytest.raises(ValueError, match="lae2"):
        w.step({0: arr})
    with pytest.raises(ValueError, match="shape"):
        w.step({0: np.zeros(5)})


def test_unknown_effector_lists_valid_names(world):
    w = fresh(world)
    with pytest.raises(KeyError, match="rle1"):
        w.step({0: {"rle9": 1.0}})


def test_standing_still_keeps_height(world):
    w = fresh(world)
    for _ in range(100):
        w.step({0: np.zeros(22)})
    z = w.torso_position(0)[2]
    assert z == pytest.approx(0.384, abs=0.005)
    assert w.torso_up(0)[2] > 0.999


def test_perception_units_and_frames(world):
    w = fresh(world)
    for _ in range(5):
        w.step({0: np.zeros(22)})
    p = w.perceive(0)
    assert p.joint_names[0] == "hj1" and len(p.joint_angles_deg) == 22
    assert p.accel == pytest.approx([0, 0, 9.81], abs=0.3)  # m/s², at rest
    assert np.abs(p.gyro).max() < 1.0  # deg/s
    assert set(p.force_sensors) == {"lf", "rf"}
    for f in p.force_sensors.values():
        assert f.force[2] == pytest.approx(4.6071 * 9.81 / 2, rel=0.2)  # N, foot frame
        assert abs(f.point[2]) == pytest.approx(0.01, abs=0.003)  # sole, 1 cm below centre
    assert p.time == pytest.approx(w.time)
    gt = p.ground_truth
    assert gt.torso_pos[:2] == pytest.approx([-1.0, 0.0], abs=0.01)


def _frp_from_contacts(w: World, index: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """FRP (reference §4.6) computed independently from MuJoCo's contact list: per foot/toe geom the
    sum of the contact forces acting on it and the force-magnitude-weighted mean contact point,
    in the foot frame (``None`` where contacts exist but carry no force)."""
    m, d = w.model, w.data
    r = w.robots[index]
    feet = {"rf": "rfoot", "lf": "lfoot", "rf1": "rtoe", "lf1": "ltoe"}
    geoms = {}
    for name, geom in feet.items():
        try:
            geoms[m.geom(r.prefix + geom).id] = name
        except KeyError:
            continue
    forces: dict[str, list] = {}
    for i in range(d.ncon):
        g1, g2 = d.contact.geom[i]
        if g1 not in geoms and g2 not in geoms:
            continue
        f6 = np.zeros(6)
        mujoco.mj_contactForce(m, d, i, f6)  # on geom2, contact frame
        f = d.contact.frame[i].reshape(3, 3).T @ f6[:3]
        name, sign = (geoms[g2], 1.0) if g2 in geoms else (geoms[g1], -1.0)
        forces.setdefault(name, []).append((sign * f, d.contact.pos[i].copy()))
    out = {}
    for name, items in forces.items():
        f = np.array([x[0] for x in items])
        p = np.array([x[1] for x in items])
        mag = np.linalg.norm(f, axis=1)
        if mag.sum() == 0:
            out[name] = None
            continue
        body = m.body(r.prefix + feet[name]).id
        rot = d.xmat[body].reshape(3, 3)
        cop = (mag[:, None] * p).sum(0) / mag.sum()
        out[name] = (rot.T @ (cop - d.xpos[body]), rot.T @ f.sum(0))
    return out


@pytest.mark.parametrize("types", [[0], [4, 2]])
def test_force_sensors_match_the_contacts_of_the_step(types):
    """FRP of flailing robots (feet and type-4 toes on the ground, in the air, on the ball):
    the same as summing MuJoCo's contact forces per foot geom and weighting the contact points
    by force magnitude."""
    w = World(types, seed=3)
    for i in range(len(types)):
        w.place_robot(i, -1.0 + 0.6 * i, 0.0, heading_deg=0.0)
    w.place_ball((-0.82, -0.055))
    rng = np.random.default_rng(0)
    seen = set()
    for c in range(150):
        cmds = {
            i: rng.uniform(-1, 1, len(r.max_speeds)) * r.max_speeds * (0.3 if c < 60 else 1.0)
            for i, r in enumerate(w.robots)
        }
        w.step(cmds)
        for i in range(len(types)):
            got = w.force_sensors(i)
            want = _frp_from_contacts(w, i)
            # a foot without contact is omitted; one whose contacts carry no force may repeat
            assert {k for k, v in want.items() if v is not None} <= set(got) <= set(want)
            for name, v in want.items():
                if v is None:
                    continue
                np.testing.assert_allclose(got[name].point, v[0], atol=1e-12)
                np.testing.assert_allclose(got[name].force, v[1], rtol=1e-12, atol=1e-9)
                seen.add(name)
    assert {"lf", "rf"} <= seen and (4 not in types or {"lf1", "rf1"} & seen)


def test_gyro_in_deg_per_s_torso_frame(world):
    w = fresh(world)
    w.place_robot(0, 0, 0, z=2.0)
    b = w.robots[0].qvel_root
    w.data.qvel[b + 5] = 1.0  # 1 rad/s yaw (torso z)
    assert w.gyro(0)[2] == pytest.approx(math.degrees(1.0))


def test_accelerometer_in_free_fall_reads_zero(world):
    w = fresh(world)
    w.place_robot(0, 0, 0, z=3.0)
    w.step()
    w.step()
    assert np.abs(w.perceive(0).accel).max() < 0.5


def test_asleep_robot_hangs_until_a_non_zero_command_then_lands(world):
    """ODE auto-disable after a trainer move (fixture README): the robot hangs where it was put
    (accelerometer 9.81, no foot contact) through zero-velocity cycles; the first non-zero joint
    velocity wakes it and it lands one step later with ~51 N per foot."""
    w = fresh(world)
    w.place_robot(0, -1.0, 0.0, z=0.385, asleep=True)
    r = w.robots[0]
    robot_q = np.r_[r.qpos_root : r.qpos_root + 7, r.qpos_joints]
    pose = w.data.qpos[robot_q].copy()
    zero = np.zeros(22)
    for _ in range(5):
        w.step({0: zero})
        p = w.perceive(0)
        assert p.accel == pytest.approx([0, 0, 9.81], abs=1e-9)
        assert not p.force_sensors
    np.testing.assert_array_equal(w.data.qpos[robot_q], pose)
    cmd = dict.fromkeys(w.robots[0].effector_names, 0.0)
    cmd["he1"] = 0.01
    w.step({0: cmd})  # queued: the dead time passes, still asleep
    assert w.torso_position(0)[2] == 0.385
    w.step({0: cmd})  # the command acts: awake, falling freely
    assert w.torso_position(0)[2] < 0.3835
    assert not w.force_sensors(0)
    w.step({0: cmd})  # lands
    forces = {k: float(np.linalg.norm(v.force)) for k, v in w.force_sensors(0).items()}
    assert forces["rf"] == pytest.approx(51.0, abs=5.0)
    assert forces["lf"] == pytest.approx(51.0, abs=5.0)


def test_asleep_robot_wakes_when_the_ball_hits_it(world):
    w = fresh(world)
    w.place_robot(0, -1.0, 0.0, z=0.385, asleep=True)
    w.place_ball((-0.7, -0.055), vel=(-3.0, 0.0, 0.0))
    for _ in range(10):
        w.step()
    assert not w.robots[0].asleep
    assert w.torso_position(0)[2] < 0.3845


def test_placement_is_instant_with_joint_angles(world):
    w = fresh(world)
    w.place_robot(0, 2.0, 3.0, heading_deg=90.0, joint_angles_deg={"rle3": 30.0, "lae1": -90})
    a = w.joint_angles_deg(0)
    names = w.robots[0].effector_names
    assert a[names.index("rle3")] == pytest.approx(30.0)
    assert a[names.index("lae1")] == pytest.approx(-90.0)
    assert w.torso_position(0)[:2] == pytest.approx([2.0, 3.0])
    # facing +y: torso forward axis (local +y) points to world +y
    fwd = w.data.xmat[w.robots[0].torso_body].reshape(3, 3)[:, 1]
    assert fwd == pytest.approx([0, 1, 0], abs=1e-9)
    w.place_ball((1.0, 2.0), vel=(1.0, 0.0, 0.0))
    assert w.ball_velocity() == pytest.approx([1, 0, 0])
    w.set_game(play_mode="PlayOn", game_time=12.0)
    w.step()
    assert w.perceive(0).game.game_time == pytest.approx(12.02)


def test_ball_rolls_and_slows_by_drag(world):
    w = fresh(world)
    w.place_ball((0.0, 0.0), vel=(2.0, 0.0, 0.0))
    for _ in range(50):
        w.step()
    v1 = w.ball_velocity()[0]
    assert 0.3 < v1 < 2.0 and w.ball_position()[0] > 0.5
    assert abs(w.ball_position()[2] - 0.041) < 0.003  # rolls on the ground


def test_vision_every_third_cycle_and_field_of_view(world):
    w = fresh(world)
    w.place_ball((0.0, 0.0))
    seen = []
    for _ in range(6):
        w.step()
        seen.append(w.perceive(0).vision is not None)
    assert seen == [False, False, True, False, False, True]
    v = w.vision(0)
    d, theta, phi = v.objects["B"]
    assert d == pytest.approx(
        math.dist(w.data.xpos[w.robots[0].head_body], w.ball_position()), abs=1e-6
    )
    assert abs(theta) < 1.0 and phi < 0  # straight ahead, below the head
    assert "F1L" not in v.objects  # behind the robot
    assert len(v.lines) > 0 and v.lines.shape[1:] == (2, 3)
    w.place_ball((-1.0, 3.0))  # 90 deg to the left: outside the 120 deg cone
    assert "B" not in w.vision(0).objects


def test_vision_noise_and_determinism():
    def run(seed):
        w = World([0], seed=seed)
        w.place_robot(0, -1.0, 0.0)
        w.place_ball((0.0, 0.0))
        rng = np.random.default_rng(3)
        for _ in range(20):
            w.step({0: rng.uniform(-1, 1, 22)})
        return w.vision(0).objects["B"], w.state()

    (b1, s1), (b2, s2), (b3, _) = run(5), run(5), run(6)
    assert np.array_equal(s1, s2) and np.array_equal(b1, b2)
    assert not np.array_equal(b1, b3)


def test_say_and_hear():
    w = World([0, 0], teams=["left", "right"], vision=VisionConfig(noise=False))
    w.set_team(0, "left", "A", 1)
    w.set_team(1, "right", "B", 1)
    w.step({0: AgentCommand(say="hello")})
    p0, p1 = w.perceive(0), w.perceive(1)
    assert p0.heard[0].is_self and p0.heard[0].message == "hello"
    assert p1.heard[0].team == "A" and not p1.heard[0].is_self
    assert p0.game.unum == 1 and p0.game.team_side == "left"
    assert w.perceive(0).game.unum is None  # sent once


def test_divergence_is_reported_and_world_recovers(world):
    w = fresh(world)
    w.data.qvel[w.robots[0].qvel_joints[0]] = np.nan
    with pytest.raises(SimulationDivergedError, match="reset"):
        w.step()
    w.reset()
    w.step()
    assert np.isfinite(w.data.qpos).all()


@pytest.mark.parametrize("t", [1, 2, 3])
def test_other_types_stand(t):
    w = World([t], vision=VisionConfig(noise=False))
    w.place_robot(0, -1.0, 0.0)
    for _ in range(50):
        w.step()
    assert w.torso_up(0)[2] > 0.99


def test_type4_stands_and_toes_move():
    w = World([4], vision=VisionConfig(noise=False))
    w.place_robot(0, -1.0, 0.0)
    for _ in range(50):
        w.step()
    assert w.torso_up(0)[2] > 0.99
    w.place_robot(0, -1.0, 0.0, z=3.0)
    w.step({0: {"rle7": 3.0}})
    w.step()
    w.step()
    p = w.perceive(0)
    assert len(p.joint_angles_deg) == 24 and p.joint_names[-2:] == ("llj7", "rlj7")
    assert p.joint("rlj7") > 3.0


def test_several_robots_of_both_teams_stand():
    w = World([0, 1, 2, 3], teams=["left", "right", "left", "right"])
    for _ in range(100):
        w.step()
    for i in range(4):
        assert w.torso_up(i)[2] > 0.99


def _body_velocities(w: World) -> dict[int, np.ndarray]:
    """Every robot body's (linear velocity of its centre of mass, angular velocity), world frame,
    from MuJoCo's own mj_objectVelocity on the current state."""
    import mujoco

    d = w.data  # brings poses and velocities up to the state
    out = {}
    for b in w.robots[0].robot_bodies:
        v = np.zeros(6)
        mujoco.mj_objectVelocity(w.model, d, mujoco.mjtObj.mjOBJ_BODY, int(b), v, 0)
        out[int(b)] = np.concatenate([v[3:], v[:3]])
    return out


def test_drag_on_every_robot_body_from_the_velocities_at_the_start_of_the_cycle(world):
    w = fresh(world)
    rng = np.random.default_rng(0)
    vmax = w.robots[0].max_speeds
    for _ in range(10):
        w.step({0: rng.uniform(-1, 1, len(vmax)) * vmax})
    before = _body_velocities(w)
    assert max(np.abs(v).max() for v in before.values()) > 0.1  # the robot is moving
    # the forces in effect while MuJoCo integrates this cycle (spy on mj_step2)
    import mujoco

    import robocup_gym.sim.engines.mujoco.world as world_module

    seen = []

    class Spy:
        def __getattr__(self, name):
            return getattr(mujoco, name)

        def mj_step2(self, m, d):
            seen.append(d.xfrc_applied.copy())
            mujoco.mj_step2(m, d)

    world_module.mujoco = Spy()
    try:
        w.step({0: rng.uniform(-1, 1, len(vmax)) * vmax})
    finally:
        world_module.mujoco = mujoco
    assert len(seen) == w.substeps
    for b, v in before.items():
        # F = −0.01 v at the centre of mass, τ = −0.01 ω (reference §7.5), held over the cycle
        np.testing.assert_allclose(seen[0][b], -0.01 * v, rtol=1e-9, atol=1e-15)


def test_body_poses_are_up_to_date_after_a_step(world):
    import mujoco

    w = fresh(world)
    vmax = w.robots[0].max_speeds
    for _ in range(5):
        w.step({0: vmax})
    d = w.data
    # MuJoCo derives poses at the start of a step; the world's data must show the new state
    ref = mujoco.MjData(w.model)
    ref.qpos[:], ref.qvel[:] = d.qpos, d.qvel
    mujoco.mj_kinematics(w.model, ref)
    mujoco.mj_comPos(w.model, ref)
    mujoco.mj_comVel(w.model, ref)
    np.testing.assert_array_equal(d.xpos, ref.xpos)
    np.testing.assert_array_equal(d.xmat, ref.xmat)
    np.testing.assert_array_equal(d.cvel, ref.cvel)
    np.testing.assert_array_equal(d.subtree_com, ref.subtree_com)
    # perception reads the new poses too (the torso's up axis from the new orientation)
    w.step({0: vmax})
    up = w.torso_up(0)
    ref.qpos[:] = w.data.qpos
    mujoco.mj_kinematics(w.model, ref)
    np.testing.assert_array_equal(up, ref.xmat[w.robots[0].torso_body].reshape(3, 3)[:, 2])


def test_accelerometer_is_the_torso_velocity_change_of_the_previous_cycle(world):
    """SimSpark samples the accelerometer before the physics step: the reading after step k is
    (v_k − v_{k−1})/0.02 + g in the torso frame, v_k the torso velocity at the start of step k."""
    w = fresh(world)
    vmax = w.robots[0].max_speeds
    r = w.robots[0]
    vel, rot = [], []
    for k in range(4):
        vel.append(w.data.qvel[r.qvel_root : r.qvel_root + 3].copy())
        rot.append(w.data.xmat[r.torso_body].reshape(3, 3).copy())
        w.step({0: (-1) ** k * vmax})
    a_world = (vel[3] - vel[2]) / 0.02 + np.array([0.0, 0.0, 9.81])
    np.testing.assert_allclose(w.perceive(0).accel, rot[3].T @ a_world, rtol=1e-9, atol=1e-9)
    assert np.abs(w.perceive(0).accel - [0, 0, 9.81]).max() > 0.1  # the flailing robot moved

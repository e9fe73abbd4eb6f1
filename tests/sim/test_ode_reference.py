"""The ODE reference world (SimSpark's physics on ODE 0.16 itself) and the MuJoCo world against it.

The surface-mixing table needs nothing; everything else needs the system library ``libode``
(Debian/Ubuntu: ``apt-get install libode8``) and is skipped, saying so, where it is missing.
"""

import os
import subprocess
import sys

import numpy as np
import pytest

from robocup_gym.sim.engines.ode import available, mix_surfaces
from robocup_gym.sim.engines.ode.surfaces import (
    BALL_SURFACE,
    GROUND_SURFACE,
    ROBOT_SURFACE,
    WALL_SURFACE,
)
from robocup_gym.sim.fidelity import load_data, scripted_kick

needs_ode = pytest.mark.skipif(
    not available(), reason="no double-precision libode here (apt-get install libode8)"
)


def test_surface_mixing_gives_the_spec_table():
    """SimSpark's rule (reference §7.3) applied to the handlers gives the pairs of its §7.4."""
    rg = mix_surfaces(ROBOT_SURFACE, GROUND_SURFACE)
    assert (rg.bounce, rg.soft_erp, rg.soft_cfm, rg.slip) == (None, 0.4, 1e-4, 0.005)
    bg = mix_surfaces(BALL_SURFACE, GROUND_SURFACE)
    assert bg.bounce == (0.8, 0.8)
    assert (bg.soft_erp, bg.soft_cfm, bg.slip) == pytest.approx((0.35, 0.05, 0.3025))
    br = mix_surfaces(BALL_SURFACE, ROBOT_SURFACE)
    assert br.bounce == (0.8, 0.8)
    assert (br.soft_erp, br.soft_cfm, br.slip) == pytest.approx((0.55, 0.02505, 0.3025))
    rr = mix_surfaces(ROBOT_SURFACE, ROBOT_SURFACE)
    assert (rr.soft_erp, rr.soft_cfm, rr.slip) == (0.6, 1e-4, 0.005)
    bw = mix_surfaces(BALL_SURFACE, WALL_SURFACE)
    assert bw.bounce == pytest.approx((0.8, 1.4))
    assert (bw.soft_erp, bw.soft_cfm, bw.slip) == (0.5, 0.05, 0.6)


def test_missing_library_is_a_clear_error():
    code = (
        "from robocup_gym.sim.engines.ode import OdeWorld, OdeUnavailableError\n"
        "try:\n    OdeWorld([0])\nexcept OdeUnavailableError as e:\n    print(e)\n"
    )
    env = dict(os.environ, ROBOCUP_GYM_LIBODE="/nonexistent/libode.so")
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    ).stdout
    assert "libode8" in out and "/nonexistent/libode.so" in out


@needs_ode
def test_reference_reproduces_the_real_servers_kick():
    """The scripted kick on ODE with the reference's parameters lands where the real server's
    did."""
    from robocup_gym.sim.engines.ode import OdeWorld

    real = load_data("kick_D.json")
    kick = scripted_kick(world=OdeWorld([0]))
    assert kick.ball_displacement_m == pytest.approx(real["ball_displacement_xy_m"], rel=0.02)
    np.testing.assert_allclose(kick.ball_final[:2], real["ball_final"][:2], atol=0.02)
    assert abs(kick.first_move_cycle - real["ball_first_moves_at_cycle"]) <= 2
    assert kick.robot_fell


@needs_ode
def test_reference_stands_and_sleeps():
    """Standing with zero velocities: upright at the real server's height (±2 mm), joints
    unmoved, and ODE's auto-disable has put the resting robot to sleep."""
    from robocup_gym.sim.engines.ode import OdeWorld

    w = OdeWorld([0])
    w.place_robot(0, -1.0, 0.0)
    for _ in range(500):
        w.step({0: np.zeros(22)})
    assert w.torso_position(0)[2] == pytest.approx(0.3829, abs=0.002)
    assert w.torso_up(0)[2] > 0.999
    assert np.abs(w.joint_angles_deg(0)).max() < 0.01
    assert w.asleep(0)


@needs_ode
def test_reference_hinge_effector_rules():
    """Clipped to the joint's max speed; a robot moved asleep hangs until a non-zero command;
    a command is ignored while its joint is at or beyond a stop."""
    from robocup_gym.sim.engines.ode import OdeWorld

    w = OdeWorld([0], dead_time_cycles=0)
    w.place_robot(0, -1.0, 0.0, z=0.385, asleep=True)
    for _ in range(5):
        w.step({0: np.zeros(22)})
    assert w.asleep(0) and w.torso_position(0)[2] == pytest.approx(0.385, abs=1e-9)
    w.step({0: {"he1": 100.0}})
    assert not w.asleep(0)
    assert w.joint_velocities(0)[0] == pytest.approx(6.13954, abs=1e-3)
    i = 1  # he2, range ±45 deg
    for _ in range(30):
        w.step({0: {"he2": 6.0}})
    if w.joint_angles_deg(0)[i] < 45.0:
        w.step({0: {"he2": 6.0}})
    w.step({0: {"he2": -3.0}})  # at the stop: ignored, the joint bounces back in at +6 target
    w.step()
    assert w.joint_angles_deg(0)[i] > 45.0


@needs_ode
@pytest.mark.parametrize(
    ("name", "torso_m", "joints_deg"),
    [
        ("stand", 0.002, 0.05),
        ("squat", 0.005, 0.2),
        ("arm_swing", 0.01, 1.0),
        ("stops", 0.005, 0.5),
        ("fall_forward", 0.05, 2.0),
        ("ball_roll", 0.002, 0.05),
    ],
)
def test_world_follows_the_reference(name, torso_m, joints_deg):
    """The MuJoCo world and ODE end a motion within a few millimetres/degrees of each other
    (torso centre at the end, RMS joint-angle difference over the motion)."""
    from robocup_gym.sim.engines.ode.compare import compare, motions

    motion = next(m for m in motions() if m.name == name)
    c = compare(motion)
    assert c.torso_final_m < torso_m
    assert c.joints_rms_deg < joints_deg
    assert c.fell[0] == c.fell[1]
    if name == "ball_roll":
        mj, ref = c.ball_travel_m
        assert mj == pytest.approx(ref, rel=0.05)


@needs_ode
def test_world_kick_is_close_to_the_reference():
    """Kick D: the MuJoCo world's ball goes within 15 % of the reference's (ODE's maximal
    coordinates let the leg's joints stretch by millimetres at kick speed, which MuJoCo's
    joints cannot: docs/reference/engines.md §2.8)."""
    from robocup_gym.sim.engines.ode.compare import compare, motions

    c = compare(next(m for m in motions() if m.name == "kick_D"))
    mj, ref = c.ball_travel_m
    assert mj == pytest.approx(ref, rel=0.15)
    assert c.fell == (True, True)


@needs_ode
def test_reference_bad_commands_are_clear_errors():
    from robocup_gym.sim.engines.ode import OdeWorld

    w = OdeWorld([0])
    with pytest.raises(ValueError, match="he1"):
        w.step({0: {"he1": float("nan")}})
    arr = np.zeros(22)
    arr[3] = np.inf
    with pytest.raises(ValueError, match="lae2"):
        w.step({0: arr})
    with pytest.raises(ValueError, match="shape"):
        w.step({0: np.zeros(5)})
    with pytest.raises(KeyError, match="rle1"):
        w.step({0: {"rle9": 1.0}})


@needs_ode
@pytest.mark.parametrize("robot_type", [1, 2, 3, 4])
def test_every_robot_type_follows_the_reference(robot_type):
    """Longer legs and arms (1, 3), other ankle speeds (2), toes (4): squatting and driving
    joints into their stops end within millimetres and a fraction of a degree of ODE."""
    import dataclasses

    from robocup_gym.sim.engines.ode.compare import compare, motions

    for name in ("squat", "stops"):
        motion = dataclasses.replace(
            next(m for m in motions() if m.name == name), robot_type=robot_type
        )
        c = compare(motion)
        assert c.torso_final_m < 0.005, (name, c)
        assert c.joints_rms_deg < 0.2, (name, c)


@needs_ode
def test_reference_placement_matches_the_world():
    """Placed with a heading, a height and joint angles, every body of the ODE robot is where
    the MuJoCo world's is (the reference's own forward kinematics from the spec tables) and its
    hinges read the angles back."""
    import mujoco

    from robocup_gym.sim.engines.mujoco.world import World
    from robocup_gym.sim.engines.ode import OdeWorld

    angles = {"rle4": -30.0, "rle3": 15.0, "lae1": -90.0, "he1": 40.0, "lle2": 10.0}
    ref = OdeWorld([0])
    ref.place_robot(0, 1.0, 2.0, heading_deg=30.0, z=0.5, joint_angles_deg=angles)
    w = World([0])
    w.place_robot(0, 1.0, 2.0, heading_deg=30.0, z=0.5, joint_angles_deg=angles)
    np.testing.assert_allclose(ref.joint_angles_deg(0), w.joint_angles_deg(0), atol=1e-9)
    for body in ("rfoot", "lfoot", "llowerarm", "head", "rshank"):
        b = mujoco.mj_name2id(w.model, mujoco.mjtObj.mjOBJ_BODY, "r0_" + body)
        np.testing.assert_allclose(ref.body_position(0, body), w.data.xipos[b], atol=1e-9)
        np.testing.assert_allclose(
            ref.body_rotation(0, body), w.data.xmat[b].reshape(3, 3), atol=1e-9
        )


def test_a_recorded_episode_replays_exactly_on_a_fresh_world():
    """What an environment told its world (placements, every cycle's commands) replays
    open-loop on another world to the same state, bit for bit."""
    import gymnasium as gym

    import robocup_gym.envs  # noqa: F401 (registers the tasks)
    from robocup_gym.sim.engines.mujoco.world import World
    from robocup_gym.sim.engines.ode.compare import record_world, replay_recording

    env = gym.make(
        "RobocupGym/VelocityKick-v0", engine="mujoco", max_episode_steps=15, wait_steps=5
    )
    world = env.unwrapped.backend.world
    rng = np.random.default_rng(0)
    with record_world(world) as rec:
        env.reset(seed=3)
        done = False
        while not done:
            _, _, term, trunc, _ = env.step(rng.uniform(-1, 1, env.action_space.shape))
            done = term or trunc
    assert rec.cycles >= 15
    assert "step" not in vars(world)  # the recording is undone
    replay = World([0])
    replay_recording(rec, replay)
    np.testing.assert_array_equal(replay.ball_position(), world.ball_position())
    np.testing.assert_array_equal(replay.torso_position(0), world.torso_position(0))
    np.testing.assert_array_equal(replay.joint_angles_deg(0), world.joint_angles_deg(0))
    env.close()
    if available():
        from robocup_gym.sim.engines.ode import OdeWorld

        ref = OdeWorld([0])
        replay_recording(rec, ref)
        assert np.all(np.isfinite(ref.ball_position())) and ref.torso_position(0)[2] > 0.0


def _flail_reference(compiled, types, cycles=400):
    """Random over-speed flailing (partial commands, re-placements, a bouncing ball) on an
    ODE world whose robots start asleep (the first command wakes them); per cycle its joints,
    torso, ball, accelerometer and foot sensors."""
    from robocup_gym.sim.engines.ode import OdeWorld

    w = OdeWorld(list(types), compiled=compiled)
    for i in range(len(types)):
        w.place_robot(i, -1.0 - i, 0.5 * i, z=0.39, asleep=True)
    w.place_ball((-0.8, -0.055, 0.3), vel=(0.5, 0.0, -1.0))
    rng = np.random.default_rng(0)
    out = []
    for c in range(cycles):
        if c < 5:  # asleep and held above the ground until the commands begin
            w.step()
            assert w.asleep(0)
            continue
        cmds = {
            i: rng.uniform(-1.5, 1.5, len(r.model.max_speeds)) * r.model.max_speeds
            for i, r in enumerate(w.robots)
        }
        if c % 7 == 3:
            cmds[0] = {"rle3": 3.0, "lae1": -9.0}
        w.step(cmds)
        if c % 60 == 59:
            w.place_robot(0, -1.0, 0.0)
            if c % 120 == 59:
                w.sense_contacts()  # a full step, undone
        if c % 50 == 25 and len(types) > 1:  # robot 1 moved out and back, as serve does
            w.import_robot_state(1, w.export_robot_state(1))
        sensors = w.force_sensors(0)
        frp = [np.r_[f.force, f.point] for _, f in sorted(sensors.items())]
        state = [w.joint_angles_deg(0), w.torso_position(0), w.ball_position(), w.accelerometer(0)]
        out.append((np.concatenate(state + frp), tuple(sensors)))
    return w, out


@needs_ode
@pytest.mark.parametrize("types", [(0,), (4, 1)])
def test_compiled_reference_loops_are_bit_equal(types):
    """The ODE world's loops in C (drag, commands, contacts: robocup_gym/sim/engines/ode/ode_step.c)
    give exactly what the Python loops give."""
    from robocup_gym.sim import compiled

    if not compiled.available():
        pytest.skip("no C compiler here (apt-get install gcc, or set CC)")
    wp, python = _flail_reference(False, types)
    wc, fast = _flail_reference(True, types)
    assert (wp.stepper, wc.stepper) == ("python", "compiled")
    assert len(python) == len(fast)
    for c, ((a, names_a), (b, names_b)) in enumerate(zip(python, fast, strict=True)):
        assert np.array_equal(a, b), f"first difference in cycle {c}"
        assert names_a == names_b, f"foot sensors in another order in cycle {c}"
    assert sum(len(names) > 1 for _, names in fast) > 10  # the order was checked


@needs_ode
@pytest.mark.parametrize("compiled", [False, True])
def test_a_body_thrown_out_of_the_world_is_a_divergence(compiled):
    """A body 1 km or more from the origin (or at NaN) ends the step with a clear error naming
    it, with the compiled loops and without; placing again recovers."""
    from robocup_gym.sim import SimulationDivergedError
    from robocup_gym.sim import compiled as compiled_step
    from robocup_gym.sim.engines.ode import OdeWorld

    if compiled and not compiled_step.available():
        pytest.skip("no C compiler here (apt-get install gcc, or set CC)")
    w = OdeWorld([0], compiled=compiled)
    w.step()
    shin = w.robots[0].bodies[w.robots[0].body_index["lshank"]]
    w._lib.dBodySetPosition(shin, 0.0, 2000.0, 0.3)
    with pytest.raises(
        SimulationDivergedError, match=r"robot 0's lshank is at \(\S+, 1\d{3}\.\d+, \S+\) m"
    ):
        w.step()
    w.place_robot(0, -1.0, 0.0)
    w.step()
    assert w.torso_position(0)[2] > 0.3


@needs_ode
def test_reference_without_a_compiler_runs_its_python_loops(monkeypatch, tmp_path):
    from robocup_gym.sim import compiled
    from robocup_gym.sim.engines.ode import OdeWorld

    monkeypatch.setenv("ROBOCUP_GYM_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    compiled.forget()
    try:
        w = OdeWorld([0])
        assert w.stepper == "python" and "no-such-cc" in w.compiled_unavailable
        w.step({0: {"lle3": 1.0}})
        with pytest.raises(compiled.CompiledStepUnavailableError, match="no-such-cc"):
            OdeWorld([0], compiled=True)
    finally:
        compiled.forget()


def _flail_together(skip_apart_pairs: bool, cycles=150):
    """Two robots flailing into each other, with the ball, next to the left goal."""
    from robocup_gym.sim.engines.ode import OdeWorld

    w = OdeWorld([0, 3])
    if not skip_apart_pairs:  # every pair goes to dCollide, as without the AABB pre-test
        w._pair_slots[:] = -1
    w.place_robot(0, -14.6, 0.9, heading_deg=180.0)
    w.place_robot(1, -14.6, 0.6, heading_deg=90.0)
    w.place_ball((-14.5, 1.3, 0.2), vel=(-2.0, 0.0, 0.0))
    rng = np.random.default_rng(5)
    out = []
    for _ in range(cycles):
        cmds = {
            i: rng.uniform(-1.0, 1.0, len(r.model.max_speeds)) * r.model.max_speeds
            for i, r in enumerate(w.robots)
        }
        w.step(cmds)
        out.append(
            np.concatenate(
                [
                    w.joint_angles_deg(0),
                    w.joint_angles_deg(1),
                    w.torso_position(0),
                    w.torso_position(1),
                    w.ball_position(),
                ]
            )
        )
    return out


@needs_ode
def test_skipping_pairs_whose_boxes_are_apart_changes_nothing():
    """The AABB pre-test only skips dCollide calls that would make no contact: the state is
    bit-equal to colliding every pair (two robots tangled at a goal post, the ball bouncing)."""
    for a, b in zip(_flail_together(True), _flail_together(False), strict=True):
        np.testing.assert_array_equal(a, b)


@needs_ode
def test_walls_and_goals_are_solid():
    from robocup_gym.sim.engines.ode import OdeWorld

    w = OdeWorld([0])
    w.place_robot(0, 0.0, 5.0)
    w.place_ball((20.0, 0.0), vel=(10.0, 0.0, 0.0))  # towards the right wall at x = 24.49
    xs = []
    for _ in range(150):
        w.step()
        xs.append(w.ball_position()[0])
    assert max(xs) < 24.49 and xs[-1] < max(xs) - 0.5  # the centre never passed the wall's face
    # into the left goal, slow enough not to pass the 4 cm back wall within one 20 ms step
    # (as on rcssserver3d, a faster ball can tunnel through it: ODE collides discretely)
    w.place_ball((-15.0, 0.0, 0.2), vel=(-3.0, 0.0, 0.0))
    xs = []
    for _ in range(100):
        w.step()
        xs.append(w.ball_position()[0])
    assert min(xs) > -15.58 and xs[-1] > min(xs)  # stopped by the back wall, bounced

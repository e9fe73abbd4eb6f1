"""One world, two physics engines: the same tests on the MuJoCo world and on SimSpark's step on
ODE. What is above the physics (placement, perception and its units, vision, hearing, game
state, several robots, determinism, bad input) must behave the same on both."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robocup_gym.sim.engines.mujoco.world import World
from robocup_gym.sim.engines.ode import OdeWorld, available
from robocup_gym.sim.vision import VisionConfig
from robocup_gym.types import AgentCommand, Perception

ENGINES = [
    "mujoco",
    pytest.param(
        "ode",
        marks=pytest.mark.skipif(
            not available(), reason="no libode here (apt-get install libode8)"
        ),
    ),
]


def make_world(engine: str, robot_types=(0,), **kw):
    return World(list(robot_types), **kw) if engine == "mujoco" else OdeWorld(robot_types, **kw)


@pytest.fixture(params=ENGINES)
def engine(request):
    return request.param


EXACT = VisionConfig(noise=False)


def _stand(world, index=0, x=-1.0, y=0.0, heading=0.0):
    world.place_robot(index, x, y, heading_deg=heading)


def test_placement_puts_the_robot_where_asked(engine):
    w = make_world(engine)
    angles = np.zeros(22)
    angles[2] = 30.0  # lae1: arm raised
    w.place_robot(0, 2.0, -3.0, heading_deg=90.0, joint_angles_deg=angles)
    pos = w.torso_position(0)
    assert pos[:2] == pytest.approx([2.0, -3.0], abs=1e-9)
    assert 0.30 < pos[2] < 0.45  # feet on the ground, 1 mm deep
    np.testing.assert_allclose(w.joint_angles_deg(0), angles, atol=1e-9)
    np.testing.assert_allclose(w.torso_up(0), [0.0, 0.0, 1.0], atol=1e-9)


@pytest.mark.parametrize(
    ("place", "message"),
    [
        (lambda w: w.place_robot(0, "1.0", 0.0), "robot placement x must be a finite number"),
        (lambda w: w.place_ball("centre"), "ball position must be 2 or 3 finite numbers"),
        (lambda w: w.place_ball((0.0, 0.0), (1.0, 2.0)), "ball velocity must be 3 finite numbers"),
        (lambda w: w.place_ball((0.0, 0.0), (0, 0, 0), "spin"), "ball angular velocity must be"),
    ],
)
def test_a_placement_of_the_wrong_kind_is_named_and_changes_nothing(engine, place, message):
    w = make_world(engine)
    _stand(w)
    w.place_ball((1.0, 2.0))
    before = (w.torso_position(0).copy(), w.ball_position().copy())
    with pytest.raises(ValueError, match=message):
        place(w)
    np.testing.assert_array_equal(w.torso_position(0), before[0])
    np.testing.assert_array_equal(w.ball_position(), before[1])


def test_both_engines_place_identically():
    if not available():
        pytest.skip("no libode here")
    a, b = make_world("mujoco"), make_world("ode")
    for w in (a, b):
        w.place_robot(0, 1.0, 2.0, heading_deg=30.0)
    np.testing.assert_allclose(a.torso_position(0), b.torso_position(0), atol=1e-9)
    np.testing.assert_allclose(a._head_pose(0)[0], b._head_pose(0)[0], atol=1e-9)
    np.testing.assert_allclose(a._part_positions(0), b._part_positions(0), atol=1e-9)


def test_perception_has_simspark_units(engine):
    w = make_world(engine)
    _stand(w)
    w.place_ball((-0.8, -0.055))
    for _ in range(10):
        w.step({0: np.zeros(22)})
    p = w.perceive(0)
    assert isinstance(p, Perception)
    assert p.time == pytest.approx(0.2) and p.joint_names[0] == "hj1"
    assert np.abs(p.joint_angles_deg).max() < 1.0  # degrees, standing still
    np.testing.assert_allclose(p.accel, [0.0, 0.0, 9.81], atol=0.3)  # m/s², torso frame
    assert np.abs(p.gyro).max() < 5.0  # deg/s
    weight = sum(fr.force[2] for fr in p.force_sensors.values())
    assert {"lf", "rf"} <= set(p.force_sensors)
    assert weight == pytest.approx(4.6071 * 9.81, rel=0.05)  # N, the whole robot on its feet
    assert p.ground_truth.ball_pos[:2] == pytest.approx([-0.8, -0.055], abs=1e-3)


def test_the_game_clock_runs_in_play_and_stops_before_kick_off(engine):
    w = make_world(engine)
    w.set_game(play_mode="BeforeKickOff", game_time=0.0)
    w.step()
    assert w.perceive(0).game.game_time == 0.0
    w.set_game(play_mode="PlayOn")
    for _ in range(5):
        w.step()
    p = w.perceive(0)
    assert p.game.play_mode == "PlayOn" and p.game.game_time == pytest.approx(0.1)


def test_vision_sees_the_same_on_both_engines():
    if not available():
        pytest.skip("no libode here")
    seen = {}
    for engine in ("mujoco", "ode"):
        w = make_world(engine, vision=EXACT, seed=1)
        _stand(w, heading=0.0)
        w.place_ball((0.5, 0.3))
        seen[engine] = w.vision(0)
    a, b = seen["mujoco"], seen["ode"]
    assert set(a.objects) == set(b.objects) and "B" in a.objects
    for name in a.objects:
        np.testing.assert_allclose(a.objects[name], b.objects[name], atol=1e-6)
    assert len(a.lines) == len(b.lines) > 0


def test_vision_every_third_cycle(engine):
    w = make_world(engine, vision=EXACT)
    _stand(w)
    got = []
    for _ in range(6):
        w.step()
        got.append(w.perceive(0).vision is not None)
    assert got == [False, False, True, False, False, True]


def test_several_robots_see_and_hear_each_other(engine):
    w = make_world(engine, robot_types=(0, 2, 4), vision=EXACT)
    for i, x in enumerate((-2.0, 0.0, 2.0)):
        w.place_robot(i, x, 0.0, heading_deg=0.0)
        w.set_team(i, "left" if i < 2 else "right", "A" if i < 2 else "B", i + 1)
    assert w.n_robots == 3
    assert len(w.perceive(2).joint_angles_deg) == 24  # type 4 has toes
    see = w.vision(0)  # robot 0 looks along +x at the other two (and sees its own limbs)
    assert {("A", 2), ("B", 3)} <= {(p.team, p.unum) for p in see.players}
    w.say(0, "hello")
    heard = {i: w.perceive(i).heard for i in range(3)}
    assert [m.message for m in heard[1]] == ["hello"] and heard[1][0].direction_deg is not None
    assert heard[0][0].direction_deg is None  # one's own message
    assert [m.message for m in heard[2]] == ["hello"]


def test_the_same_commands_give_the_same_state(engine):
    rng = np.random.default_rng(0)
    commands = rng.uniform(-3, 3, (40, 22))
    states = []
    for _ in range(2):
        w = make_world(engine, seed=3)
        _stand(w)
        w.place_ball((-0.8, -0.055))
        for c in commands:
            w.step({0: c})
        states.append(
            (w.torso_position(0), w.joint_angles_deg(0), w.ball_position(), w.perceive(0).accel)
        )
    for x, y in zip(*states, strict=True):
        np.testing.assert_array_equal(x, y)


def test_bad_input_is_a_clear_error_and_harms_nothing(engine):
    w = make_world(engine)
    _stand(w)
    with pytest.raises(ValueError, match="lle3"):
        w.step({0: {"lle3": math.nan}})
    with pytest.raises(KeyError, match="he1"):
        w.step({0: {"no_such_joint": 1.0}})
    with pytest.raises(ValueError, match="shape"):
        w.step({0: np.zeros(5)})
    with pytest.raises(ValueError, match="finite"):
        w.place_robot(0, math.nan, 0.0)
    with pytest.raises(ValueError, match="ball"):
        w.place_ball((0.0, math.inf))
    with pytest.raises(IndexError, match="out of range"):
        w.perceive(3)
    w.step({0: AgentCommand({"lle3": 1.0}).joint_velocities})  # still usable
    assert np.isfinite(w.joint_angles_deg(0)).all()


def test_make_world_chooses_the_engine(engine):
    from robocup_gym.sim import make_world as make

    w = make([0, 4], engine=engine, seed=2)
    assert type(w).__name__ == {"mujoco": "World", "ode": "OdeWorld"}[engine]
    assert w.n_robots == 2 and len(w.joint_angles_deg(1)) == 24
    with pytest.raises(ValueError, match="unknown engine 'bullet'"):
        make([0], engine="bullet")


def _blow_up(world) -> None:
    """Put a NaN velocity into the engine's state, as a solver blow-up would."""
    if isinstance(world, World):
        world.data.qvel[world.robots[0].qvel_root] = math.nan
    else:  # ODE would abort the process if it stepped this state
        world._lib.dBodySetLinearVel(world.robots[0].bodies[3], math.nan, 0.0, 0.0)


def test_a_diverged_state_is_a_clear_error_and_placement_recovers(engine):
    from robocup_gym.sim.engines.mujoco.world import SimulationDivergedError

    w = make_world(engine)
    _stand(w)
    w.step()
    _blow_up(w)
    with pytest.raises(SimulationDivergedError, match="diverged"):
        w.step()
    with pytest.raises(SimulationDivergedError):
        w.step()  # still refused, never an abort
    if engine == "mujoco":
        w.reset()
    _stand(w)
    w.place_ball((0.0, 0.0))
    for _ in range(5):
        w.step()
    assert w.torso_position(0)[2] > 0.3 and np.isfinite(w.joint_angles_deg(0)).all()


# ---------------------------------------------------------------------------- what a server uses
def test_both_engines_give_the_same_body_frames():
    """The monitor draws each body from ``body_frames``: the same poses on both engines."""
    if not available():
        pytest.skip("no libode here")
    a, b = make_world("mujoco", (4,)), make_world("ode", (4,))
    angles = np.linspace(-20.0, 20.0, 24)
    for w in (a, b):
        w.place_robot(0, 1.0, 2.0, heading_deg=30.0, joint_angles_deg=angles)
        w.place_ball((3.0, 0.0))
    (pa, ra), (pb, rb) = a.body_frames(0), b.body_frames(0)
    assert pa.shape == (len(a.robots[0].model.bodies), 3) and ra.shape[1:] == (3, 3)
    np.testing.assert_allclose(pa, pb, atol=1e-9)
    np.testing.assert_allclose(ra, rb, atol=1e-9)
    np.testing.assert_allclose(pa[0], a.torso_position(0), atol=1e-12)
    np.testing.assert_allclose(a.ball_frame()[0], b.ball_frame()[0], atol=1e-9)
    np.testing.assert_allclose(a.torso_quat(0), b.torso_quat(0), atol=1e-9)


def test_ball_touchers_are_the_robots_touching_the_ball(engine):
    w = make_world(engine, (0, 0))
    _stand(w, 0, x=-1.0)
    _stand(w, 1, x=3.0, y=3.0)
    foot = w.body_frames(0)[0][[b.name for b in w.robots[0].model.bodies].index("rfoot")]
    w.place_ball((foot[0] + 0.12, foot[1]))  # just in front of the right foot: no contact
    w.step()
    assert w.ball_touchers() == set()
    w.place_ball((foot[0] + 0.11, foot[1]))  # ball (r 4.2 cm) against the foot's toe end
    w.step()
    assert w.ball_touchers() == {0}
    w.place_ball((10.0, 0.0))
    w.step()
    assert w.ball_touchers() == set()


def test_command_queues_for_the_next_step_and_beam_keeps_the_motors(engine):
    w = make_world(engine, dead_time_cycles=0, vision=EXACT)  # (noise would move the beam)
    _stand(w)
    w.set_team(0, "left", "A", 1)
    w.command(0, {"he1": 1.0})
    w.command(0, {"he2": -0.5})  # a second command in the cycle adds to the first
    assert not w.motor_targets(0).any()  # nothing acts before the step
    w.step()
    t = w.motor_targets(0)
    assert t[0] == pytest.approx(1.0) and t[1] == pytest.approx(-0.5) and not t[2:].any()
    assert w.joint_angles_deg(0)[0] > 0.5
    w.set_game(play_mode="PlayOn")
    assert not w.beam(0, -3.0, 1.0, 0.0)  # beam only before kick-off and after goals
    w.set_game(play_mode="BeforeKickOff")
    assert w.beam(0, -3.0, 1.0, 90.0)
    np.testing.assert_allclose(w.torso_position(0), [-3.0, 1.0, 0.4], atol=1e-9)
    np.testing.assert_allclose(w.motor_targets(0), t)
    w.command(0, AgentCommand({}, beam=(-5.0, -2.0, 0.0)))
    np.testing.assert_allclose(w.torso_position(0)[:2], [-5.0, -2.0], atol=1e-9)
    with pytest.raises(ValueError, match="he1"):
        w.command(0, {"he1": math.inf})


def test_a_robot_moves_between_worlds_exactly(engine):
    """``export_robot_state``/``import_robot_state`` (the server's rebuilds): a robot in motion,
    with a command still in its dead time, goes on in a new world as in the old one."""
    rng = np.random.default_rng(1)
    commands = rng.uniform(-4.0, 4.0, (30, 22))
    a = make_world(engine, seed=2)
    _stand(a)
    a.place_ball((-0.8, -0.055))
    for c in commands[:15]:
        a.step({0: c})
    b = make_world(engine, (2, 0), seed=2)  # other robots, another size
    b.place_robot(0, 5.0, 5.0)
    b.import_robot_state(1, a.export_robot_state(0))
    b.place_ball(a.ball_position(), a.ball_velocity(), a.ball_angular_velocity())
    b.forward()
    np.testing.assert_allclose(b.torso_position(1), a.torso_position(0), atol=1e-12)
    for c in commands[15:]:
        a.step({0: c})
        b.step({1: c})
    # (ODE keeps nothing between steps; MuJoCo's solver warm start stays behind: ~1e-6°)
    tol = {"ode": 1e-9, "mujoco": 1e-5}[engine]
    np.testing.assert_allclose(b.torso_position(1), a.torso_position(0), atol=tol)
    np.testing.assert_allclose(b.joint_angles_deg(1), a.joint_angles_deg(0), atol=tol)
    np.testing.assert_allclose(b.accelerometer(1), a.accelerometer(0), atol=1e3 * tol)
    with pytest.raises(ValueError, match="type"):
        b.import_robot_state(0, a.export_robot_state(0))  # type 0 into a type-2 robot


def test_a_torso_force_pushes_the_robot_until_it_is_lifted(engine):
    """``set_torso_force`` (the training assist): a push larger than the robot's weight lifts
    it off the ground; one below it leaves a rigid standing robot standing; (0, 0, 0) ends it."""
    weight = make_world(engine).robots[0].model.total_mass * 9.81
    heights = {}
    for share in (0.0, 0.5, 1.5):
        w = make_world(engine)
        _stand(w)
        w.set_torso_force(0, (0.0, 0.0, share * weight))
        z0 = w.torso_position(0)[2]
        for _ in range(25):
            w.step()
        heights[share] = w.torso_position(0)[2] - z0
    assert abs(heights[0.0]) < 0.01 and abs(heights[0.5]) < 0.01
    # net 0.5 g upward for 0.5 s: ½ · 4.9 m/s² · (0.5 s)² = 0.61 m
    assert 0.55 < heights[1.5] < 0.67
    w = make_world(engine)
    _stand(w)
    w.set_torso_force(0, (0.0, 0.0, 1.5 * weight))
    w.set_torso_force(0, (0.0, 0.0, 0.0))
    z0 = w.torso_position(0)[2]
    for _ in range(25):
        w.step()
    assert abs(w.torso_position(0)[2] - z0) < 0.01
    for bad in ((0.0, float("nan"), 1.0), (1.0, 2.0), "up"):
        with pytest.raises(ValueError, match="three finite numbers"):
            w.set_torso_force(0, bad)

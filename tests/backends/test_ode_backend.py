"""The ``ode`` backend: SimSpark's physics on ODE itself behind the Backend interface, with the
perceptors a kick policy reads. Needs the system library ``libode`` (skipped, saying so,
without it; tests/setup_system.sh installs it)."""

import numpy as np
import pytest

from robocup_gym.backends import BackendNotAvailableError, RobotPose, make_backend
from robocup_gym.sim.engines.mujoco.world import World
from robocup_gym.sim.engines.ode import available
from robocup_gym.sim.engines.ode import lib as ode_lib
from robocup_gym.types import AgentCommand

needs_ode = pytest.mark.skipif(
    not available(), reason="no double-precision libode here (apt-get install libode8)"
)

STANDING = RobotPose(x=-1.0, y=0.0)
BALL = (-0.8, -0.055, 0.041)


def _bow(c: int) -> dict[str, float]:
    """Joint velocities (rad/s) of a scripted motion with the feet kept on the ground: the hips
    pitch the torso forward and back at 0.6 rad/s, then the left arm swings at 4 rad/s."""
    if 5 <= c < 15:
        return {"lle3": 0.6, "rle3": 0.6}
    if 15 <= c < 25:
        return {"lle3": -0.6, "rle3": -0.6}
    if 25 <= c < 35:
        return {"lae1": -4.0}
    return {"lle3": 0.0, "rle3": 0.0, "lae1": 0.0}


@needs_ode
def test_standing_perception_is_simsparks():
    """Placed standing: both feet carry half the weight (4.607 kg · 9.81 / 2 = 22.6 N) straight
    up in their own frame, the accelerometer reads gravity, the gyro nothing, the ground truth
    is where the robot and ball were put."""
    b = make_backend("ode")
    p = b.reset_episode(STANDING, BALL)
    for _ in range(20):
        p = b.step(AgentCommand())
    assert set(p.force_sensors) == {"lf", "rf"}
    for frp in p.force_sensors.values():
        np.testing.assert_allclose(frp.force, [0.0, 0.0, 22.6], atol=0.05)
        assert abs(frp.point[2] + 0.01) < 1e-3  # on the sole (foot box half height 1 cm)
    np.testing.assert_allclose(p.accel, [0.0, 0.0, 9.81], atol=0.01)
    np.testing.assert_allclose(p.gyro, 0.0, atol=0.01)
    gt = p.ground_truth
    np.testing.assert_allclose(gt.torso_pos[:2], [-1.0, 0.0], atol=1e-3)
    np.testing.assert_allclose(gt.ball_pos, BALL, atol=2e-3)
    assert p.joint_names[0] == "hj1" and len(p.joint_angles_deg) == 22
    assert p.game.play_mode == "PlayOn" and p.game.game_time == pytest.approx(0.4)
    b.close()
    b.close()  # idempotent


@needs_ode
def test_sensors_follow_the_mujoco_worlds_on_a_motion():
    """The same scripted motion on both: gyro, accelerometer, foot forces and joint angles
    agree (the motion keeps the feet down; where contacts open and close, the two engines'
    timings part and so do the sensors)."""
    b = make_backend("ode")
    b.reset_episode(STANDING, BALL)
    w = World([0])
    w.place_robot(0, STANDING.x, STANDING.y)
    w.place_ball(BALL)
    gyro, accel, joints, fz = [], [], [], []
    for c in range(50):
        p_ode = b.step(AgentCommand(_bow(c)))
        w.step({0: _bow(c)})
        p_mj = w.perceive(0)
        gyro.append((p_ode.gyro, p_mj.gyro))
        accel.append((p_ode.accel, p_mj.accel))
        joints.append((p_ode.joint_angles_deg, p_mj.joint_angles_deg))
        fz.append([sum(f.force[2] for f in p.force_sensors.values()) for p in (p_ode, p_mj)])
    gyro, accel, joints, fz = map(np.array, (gyro, accel, joints, fz))
    assert np.abs(gyro).max() > 30.0  # deg/s: the torso pitches with the hips
    assert np.abs(accel - [0.0, 0.0, 9.81]).max() > 2.0  # m/s²: and accelerates
    assert np.abs(fz - 45.2).max() > 5.0  # N: the feet feel it
    assert np.abs(gyro[:, 0] - gyro[:, 1]).max() < 2.0
    assert np.abs(accel[:, 0] - accel[:, 1]).max() < 0.5
    assert np.abs(fz[:, 0] - fz[:, 1]).max() < 2.0
    assert np.abs(joints[:, 0] - joints[:, 1]).max() < 0.1  # deg
    b.close()


@needs_ode
def test_velocity_kick_runs_on_ode_with_the_mujoco_observation():
    """An environment on the ``ode`` backend: the same observation layout, and at the start of
    an episode nearly the same values as on the embedded world."""
    from robocup_gym.envs import VelocityKick

    envs = {name: VelocityKick(backend=name) for name in ("mujoco", "ode")}
    obs = {name: env.reset(seed=0)[0] for name, env in envs.items()}
    assert obs["ode"].shape == obs["mujoco"].shape
    labels = envs["ode"].unwrapped.observation_labels
    feet = np.array([label.startswith("foot_force/") for label in labels])
    assert feet.any() and obs["ode"][feet].any()  # the feet are loaded from the first look on
    np.testing.assert_allclose(obs["ode"], obs["mujoco"], atol=0.03)
    env = envs["ode"]
    env.action_space.seed(0)
    ended = 0
    for _ in range(120):
        o, r, te, tr, info = env.step(env.action_space.sample())
        assert np.isfinite(o).all() and np.isfinite(r)
        if te or tr:
            ended += 1
            assert "ball_dx" in info or "ball_displacement" in info
            env.reset()
    assert ended >= 1
    for e in envs.values():
        e.close()


@needs_ode
def test_sensing_contacts_at_a_placement_changes_nothing():
    """The force perceptors of a freshly placed robot come from a probe step whose state is
    put back: a world that probed runs on bit for bit like one that did not."""
    from robocup_gym.sim.engines.ode import OdeWorld

    probed, plain = OdeWorld([0]), OdeWorld([0])
    for w in (probed, plain):
        w.place_robot(0, -1.0, 0.0)
        w.place_ball((-0.8, -0.055))
    assert probed.force_sensors() == {}
    probed.sense_contacts()
    loaded = probed.force_sensors()
    assert set(loaded) == {"lf", "rf"}
    assert all(abs(f.force[2] - 22.6) < 0.5 for f in loaded.values())
    for c in range(60):
        command = {0: {"lle2": 1.0 if c < 30 else -1.0}}
        probed.step(command)
        plain.step(command)
    assert np.array_equal(probed.joint_angles_deg(), plain.joint_angles_deg())
    assert np.array_equal(probed.torso_position(), plain.torso_position())
    assert np.array_equal(probed.ball_position(), plain.ball_position())


@needs_ode
def test_bad_input_is_named():
    b = make_backend("ode")
    b.reset_episode(STANDING, BALL)
    with pytest.raises(ValueError, match="lle3"):
        b.step(AgentCommand({"lle3": float("nan")}))
    with pytest.raises(KeyError, match="he1"):
        b.step(AgentCommand({"no_such_joint": 1.0}))
    with pytest.raises(ValueError, match="ball"):
        b.reset_episode(STANDING, (0.0, float("inf")))
    b.step(AgentCommand({"lle3": 1.0}))  # still usable
    b.close()


def test_missing_libode_is_a_clear_error(monkeypatch, tmp_path):
    """Without libode the backend says how to get it."""
    monkeypatch.setenv("ROBOCUP_GYM_LIBODE", str(tmp_path / "libode.so"))
    ode_lib.load.cache_clear()
    try:
        with pytest.raises(BackendNotAvailableError, match="libode8"):
            make_backend("ode")
    finally:
        ode_lib.load.cache_clear()

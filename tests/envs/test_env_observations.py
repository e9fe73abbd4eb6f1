"""Observation components (shape, units, frames), normalisation, clipping, stacking, noise."""

from __future__ import annotations

import math

import numpy as np
import pytest
from env_helpers import raw, raw_env_options

from robocup_gym.envs import COMPONENTS, DEFAULT_OBSERVATIONS, EnvConfigError, VelocityKick
from robocup_gym.sim.vision import VisionConfig

ZERO20 = np.zeros(20, dtype=np.float32)


def test_default_observation_is_the_papers():
    assert DEFAULT_OBSERVATIONS == (
        "joint_pos",
        "joint_vel",
        "ball_rel",
        "foot_force",
        "accel",
        "gyro",
        "time",
    )


@pytest.mark.parametrize("name", [n for n in COMPONENTS if n != "toe_force"])
def test_each_component_alone_has_its_documented_size(make_env, name):
    env = make_env(observations=(name,), **raw_env_options())
    obs, _ = env.reset(seed=0)
    labels = env.observation_labels
    assert obs.shape == env.observation_space.shape == (len(labels),)
    assert all(lab.startswith(name + "/") for lab in labels)
    lo, hi = env.raw_bounds
    assert lo.shape == hi.shape == obs.shape and np.all(hi > lo)
    assert np.isfinite(obs).all()


def test_toe_force_needs_robot_type_4(make_env):
    with pytest.raises(EnvConfigError, match="type 4"):
        make_env(observations=("toe_force",))
    env = make_env(observations=("toe_force", "foot_force"), robot_type=4, **raw_env_options())
    obs, _ = env.reset(seed=0)
    assert obs.shape == (24,)
    assert "toe_force/rf1_fz" in env.observation_labels


def test_joint_pos_is_degrees_and_joint_vel_is_rad_per_s(make_env):
    env = make_env(
        observations=("joint_pos", "joint_vel"),
        controlled_joints=("lae1", "rae1"),
        joint_start_deg={"lae1": -30.0, "RShoulderPitch": 45.0},
        **raw_env_options(),
    )
    obs, _ = env.reset(seed=0)
    np.testing.assert_allclose(raw(env, obs, "joint_pos"), [-30.0, 45.0], atol=1e-6)
    np.testing.assert_allclose(raw(env, obs, "joint_vel"), [0.0, 0.0])
    # half of the max speed on lae1 for a few cycles: dq/dt in rad/s, the perceived rate
    vmax = env.robot_model.max_speeds[2]
    for _ in range(6):
        obs, *_ = env.step(np.array([0.5, 0.0], dtype=np.float32))
    vel = raw(env, obs, "joint_vel")
    assert vel[0] == pytest.approx(0.5 * vmax, rel=0.05)
    assert abs(vel[1]) < 0.05
    # consistent with the angle change over the last cycle
    prev = raw(env, obs, "joint_pos")[0]
    obs, *_ = env.step(np.array([0.5, 0.0], dtype=np.float32))
    dq = math.radians(raw(env, obs, "joint_pos")[0] - prev) / 0.02
    assert raw(env, obs, "joint_vel")[0] == pytest.approx(dq, rel=1e-4)


def test_ball_rel_and_ball_vel_are_in_the_heading_frame(make_env):
    env = make_env(observations=("ball_rel", "ball_vel"), **raw_env_options())
    obs, _ = env.reset(seed=0)
    torso_z = env.torso_pos[2]
    # default: 0.2 m ahead, 0.055 m to the right, on the ground
    np.testing.assert_allclose(raw(env, obs, "ball_rel"), [0.2, -0.055, 0.041 - torso_z], atol=1e-6)
    # robot facing +y: a ball 0.3 m further along +y is straight ahead; a ball moving +x moves to
    # the robot's right (-y in the heading frame)
    obs, _ = env.reset(
        options={
            "robot_pos": (0.0, 0.0),
            "robot_heading_deg": 90.0,
            "ball_pos": (0.0, 0.3),
            "ball_vel": (1.5, 0.0, 0.0),
        }
    )
    np.testing.assert_allclose(raw(env, obs, "ball_rel")[:2], [0.3, 0.0], atol=1e-6)
    np.testing.assert_allclose(raw(env, obs, "ball_vel"), [0.0, -1.5, 0.0], atol=1e-6)


def test_ball_vision_is_polar_from_the_head(make_env):
    env = make_env(
        observations=("ball_vision",),
        backend_options={"vision_config": VisionConfig(noise=False)},
        **raw_env_options(),
    )
    # a ball 1 m straight ahead is in view (a ball at the feet is below the view cone)
    obs, _ = env.reset(seed=0, options={"ball_pos": (0.0, 0.0)})
    d, horizontal, vertical, visible = raw(env, obs, "ball_vision")
    head, _ = env.backend.world._head_pose(0)  # the engine's own head pose
    rel = env.ball_pos - head
    assert visible == 1.0
    assert d == pytest.approx(np.linalg.norm(rel), rel=1e-4)
    assert horizontal == pytest.approx(0.0, abs=0.1)
    elevation = math.degrees(math.atan2(rel[2], math.hypot(*rel[:2])))
    assert vertical == pytest.approx(elevation, abs=0.1)
    # values are held between See messages (every 3rd cycle)
    seen = [raw(env, env.step(ZERO20)[0], "ball_vision") for _ in range(3)]
    assert all(s[3] == 1.0 for s in seen)
    # out of view: not visible
    obs, _ = env.reset(options={"ball_pos": (-2.0, 0.0)})  # behind the robot
    assert raw(env, obs, "ball_vision")[3] == 0.0


def test_sensors_standing_still(make_env):
    env = make_env(
        observations=("foot_force", "accel", "gyro", "torso_height", "torso_orientation"),
        **raw_env_options(),
    )
    obs, _ = env.reset(seed=0)
    np.testing.assert_allclose(raw(env, obs, "accel"), [0.0, 0.0, 9.81], atol=1e-6)
    np.testing.assert_allclose(raw(env, obs, "gyro"), [0.0, 0.0, 0.0], atol=1e-6)
    assert raw(env, obs, "torso_height")[0] == pytest.approx(0.384, abs=0.01)
    np.testing.assert_allclose(raw(env, obs, "torso_orientation"), [1, 0, 0, 0, 0, 1], atol=1e-6)
    for _ in range(5):
        obs, *_ = env.step(ZERO20)
    ff = raw(env, obs, "foot_force")
    weight = env.robot_model.total_mass * 9.81
    # both feet carry the robot: vertical forces in N summing to its weight
    assert ff[5] > 5 and ff[11] > 5
    assert ff[5] + ff[11] == pytest.approx(weight, rel=0.25)
    assert np.all(np.abs(ff[[0, 1, 2, 6, 7, 8]]) < 0.1)  # centres of pressure in m, in the foot
    assert raw(env, obs, "accel")[2] == pytest.approx(9.81, abs=1.0)


def test_torso_orientation_follows_heading(make_env):
    env = make_env(observations=("torso_orientation",), **raw_env_options())
    obs, _ = env.reset(options={"robot_heading_deg": 90.0})
    np.testing.assert_allclose(raw(env, obs, "torso_orientation"), [0, 1, 0, 0, 0, 1], atol=1e-6)


def test_time_kick_target_and_last_action(make_env):
    env = make_env(
        observations=("time", "kick_target", "last_action"),
        controlled_joints=("lae1", "lae2"),
        **raw_env_options(),
    )
    obs, _ = env.reset(seed=0)
    assert raw(env, obs, "time")[0] == 0
    np.testing.assert_allclose(raw(env, obs, "kick_target"), [20.0, 0.0])
    np.testing.assert_allclose(raw(env, obs, "last_action"), [0.0, 0.0])
    for k in range(1, 4):
        obs, *_ = env.step(np.array([0.25, -2.0], dtype=np.float32))
        assert raw(env, obs, "time")[0] == k
    np.testing.assert_allclose(raw(env, obs, "last_action"), [0.25, -1.0])  # clipped

    env = make_env(observations=("kick_target",), randomise_kick_target=True, **raw_env_options())
    targets = np.array([raw(env, env.reset(seed=s)[0], "kick_target") for s in range(6)])
    assert np.all((targets[:, 0] >= 3) & (targets[:, 0] <= 10))
    assert np.all((targets[:, 1] >= -45) & (targets[:, 1] <= 45))
    assert len(np.unique(targets[:, 0])) == 6


def test_min_max_normalisation_maps_the_analytic_range(make_env):
    lo, hi = -120.0, 120.0  # range of lae1
    for norm, (a, b) in (("min_max", (-1.0, 1.0)), ("min_max_01", (0.0, 1.0))):
        env = make_env(
            observations=("joint_pos",),
            controlled_joints=("lae1",),
            normalise=norm,
            obs_clip=None,
        )
        for angle, expect in ((lo, a), (hi, b), (0.0, (a + b) / 2), (60.0, a + 0.75 * (b - a))):
            obs, _ = env.reset(options={"joint_angles_deg": {"lae1": angle}})
            assert obs[0] == pytest.approx(expect, abs=1e-6), (norm, angle)


def test_clipping_bounds_every_value(make_env):
    env = make_env(observations=("ball_rel",), obs_clip=1.0)  # ball_rel range is ±2 m
    assert np.all(env.observation_space.high == 1.0) and np.all(env.observation_space.low == -1.0)
    obs, _ = env.reset(options={"ball_pos": (4.0, -9.0)})  # 5 m ahead, 9 m right: beyond range
    np.testing.assert_allclose(obs[:2], [1.0, -1.0])
    env = make_env(observations=("ball_rel",), obs_clip=None)
    obs, _ = env.reset(options={"ball_pos": (4.0, -9.0)})
    assert obs[0] == pytest.approx(5.0 / 2.0, rel=1e-4)  # 5 m / (range half-width 2 m)
    assert np.isinf(env.observation_space.high).all()


def test_frame_stacking_shifts_frames(make_env):
    env = make_env(observations=("time", "joint_pos"), frame_stack=3, **raw_env_options())
    n = env.frame_size
    assert env.observation_space.shape == (3 * n,)
    assert len(env.observation_labels) == 3 * n and env.observation_labels[0].endswith("@t-2")
    obs0, _ = env.reset(seed=0)
    np.testing.assert_array_equal(obs0[:n], obs0[n : 2 * n])
    np.testing.assert_array_equal(obs0[:n], obs0[2 * n :])
    obs1, *_ = env.step(env.action_space.sample())
    obs2, *_ = env.step(env.action_space.sample())
    np.testing.assert_array_equal(obs2[: 2 * n], obs1[n:])
    assert [obs2[0], obs2[n], obs2[2 * n]] == [0, 1, 2]  # the time component, oldest first


def test_observation_noise_is_gaussian_in_normalised_units(make_env):
    std = 0.05
    env = make_env(observations=("time",), observation_noise_std=std, obs_clip=None)
    noiseless = -1.0  # time 0 maps to -1
    samples = np.array([env.reset(seed=s)[0][0] for s in range(200)]) - noiseless
    assert abs(samples.mean()) < 0.015
    assert samples.std() == pytest.approx(std, rel=0.2)


def test_velocity_kick_default_observation_layout(make_env):
    env = make_env(VelocityKick)
    sizes = {name: sl.stop - sl.start for name, sl in env.component_slices.items()}
    assert sizes == {
        "joint_pos": 20,
        "joint_vel": 20,
        "ball_rel": 3,
        "foot_force": 12,
        "accel": 3,
        "gyro": 3,
        "time": 1,
    }
    assert env.observation_space.shape == (62,)
    assert env.observation_space.dtype == np.float32


def test_vectors_and_turns_in_the_heading_frame():
    """A robot facing +y (heading 90°): the world's +y is ahead, +x to its right; to face +x it
    turns 90° clockwise, to face −y 180° (the short way's sign: [−180, 180))."""
    from robocup_gym.envs.observations import in_heading_frame, turn_to_deg

    facing_y = (math.cos(math.pi / 2), math.sin(math.pi / 2))
    forward, left = in_heading_frame(facing_y, 0.0, 2.0)
    assert forward == pytest.approx(2.0) and left == pytest.approx(0.0, abs=1e-12)
    forward, left = in_heading_frame(facing_y, 1.0, 0.0)
    assert forward == pytest.approx(0.0, abs=1e-12) and left == pytest.approx(-1.0)
    assert turn_to_deg(facing_y, 0.0) == pytest.approx(-90.0)
    assert turn_to_deg(facing_y, math.pi) == pytest.approx(90.0)
    assert turn_to_deg(facing_y, -math.pi / 2) == pytest.approx(-180.0)

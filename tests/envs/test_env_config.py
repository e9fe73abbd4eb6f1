"""The configuration: defaults, keyword overrides, and clear errors for bad values."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

from robocup_gym.envs import (
    PAPER_STANDING_POSE_DEG,
    ActionMode,
    BaseEnv,
    EnvConfig,
    EnvConfigError,
    Normalisation,
    SimpleKick,
    SimpleKickConfig,
    VelocityKick,
    VelocityKickConfig,
)


def test_defaults_need_no_arguments(make_env):
    cfg = EnvConfig()
    assert cfg.action_mode is ActionMode.VELOCITY
    assert cfg.normalise is Normalisation.MIN_MAX
    assert cfg.obs_clip == 1.0 and cfg.frame_stack == 1
    assert cfg.max_episode_steps == 40
    assert cfg.robot_start_pos == (-1.0, 0.0)
    assert cfg.ball_start_pos == pytest.approx((-0.8, -0.055, 0.041))
    assert isinstance(SimpleKick.default_config(), SimpleKickConfig)
    assert isinstance(VelocityKick.default_config(), VelocityKickConfig)
    env = make_env()
    obs, _ = env.reset()
    assert env.observation_space.contains(obs)
    json.dumps(VelocityKick.default_config().to_dict())  # JSON-able for logging


def test_keyword_overrides_reach_the_config(make_env):
    env = make_env(VelocityKick, wait_steps=7, speed_weight=0.5, action_mode="target_angle")
    assert env.config.wait_steps == 7 and env.config.speed_weight == 0.5
    assert env.action_mode is ActionMode.TARGET_ANGLE
    base = EnvConfig(max_episode_steps=9)
    env = make_env(VelocityKick, config=base)  # a plain config given to a task
    assert isinstance(env.config, VelocityKickConfig) and env.config.max_episode_steps == 9
    env = gym.make("RobocupGym/SimpleKick-v0", robot_type=3, frame_stack=2)
    assert env.unwrapped.config.robot_type == 3 and env.unwrapped.config.frame_stack == 2
    env.close()


def test_paper_names_are_accepted():
    assert EnvConfig(action_mode="VELOCITIES").action_mode is ActionMode.VELOCITY
    assert EnvConfig(action_mode="DESIRED_ANGLES").action_mode is ActionMode.TARGET_ANGLE
    assert EnvConfig(normalise="MIN_MAX_ANALYTIC").normalise is Normalisation.MIN_MAX_01


def test_joint_names_in_any_naming(make_env):
    env = make_env(controlled_joints=("rle3", "rlj4", "RAnklePitch"))
    assert env.controlled_joints == ("rle3", "rle4", "rle5")
    assert env.observed_joints == ("rlj3", "rlj4", "rlj5")
    env = make_env(joint_start_deg=PAPER_STANDING_POSE_DEG)
    env.reset(seed=0)
    names = env.robot_model.perceptor_names
    assert env.joint_angles_deg[names.index("rlj4")] == pytest.approx(-59.42)
    assert env.joint_angles_deg[names.index("hj2")] == pytest.approx(-45.0)


@pytest.mark.parametrize(
    "options, match",
    [
        (
            {"observations": ("joint_pos", "ball_position")},
            r"unknown observation.*'ball_position'.*"
            r"valid: joint_pos",
        ),
        (
            {"controlled_joints": ("rle3", "rknee")},
            r"unknown joint 'rknee' in controlled_joints.*"
            r"valid effector names: he1",
        ),
        ({"observed_joints": ("xx",)}, r"unknown joint 'xx' in observed_joints"),
        ({"controlled_joints": ("rle3", "rlj3")}, r"names a joint twice"),
        ({"controlled_joints": "rle3"}, r"sequence of joint names"),
        ({"controlled_joints": ()}, r"at least one joint"),
        ({"joint_start_deg": {"knee": 3.0}}, r"unknown joint 'knee' in joint_start_deg"),
        ({"action_mode": "jerk"}, r"unknown action mode 'jerk'.*'velocity'"),
        ({"normalise": "zscore"}, r"unknown normalisation 'zscore'"),
        ({"frame_stack": 0}, r"frame_stack must be an integer >= 1"),
        ({"max_episode_steps": 0}, r"max_episode_steps"),
        ({"wait_steps": -1}, r"wait_steps must be an integer >= 0"),
        ({"robot_type": 5}, r"robot_type must be one of the integers 0, 1, 2, 3, 4"),
        ({"robot_type": 2.0}, r"robot_type must be one of the integers.*got 2.0"),
        ({"robot_type": True}, r"robot_type must be one of the integers"),
        ({"kick_target": (float("nan"), 0.0)}, r"kick_target must be 2 finite numbers"),
        ({"kick_target_angle_range": (45.0, -45.0)}, r"low <= high"),
        ({"fall_height": float("nan")}, r"fall_height must be a torso height"),
        ({"fall_up_z": 5.0}, r"fall_up_z must be between -1 and 1"),
        ({"play_mode": "NoSuchMode"}, r"unknown play_mode 'NoSuchMode'; valid: BeforeKickOff"),
        ({"robot_start_pos": (100.0, 100.0)}, r"robot_start_pos \(100, 100\) is off the field"),
        ({"ball_start_pos": (0.0, 30.0)}, r"ball_start_pos \(0, 30\) is off the field"),
        ({"robot_start_heading_deg": float("inf")}, r"robot_start_heading_deg must be a finite"),
        (
            {"joint_start_deg": {"rlj3": 1000.0}},
            r"joint_start_deg: rle3 \(rlj3\) = 1000° is outside its range \[-25, 100\]°",
        ),
        ({"obs_clip": -1.0}, r"obs_clip"),
        ({"observation_noise_std": -0.1}, r"observation_noise_std"),
        ({"ball_start_pos": (1.0,)}, r"ball_start_pos"),
        ({"ball_start_pos": (1.0, float("nan"))}, r"ball_start_pos"),
        ({"target_gain": 0.0}, r"target_gain"),
        ({"observations": ("time", "time")}, r"twice"),
        ({"observations": ("toe_force",)}, r"type 4"),
        ({"render_mode": "human"}, r"render_mode"),
        ({"wait_step": 3}, r"unknown option\(s\) 'wait_step'.*valid options:.*wait_steps"),
        # a value of the wrong kind (from --env KEY=VALUE or a config file) is named, never read
        # as something else: the text "false" is not a true flag
        ({"observation_noise_std": "high"}, r"observation_noise_std must be a number, got 'high'"),
        ({"obs_clip": "none"}, r"obs_clip must be a number or None, got 'none'"),
        ({"randomise_kick_target": "false"}, r"randomise_kick_target must be true or false"),
        ({"kick_target_distance_range": "3-10"}, r"kick_target_distance_range must be 2 numbers"),
        ({"kick_target_angle_range": (-45.0, "45")}, r"kick_target_angle_range must be 2 numbers"),
        ({"observations": "joint_pos"}, r"observations must be a list of component names"),
        ({"observations": None}, r"observations must be a list of component names, got None"),
        ({"observed_joints": ("rle3", 4)}, r"observed_joints must be a list of names or None"),
        ({"joint_start_noise_deg": "big"}, r"joint_start_noise_deg must be a number or a mapping"),
        ({"joint_start_noise_deg": {"rle3": "1"}}, r"joint_start_noise_deg must be a number or"),
        ({"backend_options": "fast"}, r"backend_options must be a mapping of names to values"),
    ],
)
def test_bad_config_is_a_clear_error(options, match):
    with pytest.raises(EnvConfigError, match=match):
        BaseEnv(**options)


@pytest.mark.parametrize(
    "options, match",
    [
        ({"robot_pos": (100.0, 0.0)}, r"robot_pos \(100, 0\) is off the field"),
        ({"ball_pos": (0.0, float("nan"))}, r"ball_pos must be finite"),
        ({"joint_angles_deg": {"lae1": 500.0}}, r"lae1 .* = 500° is outside its range"),
        ({"kick_target": (float("inf"), 0.0)}, r"kick_target must be finite"),
        ({"robot_heading_deg": float("nan")}, r"robot_heading_deg must be finite"),
        # values of the wrong kind name the option (text is never read as numbers)
        ({"robot_pos": "centre"}, r"robot_pos must be \(x, y\) in m, got 'centre'"),
        ({"robot_pos": (1.0, 2.0, 3.0)}, r"robot_pos must be \(x, y\) in m, got \(1.0, 2.0, 3.0\)"),
        ({"robot_heading_deg": "90"}, r"robot_heading_deg must be a number of degrees, got '90'"),
        ({"ball_pos": "spot"}, r"ball_pos must be \(x, y\) or \(x, y, z\) in m, got 'spot'"),
        ({"ball_vel": (1.0, 0.0)}, r"ball_vel must be \(x, y, z\) in m/s"),
        ({"kick_target": "far"}, r"kick_target must be \(distance m, direction deg\)"),
        ({"joint_angles_deg": "bent"}, r"joint_angles_deg must have shape \(22,\), got 'bent'"),
        ({"joint_angles_deg": {"lae1": "x"}}, r"joint_angles_deg\['lae1'\] must be a number"),
    ],
)
def test_bad_reset_options_are_clear_errors_and_the_env_goes_on(options, match):
    env = BaseEnv()
    try:
        env.reset(seed=0)
        with pytest.raises(ValueError, match=match):
            env.reset(options=options)
        env.reset(seed=1)  # nothing broke: the next episode starts normally
        env.step(np.zeros(env.action_space.shape))
    finally:
        env.close()


def test_reset_options_that_are_not_a_mapping_are_a_clear_error():
    env = BaseEnv()
    try:
        with pytest.raises(ValueError, match="reset options must map option names to values"):
            env.reset(options=["robot_pos", (0.0, 0.0)])
        env.reset(seed=1)
        env.step(np.zeros(env.action_space.shape))
    finally:
        env.close()


def test_a_closed_environment_refuses_to_step_or_reset():
    env = BaseEnv()
    env.reset(seed=0)
    env.close()
    with pytest.raises(RuntimeError, match=r"step\(\) on a closed environment"):
        env.step(np.zeros(env.action_space.shape))
    with pytest.raises(RuntimeError, match=r"reset\(\) on a closed environment"):
        env.reset()
    env.close()  # closing twice is harmless


def test_the_paper_pose_is_within_every_types_joint_ranges():
    from robocup_gym.envs.config import PAPER_STANDING_POSE_DEG

    for robot_type in range(5):
        EnvConfig(joint_start_deg=PAPER_STANDING_POSE_DEG, robot_type=robot_type)


def test_task_options_are_validated():
    with pytest.raises(EnvConfigError, match="lateral_reference"):
        VelocityKick(lateral_reference="world")
    with pytest.raises(EnvConfigError, match="unknown option"):
        BaseEnv(speed_weight=1.0)  # a VelocityKick option on the base environment
    with pytest.raises(EnvConfigError, match="must be an EnvConfig"):
        BaseEnv(config={"wait_steps": 3})


def test_normalise_none_with_clip_warns():
    with pytest.warns(UserWarning, match="obs_clip=None"):
        EnvConfig(normalise="none")


def test_every_tasks_policy_options_are_options_of_it():
    """The options a policy takes along to another task (``policy_options``) are options of
    every registered task's config, and none of them a reward's, an observation list, a start
    or an episode end."""
    import dataclasses

    from robocup_gym.train.tasks import _class_defaults, is_robocup_task

    seen = set()
    for env_id in gym.registry:
        if not is_robocup_task(env_id):
            continue
        base = _class_defaults(env_id)
        if base is None:
            continue
        cls = type(base)
        seen.add(cls.__name__)
        names = {f.name for f in dataclasses.fields(cls)}
        assert cls.policy_options <= names, (cls.__name__, cls.policy_options - names)
        for option in cls.policy_options:
            assert not option.startswith(("w_", "ball_", "robot_start", "max_episode"))
            assert option not in ("observations", "fall_penalty", "terminate_on_fall")
    assert {"WalkConfig", "RunConfig", "DribbleConfig", "GetUpConfig"} <= seen

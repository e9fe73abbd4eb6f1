"""The reference kick the kicking tasks' actions correct: it kicks and stays up on every Nao
type, and only plays where it can."""

import gymnasium
import numpy as np
import pytest

from robocup_gym.envs import EnvConfigError, LongKick, TargetKick
from robocup_gym.envs.actions import ActionMapper
from robocup_gym.envs.config import ActionMode
from robocup_gym.envs.tasks.long_kick import (
    LONG_KICK_BALL_START_POS,
    LONG_KICK_KEYFRAMES,
    LONG_KICK_KEYFRAMES_TYPE_4,
)
from robocup_gym.envs.tasks.reference_kick import (
    REFERENCE_KICK_KEYFRAMES,
    reference_kick_deg,
)
from robocup_gym.envs.tasks.target_kick import TargetKickConfig, kick_outcome
from robocup_gym.robot.nao import nao_model


def test_the_reference_kick_interpolates_its_keyframes():
    assert all(v == 0.0 for v in reference_kick_deg(0.0).values())
    last = REFERENCE_KICK_KEYFRAMES[-1][0]
    assert all(v == 0.0 for v in reference_kick_deg(last + 1.0).values())
    swing = reference_kick_deg(0.56)
    assert swing["rle3"] == pytest.approx(50.0) and swing["rle4"] == pytest.approx(20.0)
    halfway = reference_kick_deg(0.53)  # halfway between the draw-back and the swing
    assert halfway["rle3"] == pytest.approx(30.0) and halfway["rle4"] == pytest.approx(-10.0)
    # the left leg only leans: it carries the robot
    assert swing["lle2"] == pytest.approx(-8.0) and "lle3" not in swing


def test_offsets_by_name_reach_their_action_slots():
    model = nao_model(0)
    legs = [model.effector_names.index(n) for n in ("lle3", "rle3", "rle4")]
    mapper = ActionMapper(model, np.array(legs), ActionMode.TARGET_ANGLE, 1.0)
    mapper.target_offset_deg[:] = 7.0
    mapper.set_offsets({"rle4": -40.0, "rle3": 10.0, "he1": 5.0})  # he1: not controlled
    assert mapper.target_offset_deg.tolist() == [0.0, 10.0, -40.0]


MIN_LONG_KICK_M = 8.5
"""Measured (no start noise): 9.69, 9.64, 9.71, 9.36 and 9.96 m for Nao types 0-4."""


def _play(env, seed):
    env.reset(seed=seed)
    zero = np.zeros(env.action_space.shape)
    while True:
        _, reward, terminated, truncated, info = env.step(zero)
        if terminated or truncated:
            return reward, info


@pytest.mark.parametrize("robot_type", [0, 1, 2, 3, 4])
def test_zero_actions_kick_and_stay_up_on_every_nao_type(robot_type):
    """Zero actions play the reference kick alone: the ball goes 1.5 m or more, about straight
    ahead, and the robot still stands after the 1 s wait."""
    env = TargetKick(robot_type=robot_type, randomise_kick_target=False, kick_target=(3.0, 0.0))
    try:
        reward, info = _play(env, seed=robot_type)
        assert not info["fallen"] and "fall" not in info["reward_terms"]
        assert info["kick_distance_m"] > 1.5 and info["direction_error_deg"] < 25.0
        assert 20 <= info["contact_step"] <= 40  # the swing through the ball at 0.5-0.56 s
        assert reward > 0.3
    finally:
        env.close()


@pytest.mark.parametrize("robot_type", [0, 1, 2, 3, 4])
def test_long_kick_v1_kicks_far_and_stays_up_on_every_nao_type(robot_type):
    """``LongKick-v1`` plays the long kick: zero actions move the ball several times as far as
    the reference kick, about straight ahead, and the robot stands after the 1 s wait."""
    env = gymnasium.make("RobocupGym/LongKick-v1", robot_type=robot_type)
    try:
        assert env.unwrapped.config.kick_keyframes == LONG_KICK_KEYFRAMES
        assert env.unwrapped.config.ball_start_pos[:2] == LONG_KICK_BALL_START_POS
        own = LONG_KICK_KEYFRAMES_TYPE_4 if robot_type == 4 else LONG_KICK_KEYFRAMES
        assert env.unwrapped.kick_keyframes() == own
        _, info = _play(env, seed=robot_type)
        u = env.unwrapped
        kick = kick_outcome(u.ball_spawn_pos, u.ball_pos, u.ball_vel, 0.0, np.array([1.0, 0.0]))
        assert not info["fallen"] and "fall" not in info["reward_terms"]
        assert kick["kick_distance_m"] > MIN_LONG_KICK_M
        assert kick["direction_error_deg"] < 5.0
    finally:
        env.close()


def test_without_the_reference_zero_actions_hold_the_stance():
    env = LongKick(reference_kick=False)
    try:
        reward, info = _play(env, seed=0)
        assert not info["fallen"]
        assert np.linalg.norm(env.ball_pos[:2] - env.ball_spawn_pos[:2]) < 1e-3
        assert abs(reward) < 1e-3  # the ball never moved
    finally:
        env.close()


def test_the_reference_kick_refuses_what_it_cannot_play():
    with pytest.raises(EnvConfigError, match="reference_kick adds to target angles"):
        TargetKickConfig(action_mode="velocity")
    with pytest.raises(EnvConfigError, match="reference_kick is a motion of the Nao"):
        TargetKickConfig(robot="T1", joint_start_deg=None)
    # the league's robots take their own defaults: no reference kick
    assert TargetKick.league_defaults("T1")["reference_kick"] is False
    TargetKickConfig(action_mode="velocity", reference_kick=False)  # the paper's way: allowed


def test_kick_keyframes_are_checked():
    """Malformed kicks are refused, naming what is wrong."""
    with pytest.raises(EnvConfigError, match=r"must be \(time s, \{effector"):
        TargetKickConfig(kick_keyframes=((0.0,), (0.5, {"rle3": 10.0})))
    with pytest.raises(EnvConfigError, match="increasing finite times"):
        TargetKickConfig(kick_keyframes=((0.0, {}), (0.0, {"rle3": 10.0})))
    with pytest.raises(EnvConfigError, match="increasing finite times"):
        TargetKickConfig(kick_keyframes=((0.0, {}), (float("nan"), {"rle3": 10.0})))
    with pytest.raises(EnvConfigError, match=r"unknown Nao effectors \['rle9'\]"):
        TargetKickConfig(kick_keyframes=((0.0, {}), (0.5, {"rle9": 10.0})))
    with pytest.raises(EnvConfigError, match="offsets must be finite"):
        TargetKickConfig(kick_keyframes=((0.0, {}), (0.5, {"rle3": float("nan")})))
    with pytest.raises(EnvConfigError, match="must map Nao types 0-4"):
        TargetKickConfig(kick_keyframes_by_type={7: REFERENCE_KICK_KEYFRAMES})
    with pytest.raises(EnvConfigError, match="unknown Nao effectors"):
        TargetKickConfig(kick_keyframes_by_type={1: ((0.0, {"xx": 1.0}),)})


def test_a_task_plays_the_keyframes_it_is_given_and_a_type_its_own():
    """``kick_keyframes`` replaces the reference kick: a kick that only lifts the right knee
    never reaches the ball. A type listed in ``kick_keyframes_by_type`` (keyed as JSON writes
    it, too) plays its own; the others play ``kick_keyframes``."""
    lift = ((0.0, {}), (0.3, {"rle4": -30.0}), (0.6, {}))
    assert reference_kick_deg(0.3, lift) == {"rle4": -30.0}
    env = LongKick(kick_keyframes=lift)
    try:
        _, info = _play(env, seed=0)
        assert not info["fallen"]
        assert np.linalg.norm(env.ball_pos[:2] - env.ball_spawn_pos[:2]) < 0.01
    finally:
        env.close()
    by_type = {"1": lift, 3: LONG_KICK_KEYFRAMES}
    own = LongKick(robot_type=1, kick_keyframes_by_type=by_type)
    other = LongKick(robot_type=2, kick_keyframes_by_type=by_type)
    try:
        assert own.kick_keyframes() is lift
        assert other.kick_keyframes() is REFERENCE_KICK_KEYFRAMES
        _, info = _play(own, seed=0)
        assert np.linalg.norm(own.ball_pos[:2] - own.ball_spawn_pos[:2]) < 0.01
    finally:
        own.close()
        other.close()


def test_long_kick_v1_options_survive_json():
    """An exported policy's description records the options as JSON (``EnvConfig.to_dict``):
    the kicks come back as numbers, and a robot built from them plays its type's kick."""
    import json

    env = gymnasium.make("RobocupGym/LongKick-v1", robot_type=4)
    try:
        recorded = json.loads(json.dumps(env.unwrapped.config.to_dict()))
    finally:
        env.close()
    options = {k: recorded[k] for k in ("kick_keyframes", "kick_keyframes_by_type", "robot_type")}
    again = LongKick(**options)
    try:
        as_lists = [[t, k] for t, k in LONG_KICK_KEYFRAMES_TYPE_4]
        assert again.kick_keyframes() == as_lists
        assert recorded["kick_keyframes"] == [[t, k] for t, k in LONG_KICK_KEYFRAMES]
    finally:
        again.close()

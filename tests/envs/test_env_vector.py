"""The environments run in Stable-Baselines3's and Gymnasium's vectorised wrappers."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from robocup_gym.envs import VelocityKick

sb3_vec = pytest.importorskip("stable_baselines3.common.vec_env")

SHORT = {"max_episode_steps": 3, "wait_steps": 2}


def _make():
    return VelocityKick(**SHORT)


def _drive_sb3(vec, n_envs):
    obs = vec.reset()
    assert obs.shape == (n_envs, 62)
    dones_seen = 0
    for _ in range(7):  # crosses two episode ends (auto-reset)
        actions = np.stack([vec.action_space.sample() for _ in range(n_envs)])
        obs, rewards, dones, infos = vec.step(actions)
        assert obs.shape == (n_envs, 62) and np.isfinite(obs).all()
        assert rewards.shape == (n_envs,) and np.isfinite(rewards).all()
        for done, info in zip(dones, infos, strict=True):
            if done:
                dones_seen += 1
                assert "terminal_observation" in info and "ball_distance" in info
    assert dones_seen >= n_envs


def test_sb3_dummy_vec_env():
    vec = sb3_vec.DummyVecEnv([_make, _make])
    try:
        _drive_sb3(vec, 2)
    finally:
        vec.close()


def test_sb3_subproc_vec_env():
    vec = sb3_vec.SubprocVecEnv([_make, _make], start_method="fork")
    try:
        _drive_sb3(vec, 2)
        assert vec.get_attr("config")[0].max_episode_steps == 3
    finally:
        vec.close()


def test_gymnasium_async_vector_env():
    vec = gym.vector.AsyncVectorEnv(
        [lambda: gym.make("RobocupGym/VelocityKick-v0", **SHORT)] * 2, context="fork"
    )
    try:
        obs, _ = vec.reset(seed=3)
        assert obs.shape == (2, 62) and obs.dtype == np.float32
        ends = 0
        for _ in range(8):
            obs, rewards, terminated, truncated, _infos = vec.step(vec.action_space.sample())
            assert np.isfinite(obs).all() and np.isfinite(rewards).all()
            ends += int(np.count_nonzero(terminated | truncated))
        assert ends >= 2
    finally:
        vec.close()

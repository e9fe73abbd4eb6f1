"""Every registered id passes Gymnasium's and Stable-Baselines3's environment checkers, and the
backend seam resolves names (with a clear error for the rcssserver3d backend until it exists)."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import robocup_gym.envs as rg_envs
from robocup_gym.backends import BackendNotAvailableError

sb3_env_checker = pytest.importorskip("stable_baselines3.common.env_checker")


def test_registry_lists_the_tasks():
    assert set(rg_envs.REGISTERED_IDS) == {
        "RobocupGym/SimpleKick-v0",
        "RobocupGym/VelocityKick-v0",
        "RobocupGym/Walk-v0",
        "RobocupGym/Run-v0",
        "RobocupGym/Run-v1",
        "RobocupGym/GetUp-v0",
        "RobocupGym/GetUp-v1",
        "RobocupGym/TargetKick-v0",
        "RobocupGym/TargetKick-v1",
        "RobocupGym/LongKick-v0",
        "RobocupGym/LongKick-v1",
        "RobocupGym/Dribble-v0",
        "RobocupGym/Dribble-v1",
    }
    for env_id in rg_envs.REGISTERED_IDS:
        assert env_id in gym.registry
        # no TimeLimit: the environments truncate themselves and then run their wait steps
        assert gym.registry[env_id].max_episode_steps is None


@pytest.mark.parametrize("env_id", rg_envs.REGISTERED_IDS)
def test_registered_env_passes_checkers(env_id):
    env = gym.make(env_id, max_episode_steps=5, wait_steps=2)
    try:
        assert isinstance(env.unwrapped, rg_envs.BaseEnv)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            check_env(env.unwrapped, skip_render_check=True)
            sb3_env_checker.check_env(env.unwrapped, warn=True)
        relevant = [w for w in caught if "diverged" not in str(w.message)]
        assert not relevant, [str(w.message) for w in relevant]
        # a whole episode through the gymnasium wrappers, observations inside the space
        obs, _ = env.reset(seed=1)
        assert env.observation_space.contains(obs)
        for _ in range(5):
            obs, reward, terminated, truncated, _info = env.step(env.action_space.sample())
            assert env.observation_space.contains(obs)
            assert np.isfinite(reward)
            if terminated or truncated:
                break
        assert terminated or truncated
    finally:
        env.close()


def test_missing_backend_is_a_clear_error(monkeypatch, tmp_path):
    monkeypatch.delenv("RCSSSERVER3D", raising=False)  # (a machine with a real server)
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(BackendNotAvailableError, match=r"rcssserver3d.*not available.*'mujoco'"):
        gym.make("RobocupGym/SimpleKick-v0", backend="rcssserver3d")
    with pytest.raises(BackendNotAvailableError, match=r"unknown backend 'bullet'"):
        gym.make("RobocupGym/VelocityKick-v0", backend="bullet")


def test_every_registered_id_has_its_version_in_the_class_history():
    """Each id's class documents its version (an id whose behaviour changes gets a new one)."""
    import gymnasium as gym

    from robocup_gym.envs import REGISTERED_IDS

    for env_id in REGISTERED_IDS:
        version = env_id.rsplit("-", 1)[1]
        spec = gym.spec(env_id)
        module, name = spec.entry_point.split(":")
        cls = getattr(__import__(module, fromlist=[name]), name)
        history = cls.__doc__.split("Version history:", 1)
        assert len(history) == 2, f"{name} has no version history"
        assert f"* {version}:" in history[1], f"{name}'s history lacks {version}"

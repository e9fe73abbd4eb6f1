"""Shared helpers of the environment tests."""

from __future__ import annotations

import warnings

import pytest

import robocup_gym.envs  # noqa: F401  (registers the Gymnasium ids)
from robocup_gym.envs import BaseEnv


@pytest.fixture
def make_env():
    """``make_env(cls=BaseEnv, **options)`` → a reset-able environment, closed after the test."""
    envs: list[BaseEnv] = []

    def factory(cls=BaseEnv, **options) -> BaseEnv:
        env = cls(**options)
        envs.append(env)
        return env

    yield factory
    for env in envs:
        env.close()


@pytest.fixture(autouse=True)
def _quiet_divergence_warnings():
    # the embedded world may still diverge now and then (physics work in progress); the
    # environments report it in info["diverged"] and warn once, which is not under test here
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="simulation diverged", category=RuntimeWarning)
        yield

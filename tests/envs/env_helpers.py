"""Helpers of the environment tests (imported by the test modules)."""

from __future__ import annotations

import numpy as np

from robocup_gym.envs import BaseEnv


def raw(env: BaseEnv, obs: np.ndarray, name: str) -> np.ndarray:
    """The slice of the last frame of ``obs`` that belongs to component ``name``."""
    n = env.frame_size
    return np.asarray(obs[-n:][env.component_slices[name]], dtype=float)


def raw_env_options(**options):
    """Options for an environment with raw (unnormalised, unclipped) observations."""
    return {"normalise": "none", "obs_clip": None, **options}

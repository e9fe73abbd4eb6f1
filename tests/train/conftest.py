"""Shared fixtures of the training tests: one tiny trained run reused by the smoke tests."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from .train_helpers import TINY_PPO, invoke


@pytest.fixture(autouse=True)
def _quiet_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        warnings.simplefilter("ignore", UserWarning)
        warnings.simplefilter("ignore", DeprecationWarning)
        yield


@pytest.fixture(scope="session")
def ppo_run(tmp_path_factory) -> Path:
    """A 1,024-step PPO run on VelocityKick with 2 subprocess environments."""
    pytest.importorskip("stable_baselines3")
    out = tmp_path_factory.mktemp("runs")
    args = "train velocity-kick --n-envs 2 --timesteps 1024 --seed 3 --checkpoint-freq 512"
    args += " --eval-freq 512"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        invoke([*args.split(), "--out", out, *TINY_PPO])
    (run,) = list(out.iterdir())
    return run

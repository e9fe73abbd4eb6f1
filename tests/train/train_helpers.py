"""Helpers of the training tests (the CLI in-process, the tiny PPO settings)."""

from __future__ import annotations

import json

TINY_PPO = [
    "--hp",
    "n_steps=16",
    "--hp",
    "batch_size=32",
    "--hp",
    "n_epochs=2",
    "--hp",
    "policy_kwargs={net_arch: [32, 32]}",
]
"""Hyperparameters that make a PPO smoke run take seconds (tests only)."""


def invoke(args: list[str]):
    """Run the CLI in-process; returns the click Result (asserting success)."""
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    result = CliRunner().invoke(app, [str(a) for a in args])
    if result.exit_code != 0:
        raise AssertionError(
            f"robocup-gym {' '.join(map(str, args))} exited {result.exit_code}:\n{result.output}"
            + (f"\n{result.exception!r}" if result.exception else "")
        )
    return result


def last_json(output: str) -> dict:
    return json.loads(output.strip().splitlines()[-1])


SHORT_EPISODES = {"max_episode_steps": 6, "wait_steps": 2}
"""VelocityKick options that make a short rollout cross falls, time limits and auto-resets."""


def small_vec_env():
    """4 short-episode VelocityKick environments in 2 worker processes (close it after use)."""
    from robocup_gym.train.vecenv import make_vec_env

    return make_vec_env(
        "RobocupGym/VelocityKick-v0", 4, n_workers=2, env_kwargs=SHORT_EPISODES, seed=5
    )


def small_pipelined_ppo(venv, **kwargs):
    """A :class:`PipelinedPPO` with 16-step rollouts and a 2×32 network; ``kwargs`` override."""
    from robocup_gym.train.pipelined import PipelinedPPO

    settings = {
        "n_steps": 16,
        "batch_size": 32,
        "seed": 1,
        "device": "cpu",
        "policy_kwargs": {"net_arch": [32, 32]},
        **kwargs,
    }
    return PipelinedPPO("MlpPolicy", venv, **settings)

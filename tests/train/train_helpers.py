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

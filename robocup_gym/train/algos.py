"""The learning algorithms a run can use: Stable-Baselines3's SAC, and PPO with pipelined
rollouts (:class:`robocup_gym.train.pipelined.PipelinedPPO`), and the check of their
hyperparameters."""

from __future__ import annotations

import inspect
from typing import Any

__all__ = ["ALGOS", "algo_class", "validate_algo_kwargs"]

ALGOS = ("ppo", "sac")
"""The algorithms ``robocup-gym train --algo`` takes."""


def algo_class(algo: str):
    """The Stable-Baselines3 class that trains ``algo``: SAC, or PPO with pipelined rollouts
    (:class:`robocup_gym.train.pipelined.PipelinedPPO`, the same algorithm, less waiting)."""
    from stable_baselines3 import SAC  # (torch: imported when an algorithm is asked for)

    from robocup_gym.train.pipelined import PipelinedPPO

    return {"ppo": PipelinedPPO, "sac": SAC}[algo.lower()]


def validate_algo_kwargs(algo: str, algo_kwargs: dict[str, Any]) -> None:
    """Check that every hyperparameter is a keyword of the algorithm's class.

    Raises:
        ValueError: naming the unknown keys and listing the valid ones.
    """
    valid: set[str] = set()
    for klass in algo_class(algo).__mro__:
        init = klass.__dict__.get("__init__")
        if init is None:
            continue
        for p in inspect.signature(init).parameters.values():
            if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD) and p.name != "self":
                valid.add(p.name)
    valid = {n for n in valid if not n.startswith("_")} - {
        "policy",
        "env",
        "support_multi_env",
        "supported_action_spaces",
        "monitor_wrapper",
    }
    unknown = sorted(set(algo_kwargs) - valid)
    if unknown:
        raise ValueError(
            f"unknown {algo.upper()} hyperparameter(s) {', '.join(map(repr, unknown))}; "
            f"valid: {', '.join(sorted(valid))}"
        )

"""The learning algorithms a run can use: Stable-Baselines3's SAC, and PPO with pipelined
rollouts (:class:`robocup_gym.train.pipelined.PipelinedPPO`), and the check of their
hyperparameters."""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Mapping
from typing import Any

from robocup_gym.types import is_integer, is_number

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
    for name, value in algo_kwargs.items():
        check = _VALUES.get(name)
        if check is not None and not (callable(value) and name in _SCHEDULED):
            what, ok = check
            if not ok(value):
                raise ValueError(
                    f"{algo.upper()} hyperparameter {name} must be {what}, got {value!r}"
                )


def _number(v: Any) -> bool:
    return is_number(v) and math.isfinite(v)


def _whole(low: int) -> Callable[[Any], bool]:
    return lambda v: is_integer(v) and v >= low


_SCHEDULED = frozenset({"learning_rate", "clip_range", "clip_range_vf"})
"""Hyperparameters that Stable-Baselines3 also takes as a schedule (a function of progress)."""
_VALUES: dict[str, tuple[str, Callable[[Any], bool]]] = {
    "learning_rate": ("a number >= 0", lambda v: _number(v) and v >= 0),
    "n_steps": ("an integer >= 1", _whole(1)),
    "batch_size": ("an integer >= 1", _whole(1)),
    "n_epochs": ("an integer >= 1", _whole(1)),
    "buffer_size": ("an integer >= 1", _whole(1)),
    "learning_starts": ("an integer >= 0", _whole(0)),
    "gradient_steps": ("an integer >= -1 (-1: as many as the rollout's steps)", _whole(-1)),
    "gamma": ("a number in [0, 1]", lambda v: _number(v) and 0 <= v <= 1),
    "gae_lambda": ("a number in [0, 1]", lambda v: _number(v) and 0 <= v <= 1),
    "tau": ("a number in [0, 1]", lambda v: _number(v) and 0 <= v <= 1),
    "clip_range": ("a number > 0", lambda v: _number(v) and v > 0),
    "clip_range_vf": ("a number > 0 or None", lambda v: v is None or (_number(v) and v > 0)),
    "vf_coef": ("a number >= 0", lambda v: _number(v) and v >= 0),
    "max_grad_norm": ("a number > 0", lambda v: _number(v) and v > 0),
    "target_kl": ("a number > 0 or None", lambda v: v is None or (_number(v) and v > 0)),
    "use_sde": ("true or false", lambda v: isinstance(v, bool)),
    "normalize_advantage": ("true or false", lambda v: isinstance(v, bool)),
    "sde_sample_freq": ("an integer (-1: only at a rollout's start)", _whole(-1)),
    "policy_kwargs": ("a mapping of options", lambda v: v is None or isinstance(v, Mapping)),
}
"""What the common hyperparameters must be (the algorithms' own checks come later, some as
an assertion deep in a run's start, some not at all: a discount above 1 trains)."""

"""Simulators behind the environments, resolved by name.

>>> from robocup_gym.backends import make_backend
>>> backend = make_backend("mujoco", robot_type=0)   # the embedded SimSpark world (default)

``"rcssserver3d"`` drives the real server; ``"ode"`` steps SimSpark's physics on ODE itself
(needs ``libode``), to check closed-loop that a policy learnt on the embedded world works there.

Backends are looked up in a small registry of ``name -> "module:Class"`` entries and imported
only when asked for. Adding a backend is one line here (or one call to :func:`register_backend`).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

from robocup_gym.backends.base import (
    Backend,
    BackendDivergedError,
    BackendError,
    BackendNotAvailableError,
    RobotPose,
)

__all__ = [
    "Backend",
    "BackendDivergedError",
    "BackendError",
    "BackendNotAvailableError",
    "RobotPose",
    "available_backends",
    "make_backend",
    "register_backend",
]

_REGISTRY: dict[str, str | Callable[..., Backend]] = {
    "mujoco": "robocup_gym.backends.mujoco_backend:MujocoBackend",
    "rcssserver3d": "robocup_gym.backends.rcssserver3d_backend:Rcssserver3dBackend",
    "ode": "robocup_gym.backends.ode_backend:OdeBackend",
}
"""Implemented backends: name -> ``"module:Class"`` (imported lazily) or a factory."""

_PLANNED: dict[str, str] = {}
"""Backends that are designed but not implemented yet: name -> what it will be."""


def register_backend(name: str, entry_point: str | Callable[..., Backend]) -> None:
    """Make ``make_backend(name, ...)`` build ``entry_point`` (``"module:Class"`` or a factory)."""
    _REGISTRY[name] = entry_point
    _PLANNED.pop(name, None)


def available_backends() -> tuple[str, ...]:
    """Names that :func:`make_backend` can build now."""
    return tuple(_REGISTRY)


def make_backend(name: str, **kwargs: Any) -> Backend:
    """Build the backend registered as ``name`` with keyword options ``kwargs``.

    Raises:
        BackendNotAvailableError: unknown name, or a backend that is planned but not implemented;
            the message names it and lists the available ones.
    """
    entry = _REGISTRY.get(name)
    if entry is None:
        available = ", ".join(repr(n) for n in _REGISTRY)
        if name in _PLANNED:
            raise BackendNotAvailableError(
                f"backend {name!r} is not available yet: it {_PLANNED[name]}. "
                f"Available backends: {available}."
            )
        raise BackendNotAvailableError(
            f"unknown backend {name!r}; available backends: {available}"
            + (f" (planned: {', '.join(repr(n) for n in _PLANNED)})" if _PLANNED else "")
        )
    if isinstance(entry, str):
        module_name, _, attr = entry.partition(":")
        entry = getattr(importlib.import_module(module_name), attr)
    return entry(**kwargs)

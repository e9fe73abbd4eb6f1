"""Simulators behind the environments, resolved by name.

>>> from robocup_gym.backends import make_backend
>>> backend = make_backend("ode", robot_type=0)   # SimSpark's physics on ODE (the default)

Two of them are the in-process world on its two physics engines (:data:`ENGINES`): ``"ode"``,
SimSpark's own step on the Open Dynamics Engine, exact and the default (needs the system library
``libode``), and ``"mujoco"``, the fast approximation (matches slow motions and walking, not
impacts: a kick learnt there does not kick on rcssserver3d). ``"rcssserver3d"`` drives a real
server. ``"rcsssmj"`` is the league's current simulator (RCSSServerMJ) in-process, for its
robots (``robot="T1"``, ``"K1"``; needs ``pip install robocup-gym[mj]``), and
``"rcssservermj"`` drives a real one.

Backends are looked up in a small registry of ``name -> "module:Class"`` entries and imported
only when asked for. Adding a backend is one line here (or one call to :func:`register_backend`).
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable
from typing import Any

from robocup_gym.backends.base import (
    Backend,
    BackendDivergedError,
    BackendError,
    BackendNotAvailableError,
    RobotPose,
)
from robocup_gym.sim import ENGINES

__all__ = [
    "DEFAULT_ENGINE",
    "ENGINES",
    "IN_PROCESS_BACKENDS",
    "LEAGUE_BACKENDS",
    "Backend",
    "BackendDivergedError",
    "BackendError",
    "BackendNotAvailableError",
    "RobotPose",
    "available_backends",
    "make_backend",
    "register_backend",
    "resolve_backend",
]

_REGISTRY: dict[str, str | Callable[..., Backend]] = {
    "mujoco": "robocup_gym.backends.in_process:MujocoBackend",
    "rcssserver3d": "robocup_gym.backends.rcssserver3d_backend:Rcssserver3dBackend",
    "ode": "robocup_gym.backends.in_process:OdeBackend",
    "rcsssmj": "robocup_gym.backends.league_backend:LeagueBackend",
    "rcssservermj": "robocup_gym.backends.rcssservermj_backend:RcssServerMJBackend",
}
"""Implemented backends: name -> ``"module:Class"`` (imported lazily) or a factory."""

DEFAULT_ENGINE = ENGINES[0]
"""SimSpark's own step on ODE: what is learnt on it works on rcssserver3d."""


IN_PROCESS_BACKENDS = ("ode", "mujoco", "rcsssmj")
"""Backends that run the simulation in this process (and can, e.g., push the robot)."""
LEAGUE_BACKENDS = ("rcsssmj", "rcssservermj")
"""The backends of the league's robots (T1, K1): their simulator in-process, or a real one."""


def resolve_backend(
    backend: str | None = None, engine: str | None = None, robot: str = "nao"
) -> str:
    """The backend name for the ``backend=`` and ``engine=`` arguments (one of them, or none
    for :data:`DEFAULT_ENGINE`) and ``robot``: a league robot (``"T1"``, ``"K1"``) runs on its
    own simulator (:data:`LEAGUE_BACKENDS`, in-process by default), never on a Nao engine.

    Raises:
        BackendNotAvailableError: an unknown engine, both given and disagreeing, or a backend
            that cannot run ``robot``.
    """
    if robot != "nao":
        if engine is not None or backend not in (None, *LEAGUE_BACKENDS):
            raise BackendNotAvailableError(
                f"the {robot} runs on the league's simulator (backend 'rcsssmj' in-process, or "
                f"'rcssservermj' for a real server), not on {engine or backend!r}"
            )
        return backend or LEAGUE_BACKENDS[0]
    if engine is not None and engine not in ENGINES:
        raise BackendNotAvailableError(
            f"unknown engine {engine!r}; engines: {', '.join(map(repr, ENGINES))} "
            "(a real server is backend='rcssserver3d')"
        )
    if backend is None:
        return engine or DEFAULT_ENGINE
    if engine is not None and backend != engine:
        raise BackendNotAvailableError(
            f"backend={backend!r} and engine={engine!r} disagree; give one of them"
        )
    return backend


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
        TypeError: an option the backend does not take (named, with the ones it takes).
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
    params = inspect.signature(entry).parameters.values()
    if not any(p.kind is p.VAR_KEYWORD for p in params):
        names = [p.name for p in params if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)]
        unknown = sorted(set(kwargs) - set(names))
        if unknown:
            raise TypeError(
                f"unknown option(s) {', '.join(map(repr, unknown))} for the {name!r} backend; "
                f"options: {', '.join(names)}"
            )
    return entry(**kwargs)

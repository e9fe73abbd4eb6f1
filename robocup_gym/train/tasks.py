"""Task names of the CLI and how they map to Gymnasium ids and environments.

``import robocup_gym.envs`` registers the tasks as ``RobocupGym/<Name>-v<N>``; the CLI names are
their kebab-case forms (``RobocupGym/VelocityKick-v0`` → ``velocity-kick``). Any other registered
Gymnasium id (``Pendulum-v1``) is accepted as is, which keeps the training code usable for stock
environments and lets its tests run on a tiny one.
"""

from __future__ import annotations

import functools
import json
import re
import warnings
from collections.abc import Mapping
from typing import Any

import gymnasium as gym

from robocup_gym.backends import DEFAULT_ENGINE
from robocup_gym.train.algos import validate_algo_kwargs  # noqa: F401 (import path kept)

NAMESPACE = "RobocupGym"
_VERSION = re.compile(r"-v(\d+)$")


def _register_tasks() -> None:
    """Import the package's environments so that they register (no-op if not importable)."""
    try:
        import robocup_gym.envs  # noqa: F401
    except ImportError as exc:  # the envs package is optional while it is being built
        if "robocup_gym.envs" not in str(exc) and getattr(exc, "name", "") != "robocup_gym.envs":
            raise


def kebab(name: str) -> str:
    """``VelocityKick`` → ``velocity-kick``."""
    s = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "-", name)
    return s.replace("_", "-").lower()


def registered_tasks() -> dict[str, str]:
    """CLI task name → Gymnasium id (newest version) of every ``RobocupGym/…`` environment."""
    _register_tasks()
    best: dict[str, tuple[int, str]] = {}
    for env_id in gym.registry:
        if not env_id.startswith(NAMESPACE + "/"):
            continue
        base = env_id.split("/", 1)[1]
        m = _VERSION.search(base)
        version = int(m.group(1)) if m else 0
        name = kebab(_VERSION.sub("", base))
        if name not in best or version > best[name][0]:
            best[name] = (version, env_id)
    return {name: env_id for name, (_, env_id) in sorted(best.items())}


def resolve_task(task: str) -> str:
    """The Gymnasium id for a task name.

    Accepts the CLI name (``velocity-kick``), the class-style name (``VelocityKick``), a full
    RobocupGym id (``RobocupGym/VelocityKick-v0``) or any registered Gymnasium id.

    Raises:
        ValueError: for an unknown name, listing the known tasks.
    """
    tasks = registered_tasks()
    key = kebab(_VERSION.sub("", task.split("/", 1)[-1]))
    if task in gym.registry:
        return task
    if key in tasks:
        return tasks[key]
    loose = {name.replace("-", ""): env_id for name, env_id in tasks.items()}
    if key.replace("-", "") in loose:  # getup, velocitykick
        return loose[key.replace("-", "")]
    team = _team_task_id(key)
    if team is not None:
        return team
    known = ", ".join(tasks) or "(none registered: robocup_gym.envs did not register any task)"
    raise ValueError(
        f"unknown task {task!r}; known tasks: {known}; team scenarios: penalty, keepaway, "
        "game-NvN (or any registered Gymnasium id)"
    )


TEAM_TASK_PREFIX = "soccer/"
"""Ids of the team scenarios (``soccer/game-2v2``): :mod:`robocup_gym.train.selfplay`."""


def _team_task_id(key: str) -> str | None:
    """``soccer/<name>`` for a team scenario's name (``penalty``, ``game-2v2``), else ``None``."""
    if not (key in ("penalty", "keepaway") or key.startswith("game-")):
        return None
    from robocup_gym.soccer.team_view import team_scenario  # needs the soccer extra

    team_scenario(key)  # an impossible game (game-2v3, game-12v12): its own error
    return TEAM_TASK_PREFIX + key


def is_team_task(env_id: str) -> bool:
    """Whether ``env_id`` is a team scenario (one policy for a team's players)."""
    return env_id.startswith(TEAM_TASK_PREFIX)


def is_robocup_task(env_id: str) -> bool:
    return env_id.startswith(NAMESPACE + "/")


def task_name(env_id: str) -> str:
    """Short name of an id for folder names (``RobocupGym/VelocityKick-v0`` → ``velocity-kick``,
    ``soccer/game-2v2`` → ``game-2v2``)."""
    base = env_id.split("/", 1)[-1]
    return kebab(_VERSION.sub("", base)) if is_robocup_task(env_id) else base.lower()


def make_env(
    env_id: str,
    *,
    backend: str = DEFAULT_ENGINE,
    env_kwargs: dict[str, Any] | None = None,
    render_mode: str | None = None,
) -> gym.Env:
    """``gymnasium.make`` with the backend and config passed only to RobocupGym tasks.

    A task's ``max_episode_steps`` reaches its config (``gymnasium.make`` would take it as its
    own ``TimeLimit`` and leave the task's episode length, after which it computes its final
    reward, as it was); the ``TimeLimit`` gets the same number."""
    if env_kwargs is not None and not isinstance(env_kwargs, Mapping):
        raise ValueError(f"env_kwargs must map option names to values, got {env_kwargs!r}")
    kwargs = dict(env_kwargs or {})
    if is_team_task(env_id):
        raise ValueError(
            f"{task_name(env_id)} is a team scenario, not a single-agent environment: its "
            "players train together (robocup-gym train), and teams play with robocup-gym match"
        )
    if is_robocup_task(env_id):
        _register_tasks()  # subprocess workers start with an empty registry
        kwargs.setdefault("backend", backend)
        if "max_episode_steps" in kwargs and "config" not in kwargs:
            options = {k: v for k, v in kwargs.items() if k not in _NOT_CONFIG}
            config = _config_of(env_id, options)
            if config is not None:
                kwargs = {k: v for k, v in kwargs.items() if k in _NOT_CONFIG}
                kwargs["config"] = config
                # gymnasium.make passes the id's own options too, which would go over config
                kwargs.update({k: getattr(config, k) for k in _version_options(env_id)})
                kwargs["max_episode_steps"] = int(config.max_episode_steps)
    elif backend != DEFAULT_ENGINE:
        raise ValueError(f"--backend/--engine only apply to RobocupGym tasks, not {env_id!r}")
    if render_mode is not None:
        kwargs["render_mode"] = render_mode
    with warnings.catch_warnings():
        # an older version named on purpose (the one a policy was trained on) is not a mistake
        warnings.filterwarnings("ignore", ".*The environment .* is out of date", DeprecationWarning)
        return gym.make(env_id, **kwargs)


_NOT_CONFIG = ("backend", "render_mode", "render_size", "config")
"""``gymnasium.make`` keywords of the tasks that are not config fields."""


def _version_options(env_id: str) -> dict[str, Any]:
    """The options the registered id ``env_id`` sets over its class's defaults (a version's,
    ``RobocupGym/Run-v1``'s sprint, say)."""
    return {k: v for k, v in (gym.registry[env_id].kwargs or {}).items() if k not in _NOT_CONFIG}


def _class_defaults(env_id: str, robot: str = "nao"):
    """The config of the task class behind ``env_id`` with its class's defaults (no version's
    options); ``None`` for an environment that is not a RobocupGym task with a config."""
    if not is_robocup_task(env_id):
        return None
    _register_tasks()
    entry = gym.registry[env_id].entry_point
    if isinstance(entry, str):
        module, _, attr = entry.partition(":")
        import importlib

        cls = getattr(importlib.import_module(module), attr)
    else:
        cls = entry
    default_config = getattr(cls, "default_config", None)
    if default_config is None:
        return None
    return default_config(robot) if robot != "nao" else default_config()


def options_a_policy_takes_along(env_id: str, options: dict[str, Any]) -> dict[str, Any]:
    """Of a policy's ``options``, those that go with it to a run of the task ``env_id``: the
    ones that shape how it acts (the task config's ``policy_options``: its stance, the joints
    it drives, how its actions become commands, a reference motion; a walk's gait). Every one
    for an environment without a config (a team scenario's)."""
    base = _class_defaults(env_id, options.get("robot", "nao"))
    if base is None:
        return dict(options)
    return {k: v for k, v in options.items() if k in type(base).policy_options}


def _config_of(env_id: str, env_kwargs: dict[str, Any] | None):
    """The task's config as the id ``env_id`` makes it (its version's options over the class's
    defaults) with ``env_kwargs`` applied (validated), without starting any simulator; ``None``
    for an environment that is not a RobocupGym task with a config."""
    options = {k: v for k, v in (env_kwargs or {}).items() if k not in _NOT_CONFIG}
    base = _class_defaults(env_id, options.get("robot", "nao"))
    if base is None:
        return None
    return base.replace(**{**_version_options(env_id), **options})


def with_version_options(
    env_id: str, env_config: dict[str, Any], env_kwargs: dict[str, Any]
) -> dict[str, Any]:
    """A run's recorded ``env_config`` with its version's own options where the record kept
    the class's default instead (as a record written by an earlier robocup-gym did): an option
    the version sets, that the run did not set itself (``env_kwargs``) and that holds the
    class's default, takes the version's value, which the run's environment had."""
    if not env_config or env_id not in gym.registry:
        return env_config
    version = _version_options(env_id)
    base = _class_defaults(env_id, env_kwargs.get("robot", "nao")) if version else None
    if base is None:
        return env_config
    defaults = base.to_dict()
    plain = functools.partial(json.dumps, sort_keys=True, default=list)
    out = dict(env_config)
    for key, value in version.items():
        default = defaults.get(key)
        if key in env_kwargs or key not in out or plain(value) == plain(default):
            continue
        if plain(out[key]) == plain(default):
            out[key] = value
    return out


def resolved_env_config(env_id: str, env_kwargs: dict[str, Any] | None) -> dict[str, Any]:
    """Every option of the task ``env_id`` with ``env_kwargs`` applied, as plain values (what a
    run records in ``TrainConfig.env_config``); ``{}`` for other environments.
    ``backend_options`` (objects) are left out. No simulator is started, so a typo fails before
    a run folder or a worker process exists.

    Raises:
        ValueError: (:class:`~robocup_gym.envs.config.EnvConfigError`) naming the option and the
            valid ones, or the value and what it must be.
    """
    if is_team_task(env_id):
        from robocup_gym.soccer.team_view import scenario_options

        return scenario_options(task_name(env_id), env_kwargs)
    config = _config_of(env_id, env_kwargs)
    if config is None:
        return {}
    out = config.to_dict()
    out.pop("backend_options", None)
    return out

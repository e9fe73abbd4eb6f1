"""What every ``robocup-gym`` command shares: errors in one line (:func:`_fail`, usage errors as
click's own), the console, the options every command reads alike (``--engine``/``--backend``,
``--types``, ``--ray``, ``KEY=VALUE`` lists)."""

from __future__ import annotations

from typing import Any, NoReturn

import typer


def _console():
    from rich.console import Console

    return Console(soft_wrap=True)


def _click():
    """``(exceptions, globals)`` of the click that typer runs on (typer >= 0.20 carries its
    own copy)."""
    try:
        from typer._click import exceptions, globals
    except ImportError:  # pragma: no cover - older typer with the click package
        from click import exceptions, globals
    return exceptions, globals


def _usage_error(message: str) -> Exception:
    """A usage error of the running command (exit status 2, one line naming its ``--help``),
    as click's own."""
    exceptions, globals_ = _click()
    return exceptions.UsageError(message, ctx=globals_.get_current_context(silent=True))


def _task_measure_rows() -> list[tuple[str, str]]:
    """(summary key, label) of the tasks' own measures: GetUp's success rate and
    :data:`~robocup_gym.train.metrics.TASK_MEASURES`."""
    from robocup_gym.train.metrics import TASK_MEASURES

    return [("success_rate", "success rate")] + [
        (f"{key}_mean", label) for key, label in TASK_MEASURES.items()
    ]


def _robot_types(types: str | None) -> list[int] | None:
    """``--types 0,1,2`` as numbers (``None`` stays ``None``); exits with a clear error."""
    if types is None:
        return None
    try:
        return [int(t) for t in types.split(",")]
    except ValueError:
        _fail(f"--types expects numbers like 0,1,2, got {types!r}")


def _fail(message: str, code: int = 1) -> NoReturn:
    from rich.console import Console
    from rich.markup import escape

    Console(stderr=True, soft_wrap=True).print(
        f"[bold red]error:[/bold red] {escape(message)}", highlight=False
    )
    raise typer.Exit(code)


def _single_thread_torch() -> None:
    """Inference of small MLPs is fastest (and immune to busy cores) on one thread."""
    import torch

    torch.set_num_threads(1)


def _backend(backend: str | None, engine: str | None) -> str | None:
    """``--backend``/``--engine`` as one backend name (``None`` when neither is given)."""
    if backend is None and engine is None:
        return None
    from robocup_gym.backends import BackendNotAvailableError, resolve_backend

    try:
        return resolve_backend(backend, engine)
    except BackendNotAvailableError as exc:
        _fail(str(exc))


_RESUME_OPTIONS = {"timesteps", "n_workers"}
"""TrainConfig options a resumed run takes (its new total; where its environments step)."""


def _placement(ray: bool | None, ray_address: str | None, n_workers: int | None) -> dict[str, Any]:
    """Where a run's environments step (``--ray/--no-ray``, ``--ray-address``, ``--n-workers``),
    as TrainConfig fields; only those given. Without Ray installed, ``--ray`` says how to get
    it."""
    out: dict[str, Any] = {}
    if n_workers is not None:
        out["n_workers"] = n_workers
    if ray is False:
        if ray_address:
            _fail("--no-ray and --ray-address contradict each other")
        out["vec_env"], out["ray_address"] = "auto", ""
    elif ray or ray_address:
        from robocup_gym.train.ray_vecenv import import_ray

        try:
            import_ray()
        except ImportError as exc:
            _fail(str(exc))
        out["vec_env"] = "ray"
        out["ray_address"] = ray_address or ""
    return out


def _parse_assignments(items: list[str] | None, what: str) -> dict[str, Any]:
    """``["a=1", "b=[1, 2]"]`` → ``{"a": 1, "b": [1, 2]}`` (values read as YAML; ``3e-4`` is a
    number); a malformed item ends the command with its message."""
    from robocup_gym.train.config import parse_assignments

    try:
        return parse_assignments(items, what)
    except ValueError as exc:
        _fail(str(exc))

"""``robocup-gym``: train, evaluate, export and serve (see ``docs/training.md``).

The commands live in :mod:`robocup_gym.cli.training` (train, eval, export, tasks, experiments)
and :mod:`robocup_gym.cli.game` (agent, serve, match, team). Heavy libraries (torch,
Stable-Baselines3, MuJoCo) are imported inside the commands, so ``robocup-gym --help`` answers at
once and ``robocup-gym train`` prints where it is going before the learner starts.
"""

from __future__ import annotations

import importlib
import sys

try:
    import typer
except ImportError:  # pragma: no cover - the CLI needs the train extra
    typer = None

if typer is not None:
    from robocup_gym.cli.app import app, experiments_app, summarise_commands
    from robocup_gym.cli.common import _click
    from robocup_gym.cli.options import _NOT_TRAIN_OPTIONS

    for _commands in ("training", "game"):  # they register on `app`, in --help's order
        importlib.import_module(f"robocup_gym.cli.{_commands}")
    summarise_commands(app, experiments_app)

_MISSING_EXTRA = (
    "robocup-gym's command line needs the training extra: pip install -e '.[train]' "
    "(typer, rich, torch, stable-baselines3, …)"
)

__all__ = ["_NOT_TRAIN_OPTIONS", "app", "experiments_app", "main"]


def _require_typer() -> None:
    if typer is None:  # pragma: no cover
        sys.stderr.write(_MISSING_EXTRA + "\n")
        raise SystemExit(1)


def main(argv: list[str] | None = None) -> None:
    """Entry point of the ``robocup-gym`` script. Usage errors (an unknown command or option, a
    value of the wrong type, a missing argument) are one line on stderr, exit status 2."""
    _require_typer()
    cx = _click()[0]

    try:
        code = app(args=argv, standalone_mode=False)
    except getattr(cx, "NoArgsIsHelpError", ()) as exc:  # `robocup-gym` alone: the help
        sys.stdout.write(exc.ctx.get_help() + "\n")
        raise SystemExit(0) from None
    except cx.UsageError as exc:
        where = exc.ctx.command_path if exc.ctx is not None else "robocup-gym"
        message = " ".join(exc.format_message().split())
        sys.stderr.write(f"error: {message} (see {where} --help)\n")
        raise SystemExit(2) from None
    except cx.ClickException as exc:
        sys.stderr.write(f"error: {' '.join(exc.format_message().split())}\n")
        raise SystemExit(exc.exit_code) from None
    except (KeyboardInterrupt, getattr(cx, "Abort", KeyboardInterrupt)):
        sys.stderr.write("aborted\n")
        raise SystemExit(130) from None
    raise SystemExit(code if isinstance(code, int) else 0)

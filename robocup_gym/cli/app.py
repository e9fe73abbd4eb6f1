"""The ``robocup-gym`` command group and its ``experiments`` subgroup; the commands register
themselves on them (:mod:`robocup_gym.cli.training`, :mod:`robocup_gym.cli.game`)."""

import inspect

import typer

app = typer.Typer(
    name="robocup-gym",
    help="Train RoboCup 3D Nao skills on SimSpark's physics (ODE; MuJoCo as the fast "
    "approximation): train, eval, export to ONNX, reproduce the paper, serve the "
    "rcssserver3d protocol.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
experiments_app = typer.Typer(
    help="Reproduce the paper's experiments; learning curves of the locomotion tasks.",
    no_args_is_help=True,
    add_completion=False,
)
app.add_typer(experiments_app, name="experiments")


def summarise_commands(*groups: typer.Typer) -> None:
    """Give every command of ``groups`` that has none a one-line summary for the groups' command
    lists: its docstring's first paragraph on one line (rich's help keeps a docstring's line
    breaks there, which then split the list's sentences mid-way)."""
    for group in groups:
        for info in group.registered_commands:
            doc = info.help or (info.callback.__doc__ if info.callback else None) or ""
            doc = inspect.cleandoc(doc)
            if info.short_help is None and doc:
                info.short_help = " ".join(doc.split("\n\n")[0].split())

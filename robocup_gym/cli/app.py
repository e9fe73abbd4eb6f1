"""The ``robocup-gym`` command group and its ``experiments`` subgroup; the commands register
themselves on them (:mod:`robocup_gym.cli.training`, :mod:`robocup_gym.cli.game`)."""

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

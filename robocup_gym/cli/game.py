"""The commands that play: ``agent`` (a policy on any rcssserver3d-protocol server), ``serve``
(the world behind that protocol), ``match`` and ``team``."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated, Any

import typer

from robocup_gym.cli.app import app
from robocup_gym.cli.common import _console, _fail, _parse_assignments, _robot_types, _usage_error


# ------------------------------------------------------------------------------ agent
@app.command()
def agent(
    onnx: Annotated[
        Path | None,
        typer.Argument(help="Exported policy (.onnx), or --pretrained.", exists=True),
    ] = None,
    pretrained: Annotated[
        str | None,
        typer.Option("--pretrained", help="Run a policy shipped with the package (e.g. get-up)."),
    ] = None,
    host: Annotated[str, typer.Option(help="Server address.")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="Agent port.")] = 3100,
    monitor_port: Annotated[
        int | None,
        typer.Option(help="Monitor/trainer port to reset episodes (e.g. 3200)."),
    ] = None,
    episodes: Annotated[int, typer.Option(help="Episodes to run.")] = 1,
    team: Annotated[str, typer.Option(help="Team name.")] = "RoboCupGym",
    unum: Annotated[int, typer.Option(help="Uniform number (0 = server's choice).")] = 0,
    sync: Annotated[bool, typer.Option(help="Send (syn) every cycle.")] = True,
    monitor_interval: Annotated[
        int,
        typer.Option(
            help="The server's cycles per monitor frame (2: rcssserver3d's default and "
            "robocup-gym serve's)."
        ),
    ] = 2,
    seed: Annotated[int, typer.Option(help="Seed of the first episode (as eval).")] = 100_000,
    env: Annotated[
        list[str] | None,
        typer.Option(
            "--env",
            help="Environment option KEY=VALUE over the policy's own (repeatable; not one "
            "that changes the observation), e.g. --env max_episode_steps=1000.",
        ),
    ] = None,
    command: Annotated[
        str | None,
        typer.Option(
            "--command",
            help="A Walk policy's velocity command, 'FORWARD,LEFT,TURN' in m/s, m/s and "
            "deg/s (CCW positive), held for the whole episode, e.g. --command 0.5,0,0.",
        ),
    ] = None,
) -> None:
    """Drive a robot with an exported policy over the rcssserver3d protocol.

    With --monitor-port the episodes start as in training and ground truth comes from the
    monitor stream (the policy sees what it sees in `eval`); without it, from the See
    extensions of a server started with ground truth. A walk goes where --command says."""
    from robocup_gym.train.agent import run_onnx_agent

    console = _console()
    if onnx is None and pretrained is None:
        raise _usage_error("Missing argument 'onnx' (an exported policy, or --pretrained)")
    if onnx is not None and pretrained is not None:
        _fail("give an exported policy (.onnx) or --pretrained NAME, not both")
    overrides = _parse_assignments(env, "--env")
    if pretrained is not None:
        from robocup_gym.train.pretrained import pretrained_path

        try:
            robot_type = overrides.get("robot_type")  # a bad one is refused by the environment
            onnx = pretrained_path(pretrained, robot_type if isinstance(robot_type, int) else None)
        except ValueError as exc:
            _fail(str(exc))
    reset_options: dict[str, Any] = {}
    if command is not None:
        parts = command.split(",")
        try:
            velocity = [float(p) for p in parts]
        except ValueError:
            velocity = []
        if len(velocity) != 3 or not all(math.isfinite(v) for v in velocity):
            raise _usage_error(
                f"--command expects FORWARD,LEFT,TURN (m/s, m/s, deg/s), got {command!r}"
            )
        from robocup_gym.train.onnx_policy import read_metadata
        from robocup_gym.train.pretrained import recorded_env_options

        try:
            meta = read_metadata(onnx)
        except (OSError, ValueError) as exc:
            _fail(str(exc))
        if "command_change_steps" not in recorded_env_options(meta):
            _fail(
                f"--command gives a Walk policy its velocity_command; {onnx} is a "
                f"{meta.get('env_id')} policy, which takes none"
            )
        reset_options["velocity_command"] = tuple(velocity)
        overrides.setdefault("command_change_steps", 0)

    def report(rep) -> None:
        d, t = rep.ball_displacement, rep.torso_displacement
        console.print(
            f"episode: {rep.steps} steps, fallen={rep.fallen}, ball displacement "
            + ("–" if d is None else f"({d[0]:+.2f}, {d[1]:+.2f}) m")
            + ("" if t is None else f", torso moved ({t[0]:+.2f}, {t[1]:+.2f}) m")
            + ("" if rep.success is None else f", success={rep.success}")
            + ("" if rep.steps_to_up is None else f" (up at step {rep.steps_to_up})")
        )

    try:
        run_onnx_agent(
            str(onnx),
            host=host,
            port=port,
            monitor_port=monitor_port,
            episodes=episodes,
            team=team,
            unum=unum,
            sync=sync,
            monitor_interval=monitor_interval,
            seed=seed,
            on_episode=report,
            env_overrides=overrides,
            reset_options=reset_options,
        )
    except (OSError, RuntimeError, ValueError) as exc:
        _fail(str(exc))


# ------------------------------------------------------------------------------ serve
@app.command(
    context_settings={"allow_extra_args": True, "ignore_unknown_options": True},
    add_help_option=False,
)
def serve(ctx: typer.Context) -> None:
    """Serve the embedded world over the rcssserver3d protocol (agents, RoboViz); the
    options of `python -m robocup_gym.server` (see robocup-gym serve --help)."""
    try:
        from robocup_gym.server.__main__ import main as server_main
    except ImportError as exc:
        _fail(f"the server is not available in this installation (robocup_gym.server: {exc})")
    raise typer.Exit(server_main(list(ctx.args), prog="robocup-gym serve"))


# ------------------------------------------------------------------------------ match
@app.command()
def match(
    team_a: Annotated[
        str,
        typer.Argument(
            help="A team: scripted, standing, a team run's folder, an exported team policy "
            "(.onnx) or pretrained:NAME."
        ),
    ],
    team_b: Annotated[str, typer.Argument(help="The other team.")],
    games: Annotated[int, typer.Option(help="Games to play (sides change every game).")] = 20,
    players: Annotated[
        int | None, typer.Option(help="Players a side (1-11; default 2, a penalty 1).")
    ] = None,
    seconds: Annotated[
        float | None,
        typer.Option(help="Game time of each game, s (default 120; a penalty's 10)."),
    ] = None,
    scenario: Annotated[
        str,
        typer.Option(
            help="game, or penalty: the first team's striker against the second's "
            "goalkeeper in every game."
        ),
    ] = "game",
    types: Annotated[
        str | None,
        typer.Option(help="Each team's robot types, e.g. 0,1 (default 0,1,2,3,4 in turn)."),
    ] = None,
    engine: Annotated[str, typer.Option(help="ode (SimSpark's physics) or mujoco.")] = "ode",
    seed: Annotated[int, typer.Option(help="Game k is seeded with seed + k.")] = 0,
    video: Annotated[
        Path | None,
        typer.Option(
            help="Record the first game to this .mp4 (or .gif) file, from the side, "
            "following the ball (headless: MUJOCO_GL=egl)."
        ),
    ] = None,
    on: Annotated[
        str,
        typer.Option(
            help="in-process, serve (a fresh robocup-gym serve each game) or rcssserver3d "
            "(a real one: RCSSSERVER3D or PATH); on a server each player is its own "
            "connection acting on its own perceptors."
        ),
    ] = "in-process",
    walk: Annotated[
        str | None,
        typer.Option(
            help="In-process: the shipped walk of the players' skill actions: game-walk (the "
            "game's, to which the scripted team is tuned) or walk (the omnidirectional one). "
            "Default: the one a learnt team was trained with, else game-walk."
        ),
    ] = None,
) -> None:
    """Play two teams against each other, in-process (multi-agent soccer with skill
    actions) or on a server; a table, then one JSON object from the first team's side."""

    from rich.table import Table

    try:
        from robocup_gym.soccer.match import SERVERS, play_match, play_server_match
    except ImportError as exc:
        _fail(str(exc))
    if on not in ("in-process", *SERVERS):
        _fail(f"--on must be in-process, {', '.join(SERVERS)}; got {on!r}")
    if on != "in-process" and (scenario != "game" or video is not None):
        _fail(f"on {on} a match plays games (no --scenario penalty, no --video)")
    if on != "in-process" and walk not in (None, "game-walk"):
        _fail(f"on {on} the players walk with game-walk (--walk is for in-process matches)")
    robot_types = _robot_types(types)
    console = _console()

    def progress(k: int, g) -> None:
        console.print(
            f"game {k + 1}/{games}: {team_a} ({g.a_side}) {g.goals_for} : "
            f"{g.goals_against} {team_b}" + (" (the simulation diverged)" if g.diverged else ""),
            highlight=False,
        )

    try:
        if on == "in-process":
            result = play_match(
                team_a,
                team_b,
                games=games,
                players=players,
                seconds=seconds,
                robot_types=robot_types,
                engine=engine,
                seed=seed,
                on_game=progress,
                video=video,
                scenario=scenario,
                walk=walk,
            )
        else:
            result = play_server_match(
                team_a,
                team_b,
                server=on,
                games=games,
                players=2 if players is None else players,
                seconds=120.0 if seconds is None else seconds,
                robot_types=robot_types,
                engine=engine,
                seed=seed,
                on_game=progress,
            )
    except (ValueError, RuntimeError, OSError) as exc:
        _fail(str(exc))
    summary = result.summary
    first = result.games[0]
    if scenario == "penalty":
        title = f"{team_a}'s striker against {team_b}'s goalkeeper: {first.seconds:g} s each"
    else:
        per_side = players if players is not None else 2
        title = f"{team_a} against {team_b}: {per_side} a side, {first.seconds:g} s a game"
    table = Table(title=title)
    for col in ("games", "wins", "draws", "losses", "goals for", "goals against", "ci95"):
        table.add_column(col, justify="right")
    table.add_row(
        *map(
            str,
            (
                summary["games"],
                summary["wins"],
                summary["draws"],
                summary["losses"],
                summary["goals_for"],
                summary["goals_against"],
                summary["goal_difference_ci95"],
            ),
        )
    )
    console.print(table)
    print(json.dumps(summary))


# ------------------------------------------------------------------------------ team
@app.command()
def team(
    policy: Annotated[
        str,
        typer.Argument(
            help="The team: scripted, standing, a team run's folder, an exported team "
            "policy (.onnx) or pretrained:NAME."
        ),
    ],
    host: Annotated[str, typer.Option(help="The server's address.")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="The server's agent port.")] = 3100,
    team_name: Annotated[
        str, typer.Option("--team", help="The team's name on the server.")
    ] = "RoboCupGym",
    players: Annotated[int, typer.Option(help="Players (1-11), each its own connection.")] = 2,
    types: Annotated[
        str | None,
        typer.Option(help="The players' robot types, e.g. 0,1 (default 0,1,2,3 in turn)."),
    ] = None,
    seconds: Annotated[
        float | None,
        typer.Option(help="Stop after this much game time, s (default: until GameOver)."),
    ] = None,
    timeout: Annotated[
        float,
        typer.Option(
            help="Seconds without a percept before the server counts as gone (and, up to "
            "5 s, to wait for a starting server)."
        ),
    ] = 10.0,
    seed: Annotated[
        int | None,
        typer.Option(
            help="Seeds the team's skills: on a server in sync mode started with a seed, "
            "the same game every time (default: fresh randomness)."
        ),
    ] = None,
) -> None:
    """Play a team on a server (robocup-gym serve or rcssserver3d): each player its own
    agent connection, acting on its own perceptors (it places itself from the landmarks it
    sees) with the shipped skills; the server's referee starts the game. Prints the goals
    as they come and, last, one JSON object."""

    if not 1 <= port <= 65535:
        _fail(f"port {port} is not a port number (1-65535)")
    if not timeout > 0:
        _fail(f"--timeout must be a positive number of seconds, got {timeout}")
    robot_types = _robot_types(types)
    try:
        from robocup_gym.soccer.match import make_team
        from robocup_gym.soccer.remote import ServerTeam
    except ImportError as exc:
        _fail(str(exc))
    console = _console()
    try:
        chosen = make_team(policy)
        check = getattr(chosen, "check_fits", None)
        if check is not None:
            check("game", players, penalties=False)
        with ServerTeam(
            chosen, host, port, team_name, players, robot_types, timeout=timeout, seed=seed
        ) as playing:
            console.print(
                f"{team_name}: {players} player(s) on {host}:{port}, playing "
                f"{playing.side}; waiting for the kick-off",
                highlight=False,
            )
            result = playing.play(seconds, on_event=lambda e: console.print(e, highlight=False))
    except (OSError, ValueError, RuntimeError) as exc:
        _fail(str(exc))
    print(json.dumps(result.summary))
    if result.end not in ("GameOver", "time"):
        _fail(result.end)

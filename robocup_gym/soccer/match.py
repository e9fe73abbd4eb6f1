"""Matches between two teams: ``robocup-gym match A B --games G`` (in-process, or on a server
with ``--on serve|rcssserver3d``).

Each game is :mod:`robocup_gym.soccer.game_v1` with skill actions, ``players`` a side, for
``seconds`` of game time; the teams change sides every game (team A plays left in the first).
With ``scenario="penalty"`` each game is a penalty (:mod:`robocup_gym.soccer.penalty_v1`):
team A's striker against team B's goalkeeper.
The result is counted from team A's side: wins, draws, losses, goals for and against, and a 95 %
interval of the mean goal difference per game (normal approximation, from two games on).

:func:`play_server_match` plays the same games on a server, each on a fresh one: every player
its own connection acting on its own perceptors (:class:`robocup_gym.soccer.remote.ServerTeam`),
the server's referee, a trainer's kick-off; the team that connects first plays left (team A in
the first game, the teams change sides every game).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from robocup_gym.soccer import game_v1, penalty_v1
from robocup_gym.soccer.scripted import TEAMS
from robocup_gym.soccer.skills import runs_a_command_loop, skills_of_teams, walk_of_teams
from robocup_gym.types import is_integer

__all__ = ["SERVERS", "GameResult", "MatchResult", "make_team", "play_match", "play_server_match"]

SERVERS = ("serve", "rcssserver3d")
"""What :func:`play_server_match` plays on: ``robocup-gym serve`` or a real rcssserver3d."""

Team = Callable[[Any, list[str], dict[str, np.ndarray]], dict[str, np.ndarray]]
"""A team: ``team(env, agents, obs) → {agent: skill action}``."""


def make_team(spec: str | Team) -> Team:
    """A team by name: ``scripted``, ``standing``, a team run's folder, an exported team policy
    (``.onnx``) or a shipped one (``pretrained:NAME``); a team object (a callable
    ``team(env, agents, obs)``) is itself.

    Raises:
        ValueError: an unknown team (naming the known ones), or a policy that is not a team's.
    """
    if not isinstance(spec, str):
        if callable(spec):
            return spec
        raise ValueError(
            f"a team is a name or a callable team(env, agents, obs), got {type(spec).__name__}"
        )
    cls = TEAMS.get(spec)
    if cls is not None:
        return cls()
    from robocup_gym.soccer.learnt import PolicyTeam

    if spec.startswith("pretrained:"):
        from robocup_gym.train.pretrained import pretrained_path

        return PolicyTeam.from_onnx(pretrained_path(spec.split(":", 1)[1]), name=spec)
    path = Path(spec)
    if path.suffix == ".onnx" and path.is_file():
        return PolicyTeam.from_onnx(path)
    if path.is_dir():
        return PolicyTeam.from_run(path)
    raise ValueError(
        f"unknown team {spec!r}; teams: {', '.join(sorted(TEAMS))}, a team run's folder, an "
        "exported team policy (.onnx) or pretrained:NAME"
    )


@dataclass
class GameResult:
    """One game, from team A's side."""

    a_side: str
    goals_for: int
    goals_against: int
    seconds: float
    diverged: bool = False


@dataclass
class MatchResult:
    """A match, from team A's side."""

    team_a: str
    team_b: str
    games: list[GameResult] = field(default_factory=list)
    video: str | None = None
    """The recorded first game, if one was asked for."""

    @property
    def summary(self) -> dict[str, Any]:
        from robocup_gym.train.metrics import mean_ci95

        diffs = np.array([g.goals_for - g.goals_against for g in self.games], float)
        n = len(diffs)
        return {
            "team_a": self.team_a,
            "team_b": self.team_b,
            "games": n,
            "wins": int((diffs > 0).sum()),
            "draws": int((diffs == 0).sum()),
            "losses": int((diffs < 0).sum()),
            "goals_for": int(sum(g.goals_for for g in self.games)),
            "goals_against": int(sum(g.goals_against for g in self.games)),
            "goal_difference_mean": round(float(diffs.mean()), 3) if n else None,
            "goal_difference_ci95": mean_ci95(diffs),
            "diverged_games": int(sum(g.diverged for g in self.games)),
            **({"video": self.video} if self.video is not None else {}),
        }


def _team_name(spec: str | Team) -> str:
    """How a match names a team: its name as given, or a team object's ``name`` (else its
    class's)."""
    return spec if isinstance(spec, str) else str(getattr(spec, "name", type(spec).__name__))


def play_match(
    team_a: str | Team,
    team_b: str | Team,
    *,
    games: int = 20,
    players: int | None = None,
    seconds: float | None = None,
    robot_types: Sequence[int] | None = None,
    engine: str = "ode",
    seed: int = 0,
    on_game: Callable[[int, GameResult], None] | None = None,
    video: str | os.PathLike | None = None,
    scenario: str = "game",
    walk: str | None = None,
) -> MatchResult:
    """Play ``games`` games of ``team_a`` against ``team_b`` (each a name, as
    :func:`make_team` takes, or a team object; the game lists the motion skills and walk a
    team's ``options`` names, as a learnt team's do).

    Args:
        players: Players a side (1–11; default 2; a penalty has 1).
        seconds: Game time of each game, s (default 120; a penalty's: 10).
        scenario: ``"game"`` (:mod:`.game_v1`; the teams change sides every game) or
            ``"penalty"`` (:mod:`.penalty_v1`: team A's striker against team B's goalkeeper
            in every game, which ends at a goal, when the ball leaves the field or after
            ``seconds``; the ball's spot varies by up to 0.3 m sideways).
        robot_types: Each team's robot types (default: types 0, 1, 2, 3, 4 in turn).
        seed: Game k is seeded with ``seed + k``.
        on_game: Called after each game.
        video: Record the first game to this file (``.mp4``, or ``.gif``) at 25 frames a second
            of game time, from the side, following the ball (MuJoCo's renderer).
        walk: The shipped walk of both teams' skill actions: ``game-walk`` (the game's), or
            ``walk`` (the omnidirectional walk, which runs a command loop and so sees the
            players as they face: ``walk_faces_x`` off). Default: the walk a learnt team was
            trained with, else ``game-walk`` (:func:`~robocup_gym.soccer.skills.walk_of_teams`).

    Raises:
        ValueError: an unknown team or an impossible set-up.
    """
    if scenario not in ("game", "penalty"):
        raise ValueError(f"scenario must be 'game' or 'penalty', got {scenario!r}")
    penalty = scenario == "penalty"
    players = (1 if penalty else 2) if players is None else players
    seconds = (10.0 if penalty else 120.0) if seconds is None else float(seconds)
    if penalty and players != 1:
        raise ValueError(f"a penalty has 1 player a side, got {players!r}")
    a, b, types = _match_setup(team_a, team_b, scenario, games, players, seconds, robot_types, seed)
    walk = walk_of_teams(a, b, asked=walk)
    cycles = round(seconds / 0.02)
    result = MatchResult(_team_name(team_a), _team_name(team_b))
    recorder = None
    if video is not None:
        from robocup_gym.train.evaluate import FrameRecorder, check_renderer, ensure_gl_backend

        ensure_gl_backend()
        check_renderer()
        recorder = FrameRecorder(every=2)  # 25 frames a second of game time
    privileged = any(getattr(t, "privileged", False) for t in (a, b))
    options: dict[str, Any] = {
        "actions": "skills",
        "skills": skills_of_teams(a, b),
        "privileged": privileged,
        "left_types": types,
        "right_types": types,
        "engine": engine,
        "max_cycles": cycles,
        "render_mode": None if video is None else "rgb_array",
        "walk": walk,
        "walk_faces_x": not runs_a_command_loop(walk),
    }
    if penalty:
        env = penalty_v1.parallel_env(start_noise=penalty_v1.SPREAD_M, **options)
    else:
        env = game_v1.parallel_env(**options)
    try:
        for k in range(games):
            a_side = "left" if k % 2 == 0 or penalty else "right"
            env.cycle_hook = recorder if k == 0 else None
            obs, _ = env.reset(seed=seed + k)
            diverged = False
            while env.agents:
                mine = [n for n in env.agents if n.startswith(a_side)]
                theirs = [n for n in env.agents if not n.startswith(a_side)]
                obs, _, _, _, infos = env.step({**a(env, mine, obs), **b(env, theirs, obs)})
                diverged = diverged or any("diverged" in i for i in infos.values())
            g = env.game.world.game
            own, other = (
                (g.score_left, g.score_right) if a_side == "left" else (g.score_right, g.score_left)
            )
            game = GameResult(a_side, int(own), int(other), seconds, diverged)
            result.games.append(game)
            if recorder is not None and k == 0:
                result.video = str(recorder.save(video, fps=25.0))
                recorder.close()
            if on_game is not None:
                on_game(k, game)
    finally:
        env.close()
    return result


def _match_setup(
    team_a: str | Team,
    team_b: str | Team,
    scenario: str,
    games: int,
    players: int,
    seconds: float,
    robot_types: Sequence[int] | None,
    seed: int,
) -> tuple[Team, Team, tuple[int, ...]]:
    """The two teams and the robot types of a match, its numbers checked.

    Raises:
        ValueError: a count, duration, seed or robot types that cannot be played, an unknown
            team, or a learnt team made for another scenario or size.
    """
    if isinstance(games, bool) or not isinstance(games, int) or games < 1:
        raise ValueError(f"games must be a positive integer, got {games!r}")
    if not (is_integer(seed) and seed >= 0):
        raise ValueError(f"seed must be an integer >= 0 (game k plays seed + k), got {seed!r}")
    if not 1 <= int(players) <= 11:
        raise ValueError(f"players must be 1-11 a side, got {players!r}")
    if not (math.isfinite(seconds) and seconds > 0):
        raise ValueError(f"seconds must be a positive duration, got {seconds!r}")
    a, b = make_team(team_a), make_team(team_b)
    for team in (a, b):
        if hasattr(team, "check_fits"):  # a learnt team plays what it was trained for
            team.check_fits(scenario, int(players))
    types = tuple(robot_types) if robot_types is not None else tuple(k % 5 for k in range(players))
    if len(types) != players:
        raise ValueError(f"{players} players need {players} robot types, got {types!r}")
    return a, b, types


def play_server_match(
    team_a: str,
    team_b: str,
    *,
    server: str = "serve",
    games: int = 20,
    players: int = 2,
    seconds: float = 120.0,
    robot_types: Sequence[int] | None = None,
    engine: str = "ode",
    seed: int = 0,
    binary: str | os.PathLike | None = None,
    on_game: Callable[[int, GameResult], None] | None = None,
) -> MatchResult:
    """Play ``games`` games of ``team_a`` against ``team_b`` on a server, a fresh one each game.

    Args:
        server: ``"serve"`` (``robocup-gym serve`` in sync mode, real time off, on ``engine``,
            game k's noise and the teams' skills seeded from ``seed + k``: the same games on
            every run of one machine) or ``"rcssserver3d"`` (a real one in sync mode, real
            time off: ``binary``, else ``RCSSSERVER3D`` or ``PATH``).
        players, seconds, robot_types: as :func:`play_match` (1–11 players, default 120 s).

    Raises:
        ValueError: an unknown server or team, or an impossible set-up.
        RcssServerNotFoundError: ``"rcssserver3d"`` where none is installed.
        ConnectionError: a server that stops answering mid-game (its message says which).
    """
    if server not in SERVERS:
        raise ValueError(f"server must be one of {', '.join(SERVERS)}, got {server!r}")
    seconds = float(seconds)
    a, b, types = _match_setup(team_a, team_b, "game", games, players, seconds, robot_types, seed)
    from robocup_gym.soccer.remote import check_server_walk

    check_server_walk(a, b)
    teams = {"A": a, "B": b}
    result = MatchResult(team_a, team_b)
    for k in range(games):
        order = ("A", "B") if k % 2 == 0 else ("B", "A")
        with _GameServer(server, engine, seed + k, binary) as ports:
            settle = SETTLE_CYCLES if server == "serve" else 0
            played = _server_game(teams, order, ports, types, seconds, seed + k, settle)
        a = played["A"]
        game = GameResult(a.side, int(a.goals_for), int(a.goals_against), seconds)
        result.games.append(game)
        if on_game is not None:
            on_game(k, game)
    return result


SETTLE_CYCLES = 50
"""Monitor frames (cycles: ``serve`` runs with a monitor interval of 1 here) a match waits for
on a fresh ``serve`` before its teams join."""
KICKOFF_AFTER_CYCLES = 10
"""Cycles of the teams' play before a match's trainer kicks off on a server (each player
beams to its place in the first and stands)."""


def _wait_frames(trainer, frames: int) -> None:
    """Read ``frames`` monitor frames from a trainer's connection (each one cycle of a server
    whose monitor interval is 1)."""
    from robocup_gym.protocol.framing import FrameDecoder, recv_frame

    decoder = FrameDecoder()
    for _ in range(frames):
        recv_frame(trainer, decoder, 10.0)


def _sends_at_cycle(trainer, cycle: int, message: str) -> Callable[[Any], None]:
    """An ``on_cycle`` for :meth:`ServerTeam.play <robocup_gym.soccer.remote.ServerTeam.play>`
    that sends the trainer command ``message`` before the team answers its ``cycle``-th
    percept (on a sync server whose monitor interval is 1 it acts in the next cycle)."""
    from robocup_gym.protocol.framing import send_frame

    seen = 0

    def on_cycle(_) -> None:
        nonlocal seen
        seen += 1
        if seen == cycle:
            send_frame(trainer, message)

    return on_cycle


def _server_game(
    teams: dict[str, Team],
    order: tuple[str, str],
    ports: tuple[int, int],
    types: tuple[int, ...],
    seconds: float,
    seed: int | None = None,
    settle_cycles: int = 0,
) -> dict[str, Any]:
    """One game on a running server: ``teams[order[0]]`` joins first (and plays left), then
    the other beside it; a trainer kicks off once both have stood in their formation for
    :data:`KICKOFF_AFTER_CYCLES` cycles; returns each team's :class:`TeamResult` by name.

    Both teams join from this thread in fixed cycles (the second holds the first's players
    while it joins), the kick-off is sent in a fixed cycle of theirs (before the first team
    answers it: on a ``serve`` that reads trainer commands every cycle it acts in the next), and
    the teams' skills are seeded from ``seed``. With ``settle_cycles`` the first team joins
    only after the trainer's connection has seen that many monitor frames (the ball settles on
    the centre spot and sleeps within ~25 cycles of a server's start; a team that joined
    before that played another game). On ``serve`` seeded with ``seed``, in sync mode, the
    game is then the same every time on one machine."""
    import contextlib
    import socket
    import threading

    from robocup_gym.protocol import trainer as trainer_cmds
    from robocup_gym.protocol.framing import connect
    from robocup_gym.soccer.remote import ServerTeam

    agent_port, monitor_port = ports
    played: dict[str, Any] = {}
    errors: list[BaseException] = []
    joined: list[ServerTeam] = []
    trainer = connect("127.0.0.1", monitor_port, retry_s=10.0)
    # the first team's percepts, before it answers them
    kick_off = _sends_at_cycle(trainer, KICKOFF_AFTER_CYCLES, trainer_cmds.kick_off("Left"))

    def drain() -> None:  # the trainer's monitor frames, read so that no server waits on them
        with contextlib.suppress(OSError):
            while trainer.recv(1 << 16):
                pass

    def play(name: str, team: ServerTeam, on_cycle) -> None:
        try:
            played[name] = team.play(seconds, on_cycle=on_cycle)
        except BaseException as exc:  # raised on the caller's thread
            errors.append(exc)

    try:
        _wait_frames(trainer, settle_cycles)
        threading.Thread(target=drain, daemon=True).start()
        for i, name in enumerate(order):
            joined.append(
                ServerTeam(
                    teams[name], port=agent_port, name=f"Team{name}", players=len(types),
                    robot_types=types, timeout=60.0,
                    seed=None if seed is None else 2 * seed + i,
                    alongside=joined[0] if joined else None,
                )
            )  # fmt: skip
        threads = [
            threading.Thread(
                target=play, args=(name, team, kick_off if i == 0 else None), daemon=True
            )
            for i, (name, team) in enumerate(zip(order, joined, strict=True))
        ]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        for team in joined:
            team.close()
        with contextlib.suppress(OSError):
            trainer.shutdown(socket.SHUT_RDWR)  # ends the drain
        trainer.close()
    if errors:
        raise errors[0]
    return played


class _GameServer:
    """A fresh server for one game: ``(agent port, monitor port)`` on entering, stopped on
    leaving."""

    def __init__(self, server: str, engine: str, seed: int, binary) -> None:
        self.server, self.engine, self.seed, self.binary = server, engine, seed, binary
        self._proc: Any = None
        self._real: Any = None

    def __enter__(self) -> tuple[int, int]:
        if self.server == "serve":
            from robocup_gym.server.bench import start_server_process

            args = (
                "--sync", "--no-real-time", "--engine", self.engine, "--seed", str(self.seed),
                "--monitor-interval", "1",  # a trainer command acts in the next cycle
            )  # fmt: skip
            self._proc, agent_port, monitor_port = start_server_process(*args)
            return agent_port, monitor_port
        from robocup_gym.backends.process import ServerProcess

        self._real = ServerProcess(self.binary, sync=True, real_time=False)
        self._real.start()
        return self._real.agent_port, self._real.monitor_port

    def __exit__(self, *exc: object) -> None:
        if self._proc is not None:
            from robocup_gym.server.bench import stop_server_process

            stop_server_process(self._proc)
        if self._real is not None:
            self._real.stop()

"""Matches between two teams, in-process: ``robocup-gym match A B --games G``.

Each game is :mod:`robocup_gym.soccer.game_v1` with skill actions, ``players`` a side, for
``seconds`` of game time; the teams change sides every game (team A plays left in the first).
With ``scenario="penalty"`` each game is a penalty (:mod:`robocup_gym.soccer.penalty_v1`):
team A's striker against team B's goalkeeper.
The result is counted from team A's side: wins, draws, losses, goals for and against, and a 95 %
interval of the mean goal difference per game (normal approximation, from two games on).
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

__all__ = ["GameResult", "MatchResult", "make_team", "play_match"]

Team = Callable[[Any, list[str], dict[str, np.ndarray]], dict[str, np.ndarray]]
"""A team: ``team(env, agents, obs) → {agent: skill action}``."""


def make_team(spec: str) -> Team:
    """A team by name: ``scripted``, ``standing``, a team run's folder, an exported team policy
    (``.onnx``) or a shipped one (``pretrained:NAME``).

    Raises:
        ValueError: an unknown team (naming the known ones), or a policy that is not a team's.
    """
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
        diffs = np.array([g.goals_for - g.goals_against for g in self.games], float)
        n = len(diffs)
        ci = None
        if n >= 2:
            half = 1.96 * float(diffs.std(ddof=1)) / math.sqrt(n)
            ci = [round(float(diffs.mean()) - half, 3), round(float(diffs.mean()) + half, 3)]
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
            "goal_difference_ci95": ci,
            "diverged_games": int(sum(g.diverged for g in self.games)),
            **({"video": self.video} if self.video is not None else {}),
        }


def play_match(
    team_a: str,
    team_b: str,
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
) -> MatchResult:
    """Play ``games`` games of ``team_a`` against ``team_b``.

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

    Raises:
        ValueError: an unknown team or an impossible set-up.
    """
    if isinstance(games, bool) or not isinstance(games, int) or games < 1:
        raise ValueError(f"games must be a positive integer, got {games!r}")
    if scenario not in ("game", "penalty"):
        raise ValueError(f"scenario must be 'game' or 'penalty', got {scenario!r}")
    penalty = scenario == "penalty"
    players = (1 if penalty else 2) if players is None else players
    seconds = (10.0 if penalty else 120.0) if seconds is None else float(seconds)
    if penalty and players != 1:
        raise ValueError(f"a penalty has 1 player a side, got {players!r}")
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
    cycles = round(seconds / 0.02)
    result = MatchResult(team_a, team_b)
    recorder = None
    if video is not None:
        from robocup_gym.train.evaluate import FrameRecorder, check_renderer, ensure_gl_backend

        ensure_gl_backend()
        check_renderer()
        recorder = FrameRecorder(every=2)  # 25 frames a second of game time
    privileged = any(getattr(t, "privileged", False) for t in (a, b))
    options: dict[str, Any] = {
        "actions": "skills",
        "privileged": privileged,
        "left_types": types,
        "right_types": types,
        "engine": engine,
        "max_cycles": cycles,
        "render_mode": None if video is None else "rgb_array",
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

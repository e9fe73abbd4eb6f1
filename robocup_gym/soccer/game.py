"""One game of RoboCup 3D soccer in-process: a world with two teams of Nao robots (types 0–4,
mixed), the ball and the referee of ``robocup-gym serve``
(:class:`robocup_gym.sim.referee.Referee`), stepped one 20 ms cycle at a time.

:class:`SoccerGame` knows nothing of agents, observations or rewards: it places the teams and the
ball, takes every robot's joint command, steps the world, runs the rules and reports what
happened (goals, the ball's last toucher, a diverged simulation). The PettingZoo environments
(:mod:`robocup_gym.soccer.env`) are built on it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from robocup_gym.sim import SimulationDivergedError, make_world
from robocup_gym.sim.game_host import GameHost
from robocup_gym.sim.physics import BALL_REST_Z
from robocup_gym.sim.referee import Referee, Rules
from robocup_gym.sim.teams import Player
from robocup_gym.sim.vision import VisionConfig
from robocup_gym.types import PLAY_MODES

__all__ = ["SIDES", "CycleReport", "SoccerGame", "Start", "agent_name", "parse_agent_name"]

SIDES = ("left", "right")


def agent_name(side: str, unum: int) -> str:
    """PettingZoo's name of a player: ``left_1``, ``right_3``."""
    return f"{side}_{int(unum)}"


def parse_agent_name(name: str) -> tuple[str, int]:
    """``"left_2"`` → ``("left", 2)``.

    Raises:
        ValueError: not a player's name.
    """
    side, _, unum = str(name).partition("_")
    if side not in SIDES or not unum.isdigit():
        raise ValueError(f"{name!r} is not a player's name (left_N or right_N)")
    return side, int(unum)


@dataclass(frozen=True)
class Start:
    """Where an episode starts: each player's ``(x, y, heading_deg)`` in the world frame (keyed by
    agent name), the ball's position (x, y) and velocity (m/s) and the play mode."""

    players: Mapping[str, tuple[float, float, float]]
    ball: tuple[float, float] = (0.0, 0.0)
    ball_vel: tuple[float, float, float] = (0.0, 0.0, 0.0)
    play_mode: str = "PlayOn"


@dataclass
class CycleReport:
    """What one cycle changed."""

    goal: str | None = None
    """The side that scored in this cycle, else ``None``."""
    play_mode: str = "PlayOn"
    diverged: str | None = None
    """Why the simulation could not go on (the game then has to be reset), else ``None``."""


class SoccerGame:
    """Two teams, the ball and the rules on one world.

    Args:
        left_types, right_types: Nao type (0–4) of each player of the team, uniform numbers
            1, 2, … in this order. Either may be empty.
        engine: ``"ode"`` (SimSpark's physics, the default) or ``"mujoco"``.
        rules: Which rules the referee runs (:class:`~robocup_gym.sim.referee.Rules`): ``True``
            all (goals, kick-offs, ball out and set pieces, half time, …), ``False`` none (the
            play mode stays where it is put), or a mapping that switches single rules.
        vision_noise: ``See`` with rcssserver3d's noise (as on a real server).
        team_names: The two teams' names (seen by the players' vision).
        seed: Seeds vision noise and calibration offsets.
        dead_time_cycles: Cycles between a command and its effect (1, as on rcssserver3d).
    """

    def __init__(
        self,
        left_types: Sequence[int] = (0,),
        right_types: Sequence[int] = (0,),
        *,
        engine: str = "ode",
        rules: bool | Rules | Mapping[str, bool] = True,
        vision_noise: bool = True,
        team_names: tuple[str, str] = ("Left", "Right"),
        seed: int | None = None,
        dead_time_cycles: int = 1,
        self_collisions: bool = False,
        first_touch_plays_on: bool = True,
    ) -> None:
        types = [*map(int, left_types), *map(int, right_types)]
        if not types:
            raise ValueError("a game needs at least one player")
        for t in types:
            if t not in range(5):
                raise ValueError(f"robot type {t} is not a Nao type (0-4)")
        if len(left_types) > 11 or len(right_types) > 11:
            raise ValueError("a team has at most 11 players")
        if team_names[0] == team_names[1]:
            raise ValueError(f"the teams need two different names, got {team_names!r}")
        self.engine = engine
        self.rules = Rules.of(rules)
        self.first_touch_plays_on = bool(first_touch_plays_on)
        self.team_names = tuple(team_names)
        self.players: list[Player] = []
        """Every player, left team first (``index`` = the robot's index in the world)."""
        self.names: list[str] = []
        for side, team in (("left", left_types), ("right", right_types)):
            for k in range(len(team)):
                self.players.append(
                    Player(key=len(self.players), index=len(self.players), side=side, unum=k + 1)
                )
                self.names.append(agent_name(side, k + 1))
        self.robot_types = tuple(types)
        self.world = make_world(
            types,
            engine=engine,
            vision=VisionConfig(noise=bool(vision_noise)),
            seed=seed,
            dead_time_cycles=dead_time_cycles,
        )
        self.world.self_collision_rule = bool(self_collisions)
        self.host = GameHost(self.world)
        self.referee = self._new_referee(seed)
        self._diverged = False

    # ------------------------------------------------------------------ set-up
    def _new_referee(self, seed: int | None) -> Referee:
        ref = Referee(
            self.host,
            rules=self.rules,
            rng=np.random.default_rng(seed),
            type_limits=False,
            first_touch_plays_on=self.first_touch_plays_on,
        )
        for p, t in zip(self.players, self.robot_types, strict=True):
            side, unum = ref.teams.register(self.team_names[SIDES.index(p.side)], p.unum, t)
            self.world.set_team(p.index, side, self.team_names[SIDES.index(side)], unum)
        ref.players = list(self.players)
        return ref

    def index(self, name: str) -> int:
        """The world index of player ``name``.

        Raises:
            KeyError: no such player in this game.
        """
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(
                f"no player {name!r} in this game (players: {', '.join(self.names)})"
            ) from None

    def reset(self, start: Start, seed: int | None = None) -> None:
        """Put every player and the ball where ``start`` says, scores 0, game clock 0, the
        referee's memory cleared; ``seed`` re-seeds vision noise and calibration. A start is
        the same state whatever came before (placing every body forgets the solver's history),
        so a seeded episode repeats exactly."""
        if start.play_mode not in PLAY_MODES:
            raise ValueError(f"unknown play mode {start.play_mode!r}")
        missing = [n for n in self.names if n not in start.players]
        if missing:
            raise ValueError(f"the start places no {', '.join(missing)}")
        w = self.world
        if self.engine == "mujoco" and (seed is not None or self._diverged):
            w.reset(seed=seed)
        elif seed is not None:
            w.reseed(seed)
        self._diverged = False
        for name, p in zip(self.names, self.players, strict=True):
            x, y, heading = start.players[name]
            w.place_robot(
                p.index,
                float(x),
                float(y),
                heading_deg=float(heading),
                joint_angles_deg=np.zeros(len(w.robots[p.index].model.joints)),
            )
        w.place_ball(
            (float(start.ball[0]), float(start.ball[1]), BALL_REST_Z),
            tuple(float(v) for v in start.ball_vel),
        )
        if hasattr(w, "sense_contacts"):
            w.sense_contacts()  # ODE: the first perception shows the feet loaded
        w.set_game(play_mode="BeforeKickOff", game_time=0.0, score_left=0, score_right=0)
        self.referee = self._new_referee(seed)
        self.referee.set_play_mode(start.play_mode)

    # ------------------------------------------------------------------ the cycle
    def step(self, commands: Mapping[int, np.ndarray]) -> CycleReport:
        """One cycle: every robot's joint velocities (rad/s, canonical order; robots not given
        keep their targets), one physics step, the rules.

        A simulation that diverges is reported in :attr:`CycleReport.diverged`; the game must
        then be reset before it goes on."""
        if self._diverged:
            raise RuntimeError("the simulation diverged: reset the game before stepping it")
        w = self.world
        for i, velocities in commands.items():
            w.command(i, velocities)
        before = (w.game.score_left, w.game.score_right)
        try:
            w.step()
            positions = w.body_positions()
            if not np.isfinite(positions).all() or np.abs(positions).max(initial=0.0) > 100.0:
                raise SimulationDivergedError(
                    f"simulation diverged at t = {w.time:.2f} s: a body left the field by 100 m"
                )
        except SimulationDivergedError as exc:
            self._diverged = True
            return CycleReport(play_mode=w.game.play_mode, diverged=str(exc))
        self.referee.update(self.players)
        after = (w.game.score_left, w.game.score_right)
        goal = "left" if after[0] > before[0] else "right" if after[1] > before[1] else None
        return CycleReport(goal=goal, play_mode=w.game.play_mode)

    # ------------------------------------------------------------------ readings
    @property
    def last_touch(self) -> Player | None:
        """The player who touched the ball last (the referee's memory)."""
        return self.referee.last_touch

    def ball_position(self) -> np.ndarray:
        return self.world.ball_position()

    def ball_velocity(self) -> np.ndarray:
        return self.world.ball_velocity()

    def close(self) -> None:
        close = getattr(self.world, "close", None)
        if close is not None:
            close()

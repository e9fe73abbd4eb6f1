"""The rules of the game, once for every world: teams (``init``) and the automatic referee
(wire reference §3.4, reference §9). ``robocup-gym serve`` and the soccer environments
(:mod:`robocup_gym.soccer`) run the same :class:`Referee` over their worlds.

:class:`TeamRegistry` decides sides, uniform numbers, the robot-type composition limits and the
sideline start slots exactly as rcssserver3d's ``GameStateAspect``. :class:`Referee` runs the game
flow after every physics step: BeforeKickOff (ball held at the centre, teams kept in their
halves), kick-off clearing and the first touch, goals and score, the goal pause and the following
kick-off, ball out over a side line (kick-in) or goal line (goal kick / corner kick), set pieces
(ball held at the spot after 1 s, opponents kept 2 m away, first touch → PlayOn, drop ball after
15 s), pass mode, half time (300 s → BeforeKickOff of the second half) and the end of the game
(600 s → GameOver), fallen robots, illegal defence, and the fouls between robots of
:mod:`robocup_gym.sim.fouls` (touching groups, charging, the safe spots of the referee's moves),
and the rules on the restarting kick and on scoring of :mod:`robocup_gym.sim.kick_rules`. The
self-collision rule runs with the world (:mod:`robocup_gym.sim.self_collision`).
``docs/serve.md`` lists what is not implemented (offside, some monitor predicates).

The referee acts on the world through a :class:`~robocup_gym.sim.game_host.GameHost` (the
server's host rebuilds its world as robots come and go; an environment's keeps one).
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np

from robocup_gym.sim.field import (
    CENTRE_CIRCLE_RADIUS,
    FIELD_HALF_LENGTH,
    FIELD_HALF_WIDTH,
    GOAL_HALF_WIDTH,
    GOAL_HEIGHT,
    PENALTY_HALF_WIDTH,
    PENALTY_X,
)
from robocup_gym.sim.fouls import (
    AGENT_RADIUS,
    MAX_PLAYERS_IN_OWN_AREA,
    MOVED_GRACE_CYCLES,
    ContactFouls,
    SafeSpot,
    robot_box,
)
from robocup_gym.sim.game_host import GameHost
from robocup_gym.sim.kick_rules import FREE_KICK_DISTANCE, PASS_MODE_MIN_OPP_DIST, KickRules
from robocup_gym.sim.physics import BALL_RADIUS, CYCLE_S
from robocup_gym.types import PLAY_MODES, reject_unknown_fields

log = logging.getLogger("robocup_gym.referee")

FREE_KICK_MOVE = 2.5
HALF_TIME = 300.0
GOAL_PAUSE = 3.0
KICK_IN_PAUSE = 1.0
DROP_BALL_TIME = 15.0
PASS_MODE_DURATION = 4.0
PASS_MODE_RETRY = 3.0
PASS_MODE_MAX_BALL_SPEED = 0.05
PASS_MODE_MAX_BALL_DIST = 0.5
MAX_PLAYERS = 11
FOUL_TOUCHING, FOUL_ILLEGAL_DEFENCE, FOUL_INCAPABLE, FOUL_CHARGING, FOUL_SELF_COLLISION = (
    1,
    2,
    4,
    6,
    7,
)
"""Foul types as monitors number them (reference §7.3 of the wire reference)."""
MAX_ROBOT_TYPE_COUNT = 7
MIN_ROBOT_TYPES = 3
MAX_SUM_TWO_TYPES = 9

BEAM_MODES = ("BeforeKickOff", "Goal_Left", "Goal_Right")
PAUSED_MODES = ("BeforeKickOff", "GameOver")
"""Play modes in which the game clock stands still."""
FOULS_PAUSED_MODES = ("BeforeKickOff", "Goal_Left", "Goal_Right")
"""Play modes in which the game is paused for the fouls: they are not counted and their counters
start again. rcssserver3d pauses the game in these modes' updates and resumes it in every other
mode's (pass and offside modes keep play-on's), so a game put into play-on by a trainer command
counts fouls at once, and one in a goal's pause does not."""
NOT_STANDING_Z = 0.25
"""A robot whose torso centre is lower than this (m) is not standing (reference §9.5)."""
ON_GROUND_Z = 0.15
"""… and lower than this, on the ground."""
STANDING_AGAIN_S = 0.5
"""Standing this long clears a robot's time not standing."""
INCAPABLE_S = {"ground": (15.0, 30.0), "not_standing": (30.0, 60.0)}
"""How long (s) a field player / the goalkeeper may be on the ground or not standing before it
is taken off the field."""
FOUL_HOLD_S = 0.5
"""A penalised robot is held in the air this long, then put beside the field."""
_SET_PIECES = {
    "KickIn_Left": "left",
    "KickIn_Right": "right",
    "corner_kick_left": "left",
    "corner_kick_right": "right",
    "goal_kick_left": "left",
    "goal_kick_right": "right",
    "free_kick_left": "left",
    "free_kick_right": "right",
    "direct_free_kick_left": "left",
    "direct_free_kick_right": "right",
    "offside_left": "left",
    "offside_right": "right",
}


def _in_own_area(side: str, x: float, y: float) -> bool:
    """Whether (x, y) is in ``side``'s own penalty area (edges included)."""
    sign = -1.0 if side == "left" else 1.0
    return sign * x >= PENALTY_X and abs(x) <= FIELD_HALF_LENGTH and abs(y) <= PENALTY_HALF_WIDTH


def other(side: str) -> str:
    return "right" if side == "left" else "left"


def restart_side(play_mode: str) -> str | None:
    """The team that restarts play in ``play_mode`` (a kick-off or set piece: ``"left"`` or
    ``"right"``; the other team keeps its distance), else ``None``."""
    if play_mode in ("KickOff_Left", "KickOff_Right"):
        return "left" if play_mode == "KickOff_Left" else "right"
    return _SET_PIECES.get(play_mode)


def half_kickoff_side(half: int) -> str:
    """The team whose kick-off starts half ``half`` (1 or 2) when a trainer's ``kickOff`` names
    no side: the left team in the first half, the right team in the second."""
    return "left" if half == 1 else "right"


def next_kickoff_side(play_mode: str, game_time: float) -> str | None:
    """The team that kicks off next, during the pauses in which players beam: after a goal the
    team that conceded it; before a half's kick-off :func:`half_kickoff_side` (what a trainer's
    ``kickOff`` without a side gives); else ``None``."""
    if play_mode in ("Goal_Left", "Goal_Right"):
        return "right" if play_mode == "Goal_Left" else "left"
    if play_mode == "BeforeKickOff":
        return half_kickoff_side(1 if game_time < HALF_TIME else 2)
    return None


class InitError(Exception):
    """An ``init`` that the server rejects (the message says why)."""


@dataclass
class Player:
    """A robot that belongs to a team, as the referee sees it."""

    key: int
    index: int
    side: str
    unum: int


class TeamRegistry:
    """Sides, uniform numbers and robot types of the two teams (wire reference §3.4, reference
    §9.8).

    Args:
        robot_types: The robot types a player may use (rcssserver3d: 0–4).
        type_limits: Apply the league's per-team robot-type rules (at most 7 of one type, 9 of
            the two most used, at least 3 types); ``False`` for training set-ups such as eleven
            robots of one type.
    """

    def __init__(self, robot_types=(0, 1, 2, 3, 4), type_limits: bool = True) -> None:
        self.robot_types = frozenset(int(t) for t in robot_types)
        self.type_limits = bool(type_limits)
        self.names: dict[str, str] = {}
        """side → team name (first distinct name = left, second = right; never reassigned)."""
        self.members: dict[str, dict[int, int]] = {"left": {}, "right": {}}
        """side → {unum: robot type}."""
        self.init_count: dict[str, int] = {"left": 0, "right": 0}

    def side_of(self, name: str) -> str | None:
        for side, n in self.names.items():
            if n == name:
                return side
        return None

    def register(self, team_name: str, unum: int, robot_type: int) -> tuple[str, int]:
        """Join ``team_name`` as ``unum`` (0 = lowest free); returns (side, unum).

        Raises:
            InitError: third team, empty name, number taken or out of 0–11, team full, or the
                robot-type limits (§3.4).
        """
        if not team_name:
            raise InitError("empty team name")
        if robot_type not in self.robot_types:
            allowed = ", ".join(map(str, sorted(self.robot_types)))
            raise InitError(
                f"robot type {robot_type} is not allowed on this server (allowed: {allowed})"
            )
        side = self.side_of(team_name)
        if side is None:
            if len(self.names) >= 2:
                raise InitError(
                    f"team {team_name!r} rejected: the teams are already "
                    f"{self.names['left']!r} and {self.names['right']!r}"
                )
            side = "left" if "left" not in self.names else "right"
            self.names[side] = team_name
        members = self.members[side]
        if len(members) >= MAX_PLAYERS:
            raise InitError(f"team {team_name!r} already has {MAX_PLAYERS} players")
        if unum == 0:
            unum = next(n for n in range(1, MAX_PLAYERS + 1) if n not in members)
        elif not 1 <= unum <= MAX_PLAYERS:
            raise InitError(f"uniform number {unum} is outside 1..{MAX_PLAYERS}")
        elif unum in members:
            raise InitError(f"uniform number {unum} is already taken in team {team_name!r}")
        if self.type_limits:
            self._check_types(team_name, list(members.values()), robot_type)
        members[unum] = robot_type
        return side, unum

    @staticmethod
    def _check_types(team: str, types: list[int], new: int) -> None:
        counts = Counter(types)
        if counts[new] + 1 > MAX_ROBOT_TYPE_COUNT:
            raise InitError(
                f"team {team!r} would have more than {MAX_ROBOT_TYPE_COUNT} robots of type {new}"
            )
        counts[new] += 1
        top_two = sum(sorted(counts.values(), reverse=True)[:2])
        if top_two > MAX_SUM_TWO_TYPES:
            raise InitError(
                f"team {team!r} would have more than {MAX_SUM_TWO_TYPES} robots of its two "
                "most used types"
            )
        counts[new] -= 1
        free = MAX_PLAYERS - len(types)
        missing = max(0, MIN_ROBOT_TYPES - len([t for t, c in counts.items() if c > 0]))
        if free <= missing and counts[new] > 0:
            raise InitError(
                f"team {team!r} must use at least {MIN_ROBOT_TYPES} robot types: type {new} "
                "is already used and the remaining places are needed for other types"
            )

    def release(self, side: str, unum: int) -> None:
        """Free a uniform number (the agent disconnected or was killed)."""
        self.members[side].pop(unum, None)

    def next_slot(self, side: str) -> tuple[float, float, float, float]:
        """The sideline start slot of the next ``init`` of ``side``: (x, y, z, heading°)."""
        n = self.init_count[side]
        self.init_count[side] += 1
        col, row = divmod(n, 17)
        x = -FIELD_HALF_LENGTH + 2 * AGENT_RADIUS + 2 * AGENT_RADIUS * col
        y = FIELD_HALF_WIDTH - 2 * AGENT_RADIUS - 3 * AGENT_RADIUS * row
        if side == "right":
            return (-x, y, AGENT_RADIUS, 180.0)
        return (x, y, AGENT_RADIUS, 0.0)


@dataclass(frozen=True)
class Rules:
    """Which of the referee's rules run: all, as on rcssserver3d, by default. A rule that is
    off leaves its play modes alone (they change only by trainer command or another rule)."""

    before_kickoff: bool = True
    """BeforeKickOff: the ball held on the centre spot, each team kept in its own half."""
    kickoff: bool = True
    """A kick-off: opponents kept out of the centre circle and every player out of the other
    half, the first touch starts play, a drop ball after 15 s."""
    goals: bool = True
    """A ball in a goal scores; the goal pause, then the conceding team's kick-off."""
    ball_out: bool = True
    """A ball over a side line gives a kick-in, over a goal line a corner or a goal kick."""
    set_pieces: bool = True
    """During a kick-in, corner or goal kick: the ball held at its spot, opponents 2 m away,
    the first touch starts play, a drop ball after 15 s."""
    half_time: bool = True
    """300 s: the second half's BeforeKickOff; 600 s: game over."""
    pass_mode: bool = True
    """An agent's ``(pass)`` request is granted when its conditions hold."""
    fallen_robots: bool = True
    """While the game runs, a robot on the ground for 15 s (goalkeeper 30 s) or not standing for
    30 s (60 s) is lifted for 0.5 s and put beside the field (reference §9.5)."""
    illegal_defence: bool = True
    """While the game runs, a team with more than 3 robots (torso centres) in its own penalty
    area has the one that entered last moved out, 0.4 m beyond the area's nearest edge; when the
    goalkeeper (number 1) entered last, the field player farthest from the goal of those already
    inside (reference §9.5)."""
    touching: bool = True
    """While the game runs, a group of more than 2 robots linked by contacts has the one that
    just joined moved 0.4 m away from the group's centre (:mod:`robocup_gym.sim.fouls`)."""
    charging: bool = True
    """While the game runs, a robot that keeps running into an opponent (not toward the ball)
    is lifted for 0.5 s and put beside the field (:mod:`robocup_gym.sim.fouls`)."""

    @property
    def any(self) -> bool:
        return any(getattr(self, f.name) for f in fields(self))

    @classmethod
    def of(cls, value: bool | Rules | Mapping[str, bool]) -> Rules:
        """``True``: every rule; ``False``: none; a mapping: every rule, the named ones set.

        Raises:
            ValueError: an unknown rule (naming the rules) or a value that is not a bool.
        """
        if isinstance(value, Rules):
            return value
        if isinstance(value, bool | np.bool_):
            return cls(**{f.name: bool(value) for f in fields(cls)})
        if isinstance(value, Mapping):
            reject_unknown_fields(cls, value, "rule", "rules")
            for k, v in value.items():
                if not isinstance(v, bool | np.bool_):
                    raise ValueError(f"rule {k!r} must be true or false, got {v!r}")
            return cls(**{k: bool(v) for k, v in value.items()})
        raise ValueError(f"rules must be true, false or a mapping of rule names, got {value!r}")


@dataclass
class _Posture:
    """How long (cycles) a player has not stood, been on the ground, stood again."""

    not_standing: int = 0
    ground: int = 0
    standing: int = 0
    held: int = 0
    """Cycles the penalised robot has been held in the air (0: not penalised)."""
    why: str = ""


class Referee:
    """Game flow on top of the World's play mode, clock and scores.

    Args:
        host: the world's host (the world may be replaced, so it is looked up every time).
        rules: Which rules run (:class:`Rules`, ``True`` for all, ``False`` for none, or a
            mapping of rule names to switch single ones): ``False`` switches the automatic
            referee off ("soccer rules" off in FC Portugal's tools), play modes then change
            only by trainer command.
        rng: for the coin toss of ``(kickOff None)``.
        robot_types, type_limits: see :class:`TeamRegistry`.
        first_touch_plays_on: A kick-off, set piece or pass mode ends at the first touch of
            the ball, as on rcssserver3d. ``False`` keeps ``game_v0``'s behaviour, in which
            only the drop ball after 15 s (or the toucher leaving the game) ended them.
    """

    def __init__(
        self,
        host: GameHost,
        *,
        rules: bool | Rules | Mapping[str, bool] = True,
        rng=None,
        robot_types=(0, 1, 2, 3, 4),
        type_limits: bool = True,
        first_touch_plays_on: bool = True,
    ) -> None:
        self.host = host
        self.first_touch_plays_on = bool(first_touch_plays_on)
        self.rules = Rules.of(rules)
        self.rng = rng if rng is not None else np.random.default_rng()
        self.teams = TeamRegistry(robot_types, type_limits)
        self.half = 1
        self.mode_cycles = 0
        self.kickoffs_this_half = 0
        self.last_touch: Player | None = None
        """The player who touched the ball last (forgotten when that player leaves the game,
        as rcssserver3d no longer finds the agent then)."""
        self.touched_in_mode = False
        self.touch_time = 0.0
        """Game time of the last touch of the ball (s)."""
        self.kicks = KickRules()
        """The rules on the restarting kick and on scoring (:mod:`robocup_gym.sim.kick_rules`)."""
        self._touchers: list[Player] = []
        self.spot: np.ndarray | None = None
        self.last_inside_x = 0.0
        self.last_inside = np.array([0.0, 0.0, BALL_RADIUS])
        """Where the ball last was on the field."""
        self.pass_started: dict[str, float] = {}
        self.players: list[Player] = []
        self.posture: dict[int, _Posture] = {}
        """Each player's standing counters (by :attr:`Player.key`)."""
        self.in_own_area: dict[int, bool] = {}
        """Whether each player's torso was in its own penalty area last cycle (by key)."""
        self.contact_fouls = ContactFouls()
        """Touching groups and the charging clocks (:mod:`robocup_gym.sim.fouls`)."""
        self._area: dict[str, list] = {}
        """This cycle, per side: [robots in the own penalty area, robots moved into it]."""
        self._before: dict[int, bool] = {}
        """This cycle, whether each player (by key) was in its own penalty area the cycle before."""
        self._inside: dict[int, bool] = {}
        """This cycle, whether each player (by key) is in its own penalty area."""
        self._penalised: dict[int, int] = {}
        """This cycle, the players (by key) moved for touching or illegal defence, and why."""
        self.fouls: list[tuple[int, int, str, int]] = []
        """Every foul so far: ``(number from 1, type, side, uniform number)``."""
        self._fouled: set[int] = set()
        """This cycle, the players (by key) with a foul to serve."""

    # ------------------------------------------------------------------ state
    @property
    def play_mode(self) -> str:
        return self.host.world.game.play_mode

    @property
    def game_time(self) -> float:
        return self.host.world.game.game_time

    @property
    def mode_time(self) -> float:
        """Seconds since the current play mode started (counted in cycles)."""
        return self.mode_cycles * CYCLE_S

    def set_play_mode(self, mode: str, *, spot: np.ndarray | None = None) -> None:
        """Switch the play mode and restart its timer (trainer ``playMode`` and the rules)."""
        if mode not in PLAY_MODES:
            raise ValueError(f"unknown play mode {mode!r}")
        if mode != self.play_mode:
            log.info("play mode %s -> %s (t = %.2f)", self.play_mode, mode, self.game_time)
        self.host.world.set_game(play_mode=mode)
        self.mode_cycles = 0
        self.touched_in_mode = False
        if mode in _SET_PIECES:
            self.spot = spot if spot is not None else self.host.ball_state()[0]
        else:
            self.spot = None

    def kick_off(self, team: str = "None") -> None:
        """Trainer ``(kickOff Left|Right|None)``: ball and robots are not moved by this."""
        if team == "None":
            if self.kickoffs_this_half == 0:
                side = half_kickoff_side(self.half)
            else:
                side = "left" if self.rng.random() < 0.5 else "right"
        else:
            side = team.lower()
        self.kickoffs_this_half += 1
        self.set_play_mode("KickOff_Left" if side == "left" else "KickOff_Right")

    # ------------------------------------------------------------------ actions
    def drop_ball(self) -> None:
        """Drop the ball where it is (out of the penalty areas, inside the side lines), clear a
        2 m circle around it, PlayOn."""
        p, _, _ = self.host.ball_state()
        x, y = float(p[0]), float(p[1])
        x = max(-FIELD_HALF_LENGTH, min(FIELD_HALF_LENGTH, x))
        y = max(-FIELD_HALF_WIDTH, min(FIELD_HALF_WIDTH, y))
        if abs(x) > PENALTY_X and abs(y) < PENALTY_HALF_WIDTH:
            x = math.copysign(PENALTY_X, x)
            y = math.copysign(PENALTY_HALF_WIDTH, y if y != 0 else 1.0)
        self.host.set_ball((x, y, BALL_RADIUS), (0.0, 0.0, 0.0))
        self._clear_circle(np.array([x, y]), FREE_KICK_DISTANCE, None)
        self.set_play_mode("PlayOn")

    def repos(self, player: Player) -> None:
        """Trainer ``repos``: move a player to a free spot away from the ball."""
        ball = self.host.ball_state()[0][:2]
        own = -1.0 if player.side == "left" else 1.0
        w = self.host.world
        occupied = [w.torso_position(p.index)[:2] for p in self.players if p is not player]
        for k in range(100):
            x = own * (3.0 + 0.8 * (k % 12))
            y = -FIELD_HALF_WIDTH + 1.0 + 1.2 * (k // 12)
            cand = np.array([x, math.copysign(abs(y), 1.0 if ball[1] < 0 else -1.0)])
            if np.hypot(*(cand - ball)) < 1.0:
                continue
            if all(np.hypot(*(cand - o)) >= 2 * AGENT_RADIUS for o in occupied):
                self.host.teleport(player.index, (cand[0], cand[1], AGENT_RADIUS))
                return

    def request_pass(self, player: Player, touching: set[int]) -> bool:
        """The agent's ``(pass)``: grant pass mode if all conditions of §4.5 hold."""
        if not self.rules.pass_mode or self.play_mode != "PlayOn":
            return False
        side = player.side
        last = self.pass_started.get(side)
        if last is not None and self.game_time - last < PASS_MODE_RETRY:
            return False
        if any(p.index in touching for p in self.players if p.side == side):
            return False
        pos, vel, _ = self.host.ball_state()
        if float(np.linalg.norm(vel)) > PASS_MODE_MAX_BALL_SPEED:
            return False
        w = self.host.world
        if np.hypot(*(w.torso_position(player.index)[:2] - pos[:2])) > PASS_MODE_MAX_BALL_DIST:
            return False
        for p in self.players:
            if p.side != side:
                d = np.hypot(*(w.torso_position(p.index)[:2] - pos[:2]))
                if d < PASS_MODE_MIN_OPP_DIST:
                    return False
        self.pass_started[side] = self.game_time
        self.set_play_mode("pass_left" if side == "left" else "pass_right")
        return True

    # ------------------------------------------------------------------ per cycle
    def update(self, players: list[Player]) -> None:
        """Run the rules after a physics step (the game clock was already advanced)."""
        self.players = players
        self.mode_cycles += 1
        touching = self.host.ball_touchers()
        self._touchers = [p for p in players if p.index in touching] if touching else []
        toucher = min(self._touchers, key=lambda p: p.index, default=None)
        if toucher is not None:
            self.last_touch = toucher
            self.touch_time = self.game_time
            if self.first_touch_plays_on:
                self.touched_in_mode = True
        elif self.last_touch is not None and all(p.key != self.last_touch.key for p in players):
            self.last_touch = None
            self.touched_in_mode = True
        rules = self.rules
        if not rules.any:
            return
        self._fouls(players, touching)
        self._game_flow(players)
        if rules.charging:
            w = self.host.world
            for p in players:
                self.contact_fouls.record_velocity(p.key, w.torso_velocity(p.index))

    def _fouls(self, players: list[Player], touching: set[int]) -> None:
        """The fouls of robots, in rcssserver3d's order: while the game is paused their
        clocks start again (touching groups only grow); while it runs, the standing clocks,
        charging, illegal defence, touching groups, then the penalised robots are lifted and
        put beside the field."""
        rules = self.rules
        fouls = self.contact_fouls
        keys = [p.key for p in players]
        if rules.touching and len(players) > 2:
            keys_of = {p.index: p.key for p in players}
            fouls.link(keys_of, self.host.world.robot_contacts())
        if self.play_mode in FOULS_PAUSED_MODES:
            self.posture.clear()
            self.in_own_area.clear()
            fouls.pause()
            return
        w = self.host.world
        positions = {p.key: w.torso_position(p.index) for p in players}
        self._count_posture(players, positions)
        self._fouled = {p.key for p in players if self.posture[p.key].held}
        self._penalised = {}
        self._area_census(players, positions)
        if rules.charging:
            by_index = {p.index: p.key for p in players}
            fouls.tick(keys, {by_index[i] for i in touching if i in by_index})
            self._charging(players, positions)
        self._self_collision_fouls(players)
        if rules.illegal_defence:
            for side in ("left", "right"):
                self._illegal_defence([p for p in players if p.side == side], positions)
        if rules.touching and len(players) > 2:
            self._touching(players, positions)
        self._take_off_fallen(players, positions)
        if rules.touching and len(players) > 2:
            fouls.restart_groups(keys)

    def _game_flow(self, players: list[Player]) -> None:
        """The play modes: half time, goals, ball out, kick-offs, set pieces, pass mode."""
        rules = self.rules
        pm = self.play_mode
        t = self.game_time
        if rules.half_time and pm != "GameOver" and pm != "BeforeKickOff":
            if self.half == 1 and t >= HALF_TIME:
                self.half = 2
                self.kickoffs_this_half = 0
                self.host.set_ball((0.0, 0.0, BALL_RADIUS), (0.0, 0.0, 0.0))
                self.set_play_mode("BeforeKickOff")
                return
            if self.half == 2 and t >= 2 * HALF_TIME:
                self.set_play_mode("GameOver")
                return
        pos = self.host.ball_position()
        x, y = pos[0].item(), pos[1].item()
        if abs(x) < FIELD_HALF_LENGTH and abs(y) < FIELD_HALF_WIDTH:
            self.last_inside_x = x
            self.last_inside = pos.copy()
        self.kicks.ball_touched_by({p.side for p in self._touchers}, pos)
        if pm == "BeforeKickOff":
            if players and rules.before_kickoff:
                self._hold_ball((0.0, 0.0))
                self._keep_in_halves()
        elif pm in ("KickOff_Left", "KickOff_Right"):
            if not rules.kickoff:
                return
            kicker = "left" if pm == "KickOff_Left" else "right"
            self.kicks.kick_off()
            self._kickoff_clear(kicker)
            if self.touched_in_mode:
                if len(players) > 2 and self.last_touch is not None:
                    self.kicks.taken(self.last_touch, self.touch_time, True, kick_off=True)
                self.set_play_mode("PlayOn")
            elif self.mode_time >= DROP_BALL_TIME:
                self.drop_ball()
        elif pm == "PlayOn":
            self._play_on(pos)
        elif pm in ("Goal_Left", "Goal_Right"):
            if not rules.goals:
                return
            conceding = next_kickoff_side(pm, t)
            self._kickoff_clear(conceding)
            if self.mode_time >= GOAL_PAUSE:
                self.host.set_ball((0.0, 0.0, BALL_RADIUS), (0.0, 0.0, 0.0))
                self.kickoffs_this_half += 1
                self.set_play_mode("KickOff_Left" if conceding == "left" else "KickOff_Right")
        elif pm in ("pass_left", "pass_right"):
            if not rules.pass_mode:
                return
            side = "left" if pm == "pass_left" else "right"
            self.kicks.in_pass_mode(side, self.game_time, pos)
            if self.touched_in_mode or self.mode_time >= PASS_MODE_DURATION:
                self.set_play_mode("PlayOn")
                self._play_on(pos)
            else:
                self._play_on(pos)
                if self.play_mode == pm:
                    self._clear_circle(pos[:2], PASS_MODE_MIN_OPP_DIST, other(side), push=0.1)
        elif pm in _SET_PIECES and rules.set_pieces:
            self._set_piece(pm, _SET_PIECES[pm], pos)

    def _play_on(self, pos: np.ndarray) -> None:
        """Play on's checks: the window after pass mode, the taker's second touch, goal, out."""
        kicks = self.kicks
        kicks.after_pass_mode(self._touchers, self.game_time, pos)
        if self.rules.set_pieces and kicks.second_touch(self.last_touch, self.touch_time):
            side = other(self.last_touch.side)
            log.info(
                "%s #%d touched the ball twice: free kick",
                self.last_touch.side,
                self.last_touch.unum,
            )
            self.set_play_mode(f"free_kick_{side}", spot=self._free_kick_spot(self.last_inside))
            return
        self._check_goal_and_out(pos)

    def _free_kick_spot(self, pos: np.ndarray) -> np.ndarray:
        """A free kick's spot: where the ball was, out of a penalty area (to its front
        corner on the ball's side)."""
        x, y = float(pos[0]), float(pos[1])
        if abs(x) >= PENALTY_X and abs(y) <= PENALTY_HALF_WIDTH:
            x = math.copysign(PENALTY_X, x)
            y = -PENALTY_HALF_WIDTH if y < 0 else PENALTY_HALF_WIDTH
        return np.array([x, y, BALL_RADIUS])

    def _check_goal_and_out(self, pos: np.ndarray) -> None:
        x, y, z = (float(v) for v in pos)
        if (
            self.rules.goals
            and abs(x) >= FIELD_HALF_LENGTH + BALL_RADIUS
            and abs(y) < GOAL_HALF_WIDTH
            and z < GOAL_HEIGHT
        ):
            scored_on = "right" if x > 0 else "left"
            verdict, team = self.kicks.goal(
                scored_on, self.last_touch, self.touch_time, self.game_time, len(self.players) > 2
            )
            if verdict == "goal_kick":
                log.info("no goal: goal kick for the %s team", team)
                self._goal_kick(team)
                return
            if verdict == "corner_kick":
                log.info("no goal: corner kick for the %s team", team)
                self._corner_kick(team, y)
                return
            scorer = "left" if x > 0 else "right"
            g = self.host.world.game
            if scorer == "left":
                self.host.world.set_game(score_left=g.score_left + 1)
            else:
                self.host.world.set_game(score_right=g.score_right + 1)
            log.info("goal for the %s team: %d:%d", scorer, g.score_left, g.score_right)
            self.set_play_mode("Goal_Left" if scorer == "left" else "Goal_Right")
            return
        if self.last_touch is None or not self.rules.ball_out:
            # rcssserver3d awards nothing for a ball off the field that no player touched (a
            # trainer put it there): it lies where it is until it is moved or played
            return
        last = self.last_touch.side
        if abs(y) >= FIELD_HALF_WIDTH + BALL_RADIUS + 0.001:
            side = other(last)
            spot_x = max(-FIELD_HALF_LENGTH, min(FIELD_HALF_LENGTH, self.last_inside_x))
            spot = np.array([spot_x, math.copysign(FIELD_HALF_WIDTH - BALL_RADIUS, y), BALL_RADIUS])
            self.set_play_mode("KickIn_Left" if side == "left" else "KickIn_Right", spot=spot)
        elif abs(x) >= FIELD_HALF_LENGTH + BALL_RADIUS + 0.001:
            defending = "right" if x > 0 else "left"
            if last == defending:
                self._corner_kick(other(defending), y)
            else:
                self._goal_kick(defending)

    def _goal_kick(self, team: str) -> None:
        """A goal kick for ``team``, the ball at (∓14, 0) in front of its goal."""
        sx = -1.0 if team == "left" else 1.0
        self.set_play_mode(f"goal_kick_{team}", spot=np.array([sx * 14.0, 0.0, BALL_RADIUS]))

    def _corner_kick(self, team: str, y: float) -> None:
        """A corner kick for ``team`` at the other goal line, on the side of ``y``."""
        sx = 1.0 if team == "left" else -1.0
        spot = np.array(
            [sx * (FIELD_HALF_LENGTH - BALL_RADIUS), math.copysign(5.483, y), BALL_RADIUS]
        )
        self.set_play_mode(f"corner_kick_{team}", spot=spot)

    def _set_piece(self, pm: str, side: str, pos: np.ndarray) -> None:
        if self.mode_time < KICK_IN_PAUSE:
            self.touched_in_mode = False
            return
        self.kicks.restart()
        spot = self.spot if self.spot is not None else pos
        goal_kick = pm.startswith("goal_kick")
        indirect = pm.startswith(("KickIn", "free_kick", "offside"))
        if not self.touched_in_mode:
            if self.mode_time >= KICK_IN_PAUSE + DROP_BALL_TIME:
                self.host.set_ball((spot[0], spot[1], BALL_RADIUS), (0.0, 0.0, 0.0))
                self.drop_ball()
                return
            self._hold_ball(spot[:2])
            self._clear_circle(spot[:2], FREE_KICK_DISTANCE, other(side))
            return
        if goal_kick:
            in_area = abs(pos[0]) > PENALTY_X and abs(pos[1]) < PENALTY_HALF_WIDTH
            if not in_area:
                self._taken(indirect=False)
                self.set_play_mode("PlayOn")
            return
        if self.mode_time >= KICK_IN_PAUSE + 0.03:
            self._taken(indirect)
            self.set_play_mode("PlayOn")

    def _taken(self, indirect: bool) -> None:
        if self.last_touch is not None:
            self.kicks.taken(self.last_touch, self.touch_time, indirect)

    # ------------------------------------------------------------------ moving things
    def _hold_ball(self, xy: np.ndarray | tuple[float, float]) -> None:
        (px, py, _), (vx, vy, vz) = self.host.ball_pos_vel()
        # a resting ball jitters by micrometres on its contact: only re-place a ball that moved
        if (
            abs(px - xy[0]) > 1e-3
            or abs(py - xy[1]) > 1e-3
            or abs(vx) > 1e-2
            or abs(vy) > 1e-2
            or abs(vz) > 1e-2
        ):
            self.host.set_ball((float(xy[0]), float(xy[1]), BALL_RADIUS), (0.0, 0.0, 0.0))

    def _body_x_extent(self, index: int) -> tuple[float, float]:
        w = self.host.world
        xs = w.body_frames(index)[0][:, 0]
        return float(xs.min()), float(xs.max())

    def _keep_in_halves(self) -> None:
        for p in self.players:
            lo, hi = self._body_x_extent(p.index)
            if p.side == "left" and hi > 0:
                self._move_x(p, -FREE_KICK_MOVE)
            elif p.side == "right" and lo < 0:
                self._move_x(p, FREE_KICK_MOVE)

    def _kickoff_clear(self, kicker: str) -> None:
        w = self.host.world
        for p in self.players:
            xy = w.body_frames(p.index)[0][:, :2]
            lo, hi = float(xy[:, 0].min()), float(xy[:, 0].max())
            own = -1.0 if p.side == "left" else 1.0
            into_other = hi > 0 if p.side == "left" else lo < 0
            if p.side != kicker:
                in_circle = bool(np.any(np.hypot(xy[:, 0], xy[:, 1]) < CENTRE_CIRCLE_RADIUS))
                if into_other or in_circle:
                    self._move_x(p, own * FREE_KICK_MOVE)
            elif into_other:
                inside = bool(np.all(np.hypot(xy[:, 0], xy[:, 1]) < CENTRE_CIRCLE_RADIUS))
                if not inside:
                    self._move_x(p, own * FREE_KICK_MOVE)

    def _count_posture(self, players: list[Player], positions: dict[int, np.ndarray]) -> None:
        """Count how long each player (not being penalised) has not stood."""
        for p in players:
            s = self.posture.setdefault(p.key, _Posture())
            if s.held:
                continue
            pos = positions[p.key]
            z, in_field = float(pos[2]), abs(float(pos[1])) < FIELD_HALF_WIDTH + 0.1
            if z < NOT_STANDING_Z and in_field:
                s.not_standing += 1
                s.standing = 0
            if z < ON_GROUND_Z and in_field:
                s.ground += 1
            if z >= NOT_STANDING_Z:
                s.standing += 1
                s.ground = 0
            if s.standing > STANDING_AGAIN_S / CYCLE_S:
                s.not_standing = 0

    def _take_off_fallen(self, players: list[Player], positions: dict[int, np.ndarray]) -> None:
        """Lift a penalised player (charging, or down too long when the rule runs) for
        :data:`FOUL_HOLD_S`, then put it beside the field, on the far side from the ball."""
        cycles = {k: (a / CYCLE_S, b / CYCLE_S) for k, (a, b) in INCAPABLE_S.items()}
        for p in players:
            s = self.posture[p.key]
            if not s.held and self.rules.fallen_robots:
                keeper = int(p.unum == 1)
                if s.ground > cycles["ground"][keeper]:
                    s.held, s.why = 1, "on the ground too long"
                elif s.not_standing > cycles["not_standing"][keeper]:
                    s.held, s.why = 1, "not standing too long"
        due = [p for p in players if p.key in self._penalised or self.posture[p.key].held]
        # the server goes through every player in random order: the due ones' order is the same
        for p in self._clearing_order(due) if due else ():
            kind = self._penalised.get(p.key)
            if kind is not None:  # moved already: recorded only
                self._foul(kind, p)
                continue
            s = self.posture[p.key]
            if not s.held:
                continue
            self._foul(FOUL_CHARGING if s.why == "charging" else FOUL_INCAPABLE, p)
            pos = positions[p.key]
            if s.held <= FOUL_HOLD_S / CYCLE_S:  # held, 1 cm higher every cycle
                s.held += 1
                self._teleport(p, (pos[0], pos[1], 1.0 + s.held * 0.01))
                continue
            ball_y = float(self.host.ball_position()[1])
            x = (-0.6 if p.side == "left" else 0.6) * (7 - p.unum)
            y = (FIELD_HALF_WIDTH + 0.5) * (1.0 if ball_y < 0 else -1.0)
            self._safe_move(p, np.array([x, y, AGENT_RADIUS]), pos)
            log.info("%s #%d taken off the field (%s)", p.side, p.unum, s.why)
            self.posture[p.key] = _Posture()
            self.contact_fouls.forget(p.key)

    def _self_collision_fouls(self, players: list[Player]) -> None:
        """Record the world's self-collisions of this cycle that froze a joint anew (the rule
        itself runs with the world), the left team's first."""
        w = self.host.world
        if not getattr(w, "self_collision_rule", False):
            return
        state = w.self_collisions
        if not state.fouls:
            return
        by_index = {p.index: p for p in players}
        found = [by_index[i] for i in state.fouls if i in by_index]
        for p in sorted(found, key=lambda q: q.side != "left"):  # stable: each side in order
            self._foul(FOUL_SELF_COLLISION, p)

    def _clearing_order(self, players: list[Player]) -> list[Player]:
        """The order in which rcssserver3d's referee penalises: the teams in random order, each
        team's players shuffled."""
        sides = ("left", "right") if self.rng.random() < 0.5 else ("right", "left")
        out = []
        for side in sides:
            team = [p for p in players if p.side == side]
            out += [team[int(k)] for k in self.rng.permutation(len(team))]
        return out

    def _foul(self, kind: int, p: Player) -> None:
        """Record a foul (reported to monitors as ``(foul index type team unum)``)."""
        self.fouls.append((len(self.fouls) + 1, kind, p.side, p.unum))

    def _charging(self, players: list[Player], positions: dict[int, np.ndarray]) -> None:
        """Opponents in contact: one that charged is penalised (lifted, then put beside the
        field, as one that stayed down too long)."""
        key_of = {p.index: p for p in players}
        opponents: dict[int, list] = {}
        for (i, j), (point, _n) in self.host.world.robot_contacts().items():
            a, b = key_of.get(i), key_of.get(j)
            if a is None or b is None or a.side == b.side:
                continue
            left, right = (a, b) if a.side == "left" else (b, a)
            opponents.setdefault(left.key, []).append((right.key, point))
        if not opponents:
            return
        exempt = {
            p.key
            for p in players
            if self.posture[p.key].not_standing
            or self.contact_fouls.since_moved.get(p.key, MOVED_GRACE_CYCLES) < MOVED_GRACE_CYCLES
            or p.key in self._fouled
        }
        keeper = {}
        for p in players:
            if p.unum == 1:
                x, y = (float(v) for v in positions[p.key][:2])
                beyond = x <= -PENALTY_X if p.side == "left" else x >= PENALTY_X
                keeper[p.key] = beyond and abs(y) <= PENALTY_HALF_WIDTH
        fouls = self.contact_fouls.charging(
            [p.key for p in players if p.side == "left"],
            opponents,
            positions,
            self.host.ball_position(),
            exempt,
            keeper,
        )
        for p in players:
            if p.key in fouls:
                s = self.posture[p.key]
                s.held, s.why = 1, "charging"
                self._fouled.add(p.key)
                log.info("%s #%d charged", p.side, p.unum)

    def _touching(self, players: list[Player], positions: dict[int, np.ndarray]) -> None:
        """Touching groups too large: the robot that joined last is moved 0.4 m away from the
        group's centre (to the nearest free spot)."""
        by_key = {p.key: p for p in players}
        side_of = {p.key: p.side for p in players}
        unum_of = {p.key: p.unum for p in players}
        sides = ("left", "right") if self.rng.random() < 0.5 else ("right", "left")
        for side in sides:
            team = [p.key for p in players if p.side == side]
            moves = self.contact_fouls.touching(
                side, team, side_of, unum_of, positions, self._fouled, self.rng
            )
            for key, centre in moves:
                p = by_key[key]
                at = positions[key]
                away = at[:2] - centre
                n = float(np.hypot(*away))
                if n == 0.0:
                    continue
                target = np.array([*(at[:2] + away / n * AGENT_RADIUS), float(at[2])])
                self._safe_move(p, target, at)
                self._penalised[key] = FOUL_TOUCHING
                log.info("%s #%d moved out of a touching group", p.side, p.unum)

    def _area_census(self, players: list[Player], positions: dict[int, np.ndarray]) -> None:
        """Which players (not being penalised) are in their own penalty area this cycle, and
        how many per team; last cycle's answer kept in :attr:`in_own_area` until the rule
        reads it."""
        self._before = {p.key: self.in_own_area.get(p.key, False) for p in players}
        self._area = {"left": [0, 0], "right": [0, 0]}
        self._inside = {}
        for p in players:
            if p.key in self._fouled:
                self._inside[p.key] = False
                continue
            v = positions[p.key]
            inside = _in_own_area(p.side, float(v[0]), float(v[1]))
            self._inside[p.key] = inside
            self._area[p.side][0] += inside
        self.in_own_area.update(self._inside)

    def _illegal_defence(self, team: list[Player], positions: dict[int, np.ndarray]) -> None:
        """More than :data:`MAX_PLAYERS_IN_OWN_AREA` of ``team`` (one side's players) in their
        own penalty area: move out the one that just entered (in random order, until few enough
        are left), or, when the goalkeeper just entered, the one ranked
        ``MAX_PLAYERS_IN_OWN_AREA + 1`` by distance to the own goal of those already inside."""
        if not team:
            return
        sign = -1.0 if team[0].side == "left" else 1.0
        present = [p for p in team if p.key not in self._fouled]
        pos = {p.key: positions[p.key] for p in present}
        inside = {p.key: self._inside[p.key] for p in present}
        before = {p.key: self._before[p.key] for p in present}
        count = sum(inside.values())
        if count <= MAX_PLAYERS_IN_OWN_AREA:
            return
        goal = np.array([sign * FIELD_HALF_LENGTH, 0.0])
        far = 1000.0
        dist = {}
        for p in present:
            if not inside[p.key]:
                dist[p.unum] = far
            elif p.unum == 1:
                dist[p.unum] = 0.0
            else:
                dist[p.unum] = float(np.hypot(*(pos[p.key][:2] - goal))) if before[p.key] else far
        # rcssserver3d's ranking: 1 + those nearer, a tie going to the higher number
        rank = {
            u: 1 + sum(d2 < d or (d2 == d and u2 > u) for u2, d2 in dist.items() if u2 != u)
            for u, d in dist.items()
        }
        keeper = next((p for p in present if p.unum == 1), None)
        keeper_entered = keeper is not None and inside[keeper.key] and not before[keeper.key]
        for k in self.rng.permutation(len(present)):
            p = present[int(k)]
            if count <= MAX_PLAYERS_IN_OWN_AREA:
                break
            if p.unum == 1 or not inside[p.key]:
                continue
            if not before[p.key] or (
                keeper_entered and rank[p.unum] == MAX_PLAYERS_IN_OWN_AREA + 1
            ):
                count -= 1
                self._area[p.side][0] -= 1
                self._fouled.add(p.key)
                self._out_of_area(p, pos[p.key], sign)
                self._penalised[p.key] = FOUL_ILLEGAL_DEFENCE
                log.info("%s #%d moved out of its penalty area (illegal defence)", p.side, p.unum)

    def _out_of_area(self, p: Player, pos: np.ndarray, sign: float) -> None:
        """Move ``p`` (torso at ``pos``) 0.4 m beyond its penalty area's nearest edge."""
        x, y = float(pos[0]), float(pos[1])
        xs = (sign * FIELD_HALF_LENGTH, sign * PENALTY_X)
        lo_x, hi_x = min(xs), max(xs)
        to_x = lo_x - AGENT_RADIUS if abs(lo_x - x) < abs(hi_x - x) else hi_x + AGENT_RADIUS
        lo_y, hi_y = -PENALTY_HALF_WIDTH, PENALTY_HALF_WIDTH
        to_y = lo_y - AGENT_RADIUS if abs(lo_y - y) < abs(hi_y - y) else hi_y + AGENT_RADIUS
        if abs(to_y - y) < abs(to_x - x):
            y = to_y
        else:
            x = to_x
        if abs(x) > FIELD_HALF_LENGTH and abs(y) < GOAL_HALF_WIDTH + AGENT_RADIUS:
            y = (GOAL_HALF_WIDTH + AGENT_RADIUS + 0.001) * (-1.0 if y < 0 else 1.0)
        self._safe_move(p, np.array([x, y, float(pos[2])]), pos)

    def _safe_move(self, p: Player, target: np.ndarray, at: np.ndarray) -> None:
        """Move ``p`` (torso at ``at``) to ``target`` or the nearest free spot
        (:class:`~robocup_gym.sim.fouls.SafeSpot`), as the server's safe moves do."""
        w = self.host.world
        sign = -1.0 if p.side == "left" else 1.0
        xs = (sign * FIELD_HALF_LENGTH, sign * PENALTY_X)
        spot = SafeSpot(
            side=p.side,
            area=(min(xs), max(xs), -PENALTY_HALF_WIDTH, PENALTY_HALF_WIDTH),
            crowded=sum(self._area.get(p.side, (0, 0))) >= MAX_PLAYERS_IN_OWN_AREA,
            inside=self._inside.get(p.key, False),
            boxes=[robot_box(w, q.index) for q in self.players if q.key != p.key],
            ball=self.host.ball_position()[:2],
        )
        new = spot.find(target, at[:2])
        x, y = float(new[0]), float(new[1])
        in_area = _in_own_area(p.side, x, y)
        if p.side in self._area:
            if not spot.inside and in_area:
                self._area[p.side][1] += 1
            elif spot.inside and not in_area:
                self._area[p.side][1] -= 1
        self._teleport(p, (x, y, float(new[2])))

    def _teleport(self, p: Player, pos) -> None:
        """A referee's move of ``p`` (it counts for the charging rule's grace)."""
        self.host.teleport(p.index, pos)
        self.contact_fouls.moved(p.key)

    def _move_x(self, p: Player, x: float) -> None:
        t = self.host.world.torso_position(p.index)
        self._teleport(p, (x, t[1], t[2]))

    def _clear_circle(
        self, centre: np.ndarray, radius: float, side: str | None, push: float | None = None
    ) -> None:
        """Move robots (of ``side``, or all) whose torso is within ``radius`` of ``centre``
        away from it: to ``radius + push`` (default: to 2.5 m)."""
        w = self.host.world
        target = FREE_KICK_MOVE if push is None else radius + push
        for p in self.players:
            if side is not None and p.side != side:
                continue
            t = w.torso_position(p.index)
            d = t[:2] - centre[:2]
            dist = float(np.hypot(*d))
            if dist >= radius:
                continue
            if dist < 1e-6:
                d = np.array([-1.0 if p.side == "left" else 1.0, 0.0])
                dist = 1.0
            new = centre[:2] + d / dist * target
            new[0] = max(-FIELD_HALF_LENGTH, min(FIELD_HALF_LENGTH, new[0]))
            new[1] = max(-FIELD_HALF_WIDTH, min(FIELD_HALF_WIDTH, new[1]))
            self._teleport(p, (new[0], new[1], t[2]))

"""The rules of the game, once for every world: teams (``init``) and the automatic referee
(wire reference §3.4, reference §9). ``robocup-gym serve`` and the soccer environments
(:mod:`robocup_gym.soccer`) run the same :class:`Referee` over their worlds.

The teams (sides, uniform numbers, the robot-type limits, the sideline slots) are
:class:`~robocup_gym.sim.teams.TeamRegistry`, as rcssserver3d's ``GameStateAspect``.
:class:`Referee` runs the game flow after every physics step: BeforeKickOff (ball held at the
centre, teams kept in their halves), kick-off clearing and the first touch, goals and score, the
goal pause and the following kick-off, ball out over a side line (kick-in) or goal line (goal kick
/ corner kick), set pieces (ball held at the spot after 1 s, opponents kept 2 m away, first touch
→ PlayOn, drop ball after 15 s), pass mode, half time (300 s → BeforeKickOff of the second half)
and the end of the game (600 s → GameOver); the fouls of robots (fallen robots, illegal defence,
touching groups, charging: :mod:`robocup_gym.sim.referee_fouls`, over the contact geometry of
:mod:`robocup_gym.sim.fouls`); and the rules on the restarting kick and on scoring of
:mod:`robocup_gym.sim.kick_rules`. The self-collision rule runs with the world
(:mod:`robocup_gym.sim.self_collision`). ``docs/serve.md`` lists what is not implemented
(offside, some monitor predicates).

The referee acts on the world through a :class:`~robocup_gym.sim.game_host.GameHost` (the
server's host rebuilds its world as robots come and go; an environment's keeps one).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np

from robocup_gym.robot.types import TYPE_NUMBERS
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
    ContactFouls,
)
from robocup_gym.sim.game_host import GameHost
from robocup_gym.sim.kick_rules import FREE_KICK_DISTANCE, PASS_MODE_MIN_OPP_DIST, KickRules
from robocup_gym.sim.physics import BALL_RADIUS, CYCLE_S
from robocup_gym.sim.referee_fouls import (
    RobotFouls,
    _Posture,
)
from robocup_gym.sim.teams import (
    Player,
    TeamRegistry,
)
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
BEAM_MODES = ("BeforeKickOff", "Goal_Left", "Goal_Right")
PAUSED_MODES = ("BeforeKickOff", "GameOver")
"""Play modes in which the game clock stands still."""
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


class Referee(RobotFouls):
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
        robot_types=TYPE_NUMBERS,
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

    def _parts_extents(self) -> tuple[np.ndarray, ...]:
        """Per robot of the world (by index), from all its parts at once: the smallest and the
        largest x (m), whether any part and whether every part is inside the centre circle. A
        move of one robot changes only that robot's entries."""
        w = self.host.world
        xy = w.every_body_frame()[0][:, :2]
        starts = np.cumsum([0] + [len(r.model.bodies) for r in w.robots[:-1]])
        in_circle = np.hypot(xy[:, 0], xy[:, 1]) < CENTRE_CIRCLE_RADIUS
        return (
            np.minimum.reduceat(xy[:, 0], starts),
            np.maximum.reduceat(xy[:, 0], starts),
            np.logical_or.reduceat(in_circle, starts),
            np.logical_and.reduceat(in_circle, starts),
        )

    def _keep_in_halves(self) -> None:
        if not self.players:
            return
        lo, hi, _, _ = self._parts_extents()
        for p in self.players:
            if p.side == "left" and hi[p.index] > 0:
                self._move_x(p, -FREE_KICK_MOVE)
            elif p.side == "right" and lo[p.index] < 0:
                self._move_x(p, FREE_KICK_MOVE)

    def _kickoff_clear(self, kicker: str) -> None:
        if not self.players:
            return
        lo, hi, any_in, all_in = self._parts_extents()
        for p in self.players:
            i = p.index
            own = -1.0 if p.side == "left" else 1.0
            into_other = hi[i] > 0 if p.side == "left" else lo[i] < 0
            if p.side != kicker:
                if into_other or any_in[i]:
                    self._move_x(p, own * FREE_KICK_MOVE)
            elif into_other and not all_in[i]:
                self._move_x(p, own * FREE_KICK_MOVE)

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

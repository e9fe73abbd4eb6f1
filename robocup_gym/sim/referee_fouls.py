"""The referee's judgement of robots, once per cycle in rcssserver3d's order: fallen robots
(on the ground or not standing too long: lifted, then put beside the field), charging, illegal
defence (too many robots in the own penalty area), touching groups, and the self-collisions the
world's rule reports; each foul is recorded as monitors number it. The geometry of contacts and
of the referee's safe moves is :mod:`robocup_gym.sim.fouls`.

:class:`RobotFouls` is a part of :class:`~robocup_gym.sim.referee.Referee`.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from robocup_gym.sim.field import (
    FIELD_HALF_LENGTH,
    FIELD_HALF_WIDTH,
    GOAL_HALF_WIDTH,
    PENALTY_HALF_WIDTH,
    PENALTY_X,
)
from robocup_gym.sim.fouls import (
    AGENT_RADIUS,
    MAX_PLAYERS_IN_OWN_AREA,
    MOVED_GRACE_CYCLES,
    SafeSpot,
    robot_box,
)
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.sim.teams import Player

log = logging.getLogger("robocup_gym.referee")

FOUL_TOUCHING, FOUL_ILLEGAL_DEFENCE, FOUL_INCAPABLE, FOUL_CHARGING, FOUL_SELF_COLLISION = (
    1,
    2,
    4,
    6,
    7,
)
"""Foul types as monitors number them (reference §7.3 of the wire reference)."""
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


def _in_own_area(side: str, x: float, y: float) -> bool:
    """Whether (x, y) is in ``side``'s own penalty area (edges included)."""
    sign = -1.0 if side == "left" else 1.0
    return sign * x >= PENALTY_X and abs(x) <= FIELD_HALF_LENGTH and abs(y) <= PENALTY_HALF_WIDTH


@dataclass
class _Posture:
    """How long (cycles) a player has not stood, been on the ground, stood again."""

    not_standing: int = 0
    ground: int = 0
    standing: int = 0
    held: int = 0
    """Cycles the penalised robot has been held in the air (0: not penalised)."""
    why: str = ""


class RobotFouls:
    """The fouls of robots, a part of :class:`~robocup_gym.sim.referee.Referee` (its players,
    host, rules and random numbers are the referee's)."""

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

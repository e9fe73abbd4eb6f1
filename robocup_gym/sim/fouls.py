"""rcssserver3d's fouls between robots (reference §9.5): touching groups and charging, and the
"safe" spot the referee moves a robot to.

**Touching groups.** Every contact between two robots' parts, except two feet (or toes), links
the two robots; the robots linked this cycle, directly or through others, form a group. While the
game runs, a group of more than :data:`MAX_TOUCH_GROUP` robots is too large: the robot that has
just joined it (one that was alone the cycle before) is moved :data:`AGENT_RADIUS` away from the
group's centre, or, when its team has fewer robots in the group than the other, the other team's
robot met last in a random order of the group; a goalkeeper that joins has a team-mate moved
instead. The groups start again every cycle the game runs; while it is paused they only grow.

**Charging.** Two opponents in contact, each with its torso's velocity averaged over the last
:data:`VELOCITY_SAMPLES` cycles: a robot charges when it moves at :data:`CHARGING_MIN_SPEED` or
faster, at least :data:`CHARGING_MIN_COLLISION_SPEED` of it toward the contact, and (within
:data:`CHARGING_MAX_BALL_DIST` of the ball) not toward the ball more than toward the opponent;
not both, not at the ball, and not within :data:`CHARGING_IMMUNITY_S` of its own touch of the
ball. One that has kept charging for :data:`CHARGING_COLLISION_MIN_S` commits the foul; it is
then lifted and put beside the field as a robot that stayed down too long. Robots that are not
standing, or that the referee moved in the last second, and a goalkeeper in its own penalty area
are exempt.

**Safe spots.** A robot the referee moves (touching, illegal defence) goes to the spot asked
for, or, where that spot is taken (within :data:`AGENT_RADIUS` of another robot's bounding box,
too near the ball, in a goal, or in a full own penalty area), to the nearest free spot the
server's search finds in steps of :data:`AGENT_RADIUS`.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from robocup_gym.robot.nao import mesh_boxes
from robocup_gym.sim.field import FIELD_HALF_LENGTH, GOAL_HALF_WIDTH
from robocup_gym.sim.kick_rules import PASS_MODE_MIN_OPP_DIST
from robocup_gym.sim.physics import CYCLE_S

__all__ = [
    "AGENT_RADIUS",
    "CHARGING_MIN_SPEED",
    "MAX_TOUCH_GROUP",
    "MOVED_GRACE_CYCLES",
    "ContactFouls",
    "SafeSpot",
    "robot_box",
]

AGENT_RADIUS = 0.4
"""``AgentRadius``: how far a touching foul moves a robot, and the size of a free spot, m."""
MAX_TOUCH_GROUP = 2
"""``MaxTouchGroupSize``: the most robots a touching group may hold."""
MAX_SAFE_ATTEMPTS = 100
"""``MaxNumSafeRepositionAttempts``."""
MAX_PLAYERS_IN_OWN_AREA = 3
VELOCITY_SAMPLES = 3
"""``AVERAGE_VELOCITY_MEASUREMENTS``: cycles over which a torso's velocity is averaged."""
CHARGING_MIN_SPEED = 0.4
"""``ChargingMinSpeed``, m/s."""
CHARGING_MIN_BALL_SPEED_ANGLE = 30.0
"""``ChargingMinBallSpeedAngle``, degrees."""
CHARGING_MIN_DELTA_DIST = 0.05
"""``ChargingMinDeltaDist``, m."""
CHARGING_MIN_DELTA_ANG = 15.0
"""``ChargingMinDeltaAng``, degrees."""
CHARGING_IMMUNITY_S = 1.0
"""``ChargingImmunityTime``: no charging this long after the robot's own touch of the ball."""
CHARGING_COLLISION_MIN_S = 0.2
"""``ChargingCollisionMinTime``: how long a robot must keep charging to commit the foul."""
CHARGING_MAX_BALL_DIST = 1.0
"""``ChargingMaxBallRulesDist``: within this of the ball (either robot) the ball's direction
counts, m."""
CHARGING_MIN_COLL_BALL_DIST = 0.1
"""``ChargingMinCollBallDist``: a contact nearer the ball than this is no charge, m."""
CHARGING_MIN_COLLISION_SPEED = 0.2
"""``ChargingMinCollisionSpeed``: the speed toward the contact a charge needs, m/s."""
MOVED_GRACE_CYCLES = 50
"""A robot the referee moved is exempt from charging for this many cycles (1 s)."""


def robot_box(world, index: int) -> tuple[np.ndarray, np.ndarray]:
    """rcssserver3d's bounding box of robot ``index`` (world, m): its parts' visual models
    (:func:`~robocup_gym.robot.nao.mesh_boxes`) and every part's centre."""
    model = world.robots[index].model
    centres, rots = world.body_frames(index)
    lo, hi = centres.min(axis=0), centres.max(axis=0)
    for b, box_lo, box_hi in mesh_boxes(model.robot_type.index):
        mid = centres[b] + rots[b] @ ((box_lo + box_hi) / 2)
        ext = np.abs(rots[b]) @ ((box_hi - box_lo) / 2)
        lo = np.minimum(lo, mid - ext)
        hi = np.maximum(hi, mid + ext)
    return lo, hi


def _sphere_hits_box(centre: np.ndarray, radius: float, lo: np.ndarray, hi: np.ndarray) -> bool:
    """salt's ``BoundingSphere::Intersects(AABB3)``."""
    below = np.minimum(centre - lo, 0.0)
    above = np.maximum(centre - hi, 0.0)
    return float(np.sum(below * below) + np.sum(above * above)) <= radius * radius


@dataclass
class SafeSpot:
    """The server's ``GetSafeReposition`` for one cycle's moves of one team's robot.

    ``area`` is the team's own penalty area ``(x_lo, x_hi, y_lo, y_hi)``; ``crowded`` whether
    its area already holds :data:`MAX_PLAYERS_IN_OWN_AREA` of the team's robots (those inside
    and those moved in this cycle); ``inside`` whether the robot moved is one of them;
    ``boxes`` the bounding boxes of every other robot; ``ball`` the ball's (x, y).
    """

    side: str
    area: tuple[float, float, float, float]
    crowded: bool
    inside: bool
    boxes: list[tuple[np.ndarray, np.ndarray]]
    ball: np.ndarray

    def _adjust(self, agent: np.ndarray, cur: np.ndarray) -> bool:
        """Move ``cur`` out of a full own penalty area (in place); whether it was in it."""
        if self.inside or not self.crowded:
            return False
        x_lo, x_hi, y_lo, y_hi = self.area
        r = AGENT_RADIUS
        if not (x_lo - r < cur[0] < x_hi + r and y_lo - r < cur[1] < y_hi + r):
            return False
        if self.side == "left" and cur[0] > agent[0]:
            cur[0] = x_hi + r  # beyond the top of the area
        elif self.side == "right" and cur[0] < agent[0]:
            cur[0] = x_lo - r
        elif cur[1] > agent[1] or (cur[1] == agent[1] and cur[1] < 0):
            cur[1] = y_hi + r
        else:
            cur[1] = y_lo - r
        return True

    def _sample(self, agent: np.ndarray, cur: np.ndarray, candidates: list[np.ndarray]) -> None:
        """``GetSafeRepositionHelper_SamplePositions``: spots one radius from ``cur`` in x
        (away from the own goal first) and in y, kept in ``candidates`` nearest to the robot
        first, none within half a radius of another."""
        r = AGENT_RADIUS
        new: list[np.ndarray] = []
        xmove = cur.copy()
        if self.side == "left":
            xmove[0] = cur[0] + r * (1 if agent[0] < cur[0] else -1)
        else:
            xmove[0] = cur[0] + r * (-1 if agent[0] > cur[0] else 1)
        if abs(xmove[0]) <= FIELD_HALF_LENGTH:
            self._adjust(agent, xmove)
            new.append(xmove)
        if cur[0] == agent[0]:
            xmove2 = cur.copy()
            xmove2[0] = cur[0] + (r if self.side == "left" else -r)
            if abs(xmove2[0]) <= FIELD_HALF_LENGTH:
                self._adjust(agent, xmove2)
                new.append(xmove2)
        ymove = cur.copy()
        if cur[1] == agent[1]:
            ymove[1] = cur[1] + r * (1 if agent[1] < 0 else -1)
            self._adjust(agent, ymove)
            new.append(ymove)
            ymove2 = cur.copy()
            ymove2[1] = cur[1] + r * (-1 if agent[1] < 0 else 1)
            self._adjust(agent, ymove2)
            new.append(ymove2)
        else:
            ymove[1] = cur[1] + r * (1 if agent[1] < cur[1] else -1)
            self._adjust(agent, ymove)
            new.append(ymove)
        for pos in new:
            d_new = float(np.hypot(*(pos - agent)))
            at = len(candidates)
            add = True
            for k in range(len(candidates) - 1, -1, -1):  # from the back, as the server
                c = candidates[k]
                if float(np.hypot(*(c - pos))) < r / 2.0:
                    add = False
                    break
                if d_new >= float(np.hypot(*(c - agent))):
                    break
                at = k
            if add:
                candidates.insert(at, pos)

    def _unsafe(self, pos: np.ndarray) -> bool:
        if abs(pos[0]) > FIELD_HALF_LENGTH and abs(pos[1]) < GOAL_HALF_WIDTH + AGENT_RADIUS:
            return True  # in or behind a goal
        near = max(2 * AGENT_RADIUS, PASS_MODE_MIN_OPP_DIST)  # the server's safe distance
        if float(np.hypot(*(self.ball[:2] - pos[:2]))) < near:
            return True
        return any(_sphere_hits_box(pos, AGENT_RADIUS, lo, hi) for lo, hi in self.boxes)

    def find(self, target: np.ndarray, agent_xy: np.ndarray) -> np.ndarray:
        """The spot for a robot whose torso is at ``agent_xy`` asked to go to ``target``
        (x, y, z); the target itself when no free spot is found."""
        target = np.asarray(target, dtype=float)
        agent = np.asarray(agent_xy, dtype=float)[:2]
        pos = target.copy()
        candidates: list[np.ndarray] = []
        first = target[:2].copy()
        if self._adjust(agent, first):
            self._sample(agent, target[:2].copy(), candidates)
            if not candidates:
                return target
            pos[:2] = candidates.pop(0)
        unsafe = False
        for _ in range(MAX_SAFE_ATTEMPTS):
            unsafe = self._unsafe(pos)
            if unsafe:
                self._sample(agent, pos[:2].copy(), candidates)
            if not unsafe or not candidates:
                break
            pos[:2] = candidates.pop(0)
        return target if unsafe else pos


@dataclass
class _Counters:
    """A robot's charging clocks (cycles), as rcssserver3d keeps them."""

    since_ball_touch: int = int(CHARGING_IMMUNITY_S / CYCLE_S)
    charging: int = int(CHARGING_COLLISION_MIN_S / CYCLE_S)


@dataclass
class ContactFouls:
    """The state of both contact fouls: each robot's touching group (the one of the last
    cycle too), its recent torso velocities, its charging clocks and the cycles since the
    referee last moved it. Keys are the referee's :attr:`Player.key`."""

    group: dict[int, set] = field(default_factory=dict)
    old_group: dict[int, set] = field(default_factory=dict)
    velocities: dict[int, deque] = field(default_factory=dict)
    counters: dict[int, _Counters] = field(default_factory=dict)
    since_moved: dict[int, int] = field(default_factory=dict)

    # ------------------------------------------------------------------ every cycle
    def link(self, keys_of: dict[int, int], contacts: dict) -> None:
        """This step's contacts (``robot_contacts()`` of the world) join the robots' groups;
        ``keys_of`` maps robot indices to keys. A robot without a group yet (it came into the
        game since the groups last started again) is not linked."""
        for i, j in contacts:
            a, b = keys_of.get(i), keys_of.get(j)
            if a is None or b is None:
                continue
            ga, gb = self.group.get(a), self.group.get(b)
            if ga is None or gb is None or ga is gb:
                continue
            ga |= gb
            for k in gb:
                self.group[k] = ga
            gb.clear()

    def restart_groups(self, keys: list[int]) -> None:
        """Every robot alone again (the end of a cycle in which the game ran)."""
        for k in keys:
            self.old_group[k] = self.group.get(k, set())
            self.group[k] = {k}

    def record_velocity(self, key: int, velocity: np.ndarray) -> None:
        """The torso's linear velocity (world, m/s) after this cycle's step."""
        q = self.velocities.get(key)
        if q is None:
            q = self.velocities[key] = deque(
                [np.zeros(3)] * VELOCITY_SAMPLES, maxlen=VELOCITY_SAMPLES
            )
        q.appendleft(np.asarray(velocity, dtype=float).copy())

    def mean_velocity(self, key: int) -> np.ndarray:
        q = self.velocities.get(key)
        if q is None:
            return np.zeros(3)
        return sum(q, np.zeros(3)) / VELOCITY_SAMPLES

    def tick(self, keys: list[int], touching: set[int]) -> None:
        """A cycle of a running game: the clocks advance; a robot touching the ball now has
        touched it 0 cycles ago."""
        for k in keys:
            c = self.counters.setdefault(k, _Counters())
            c.since_ball_touch += 1
            c.charging += 1
            self.since_moved[k] = self.since_moved.get(k, MOVED_GRACE_CYCLES) + 1
        for k in touching:
            self.counters.setdefault(k, _Counters()).since_ball_touch = 0

    def pause(self) -> None:
        """A cycle of a paused game: the charging clocks start again."""
        self.counters.clear()

    def moved(self, key: int) -> None:
        """The referee moved this robot."""
        self.since_moved[key] = 0

    def forget(self, key: int) -> None:
        """A robot that left the game, or was penalised (its clocks start again)."""
        self.counters.pop(key, None)

    # ------------------------------------------------------------------ the two fouls
    def touching(
        self,
        side: str,
        team: list,
        side_of: dict[int, str],
        unum_of: dict[int, int],
        positions: dict[int, np.ndarray],
        fouled: set[int],
        rng: np.random.Generator,
        only_new: bool = True,
    ) -> list[tuple[int, np.ndarray]]:
        """``AnalyseTouchGroups`` for one team (``team``: its players' keys): the robots
        penalised, each with the centre (x, y) of its group. ``fouled`` holds the keys that
        have a foul to serve this cycle (they are not counted); the penalised are added."""
        out: list[tuple[int, np.ndarray]] = []
        order = [team[int(k)] for k in rng.permutation(len(team))]
        for key in order:
            group = self.group.get(key)
            if group is None:
                continue
            if key in fouled:
                if len(group) > 1:
                    group.discard(key)
                continue
            joined = len(self.old_group.get(key, ())) == 1 or not only_new
            if not (joined and len(group) > MAX_TOUCH_GROUP):
                continue
            members = sorted(group)
            members = [members[int(k)] for k in rng.permutation(len(members))]
            counts = {"left": 0, "right": 0}
            mate = opp = None
            n_fouled = 0
            total = np.zeros(2)
            for m in members:
                if m in fouled:
                    n_fouled += 1
                    continue
                total += positions[m][:2]
                counts[side_of[m]] += 1
                if unum_of[m] != 1:
                    if side_of[m] != side:
                        opp = m
                    else:
                        mate = m
            if len(group) - n_fouled <= MAX_TOUCH_GROUP:
                continue
            centre = total / (len(group) - n_fouled)
            if counts[side] >= len(group) - counts[side]:
                who = mate if unum_of[key] == 1 else key
            else:
                who = opp
            if who is None:
                continue
            out.append((who, centre))
            fouled.add(who)
            group.discard(who)
        if only_new and any(len(self.group.get(k, ())) > MAX_TOUCH_GROUP for k in team):
            out += self.touching(
                side, team, side_of, unum_of, positions, fouled, rng, only_new=False
            )
        return out

    def charging(
        self,
        left: list[int],
        opponents_of: dict[int, list[tuple[int, np.ndarray]]],
        positions: dict[int, np.ndarray],
        ball: np.ndarray,
        exempt: set[int],
        goalie_in_area: dict[int, bool],
    ) -> set[int]:
        """``AnalyseChargingFouls``: the keys of the robots that commit a charging foul this
        cycle. ``left``: the left team's keys; ``opponents_of``: for each, the opponents it
        touched this step with the mean contact point; ``exempt``: robots not standing, moved
        by the referee in the last second or with a foul to serve."""
        new = {k: _Counters(c.since_ball_touch, c.charging) for k, c in self.counters.items()}
        fouls: set[int] = set()

        def clocks(k: int) -> _Counters:
            return self.counters.setdefault(k, _Counters())

        def new_clocks(k: int) -> _Counters:
            c = clocks(k)
            return new.setdefault(k, _Counters(c.since_ball_touch, c.charging))

        immunity = int(CHARGING_IMMUNITY_S / CYCLE_S)
        min_time = int(CHARGING_COLLISION_MIN_S / CYCLE_S)
        for a in left:
            for b, contact in opponents_of.get(a, ()):
                pair = (a, b)
                if a in exempt or b in exempt:
                    continue
                vel = [self.mean_velocity(k) for k in pair]
                pos = [positions[k] for k in pair]
                speed = [float(np.hypot(v[0], v[1])) for v in vel]
                dist = [float(np.hypot(*(p[:2] - ball[:2]))) for p in pos]
                to_ball = [_angle_deg(v, ball[:2] - p[:2]) for v, p in zip(vel, pos, strict=True)]
                to_opp = [_angle_deg(vel[i], pos[1 - i][:2] - pos[i][:2]) for i in (0, 1)]
                goalie = [goalie_in_area.get(k, False) for k in pair]
                charging = [True, True]
                if dist[0] < CHARGING_MAX_BALL_DIST or dist[1] < CHARGING_MAX_BALL_DIST:
                    charging = [
                        to_ball[i] >= to_opp[i]
                        and to_ball[i] >= CHARGING_MIN_BALL_SPEED_ANGLE
                        and speed[i] >= CHARGING_MIN_SPEED
                        for i in (0, 1)
                    ]
                    if not charging[0] and not charging[1]:
                        dd = abs(dist[0] - dist[1])
                        da = abs(to_opp[0] - to_opp[1])
                        if dd > CHARGING_MIN_DELTA_DIST:
                            turn = da > CHARGING_MIN_DELTA_ANG
                            slow = [sp < CHARGING_MIN_SPEED for sp in speed]
                            charging = [
                                dist[i] > dist[1 - i] and (turn or slow[1 - i]) for i in (0, 1)
                            ]
                for i in (0, 1):
                    d = (contact[:2] + pos[1 - i][:2]) / 2.0 - pos[i][:2]
                    n = float(np.hypot(*d))
                    along = float(vel[i][:2] @ d) / n if n > 0 else math.nan
                    charging[i] = (
                        charging[i]
                        and speed[i] >= CHARGING_MIN_SPEED
                        and along >= CHARGING_MIN_COLLISION_SPEED
                    )
                for i in (0, 1):
                    if charging[i]:
                        mine, theirs = clocks(pair[i]), new_clocks(pair[1 - i])
                        if goalie[i]:
                            theirs.since_ball_touch = 0
                        elif mine.since_ball_touch < immunity:
                            theirs.since_ball_touch = min(
                                theirs.since_ball_touch, mine.since_ball_touch
                            )
                        theirs.charging = min(theirs.charging, mine.charging)
                if (charging[0] and charging[1]) or float(
                    np.hypot(*(contact[:2] - ball[:2]))
                ) < CHARGING_MIN_COLL_BALL_DIST:
                    charging = [False, False]
                for i in (0, 1):
                    c = clocks(pair[i])
                    if (
                        charging[i]
                        and not goalie[i]
                        and c.charging >= min_time
                        and c.since_ball_touch >= immunity
                    ):
                        fouls.add(pair[i])
                if not charging[0] and not charging[1]:
                    new_clocks(a).charging = 0
                    new_clocks(b).charging = 0
        self.counters.update(new)
        return fouls


def _angle_deg(v: np.ndarray, to: np.ndarray) -> float:
    """The absolute angle (degrees, 0–180) between the (x, y) direction of ``v`` and ``to``,
    as the server computes it (``atan2`` of each, the difference normalised)."""
    a = math.atan2(float(v[1]), float(v[0])) - math.atan2(float(to[1]), float(to[0]))
    a = (a + math.pi) % (2 * math.pi) - math.pi
    return abs(math.degrees(a))

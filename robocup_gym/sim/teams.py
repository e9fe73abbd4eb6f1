"""The two teams of a game as rcssserver3d's ``GameStateAspect`` keeps them: sides, uniform
numbers, the league's robot-type composition limits (wire reference §3.4, reference §9.8) and
the sideline slots at which robots enter. ``robocup-gym serve`` and the soccer environments
register their players here (:class:`TeamRegistry`, through the referee)."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

from robocup_gym.robot.types import TYPE_NUMBERS
from robocup_gym.sim.field import FIELD_HALF_LENGTH, FIELD_HALF_WIDTH
from robocup_gym.sim.fouls import AGENT_RADIUS

MAX_PLAYERS = 11

MAX_ROBOT_TYPE_COUNT = 7

MIN_ROBOT_TYPES = 3

MAX_SUM_TWO_TYPES = 9


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

    def __init__(self, robot_types=TYPE_NUMBERS, type_limits: bool = True) -> None:
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

"""Scripted teams over skill actions: every learnt team's first opponents and a check of the
game.

:class:`ScriptedTeam` plays the obvious football: the player nearest the ball walks round behind
it, lines up with the opponent goal and walks through the ball (a dribble: the walk pushes the
ball ahead faster than kicks do, each of which usually ends with the kicker on the ground),
past an opponent in the way; near the goal it kicks when the ball is where the scripted kick
sends it into the goal. The goalkeeper (the scenario's: uniform number 1 of a team of several;
the penalty's keeper) stays between the ball and the middle of its goal; the others follow the
play 3 m behind the ball; at the other team's kick-off or set piece the chaser waits outside
the circle the referee keeps clear. A team reads the positions of the ball, its own players and
the opponents and the play mode from what the game tells it (``team_view(agents)`` →
:class:`TeamView`: ground truth in-process; on a server, each player's own estimate and what
the team has seen, :mod:`robocup_gym.soccer.localisation`). :class:`StandingTeam` stands still.

A team is called with the game (an environment, or a team's connection to a server), the names
of its agents and (optionally) their observations, and returns their skill actions
(``robocup_gym.soccer.skills.SKILL_ACTION_LABELS``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robocup_gym.envs.observations import in_heading_frame, turn_to_deg
from robocup_gym.sim.field import FIELD_HALF_LENGTH
from robocup_gym.sim.referee import restart_side
from robocup_gym.soccer.skills import MAX_FORWARD_MPS, MAX_SIDEWAYS_MPS, MAX_TURN_DPS

__all__ = [
    "KICK_SPOT_BEHIND_M",
    "KICK_SPOT_RIGHT_M",
    "TEAMS",
    "ScriptedTeam",
    "StandingTeam",
    "TeamView",
]

KICK_SPOT_BEHIND_M = 0.11
"""Where the torso must be for the scripted kick: this far behind the ball, …"""
KICK_SPOT_RIGHT_M = 0.055
"""… and the ball this far to the torso's right (in front of the right foot)."""
_CREEP = 0.3
"""Share of the walk's forward speed for the last steps onto the ball before a kick."""
SHOOT_RANGE_M = 4.0
"""The chaser kicks when the ball is this close to the opponent goal (and in front of its right
foot); farther, it only dribbles."""
_APPROACH_M = 0.35
_APPROACH_PER_OFF = 1.5
_APPROACH_MAX_M = 1.2
"""The chaser first walks to ``_APPROACH_M`` + ``_APPROACH_PER_OFF`` × its distance off the line
(at most ``_APPROACH_MAX_M``) behind the kicking spot, on the line to the goal."""
_BACKWARDS = 0.3
"""Share of the walk's speed backwards at most (the walk is sure-footed at 0.2 m/s back)."""
_SIDEWAYS = 0.5
"""Share of the walk's sideways speed at most (types 1 and 3 fall at the full 0.3 m/s)."""
_NEAR_M = 0.5
_BLEND_M = 1.0
"""Nearer than ``_NEAR_M`` to its target a player faces where it is told; farther than
``_NEAR_M + _BLEND_M`` it faces the target and walks forwards; between, a blend."""
_ROUND_M = 0.5
"""A chaser in front of the ball passes it this far to the side."""
_DRIBBLE_START = (0.06, 0.1, 0.8, 20.0)
"""A chaser starts a dribble from behind the ball (up to 0.8 m), at most 0.06 m + 0.1 × its
distance behind off the kicking line through the ball to the goal, facing the goal within
20°, …"""
_DRIBBLE_KEEP = (0.1, 0.15, 1.5, 40.0)
"""… and goes on while behind it up to 1.5 m, 0.1 m + 0.15 × that off the line, facing the
goal within 40°."""
_DRIBBLE_AIM_M = 0.5
"""A dribbler heads for the point this far beyond the kicking spot on the line to the goal, …"""
_DRIBBLE_TURN = 0.6
"""… turning at most this share of the walk's turn rate, and slower the harder it turns (at
full speed and full turn the walk falls), …"""
_DRIBBLE_SIDE = 0.4
"""… and stepping sideways at most this share of the walk's sideways speed."""
_BLOCKED_AHEAD_M = 1.5
_BLOCKED_SIDE_M = 0.6
_PASS_BY_M = 0.7
"""An opponent less than ``_BLOCKED_AHEAD_M`` ahead of the ball and ``_BLOCKED_SIDE_M`` of the
line to the goal blocks a dribble; the chaser dribbles toward the point ``_PASS_BY_M`` beside it
on its free side."""
_FACE_AHEAD_M = 10.0
"""Lining up, the chaser faces the point this far beyond the ball on the line it dribbles
along."""
_WAIT_M = 2.5
"""At the other team's kick-off or set piece the chaser waits this far from the ball, on the
side of its own goal (the referee keeps the ball 2 m clear)."""
_GOALIE_DISTANCE_M = 1.2
_SUPPORT_DISTANCE_M = 3.0


@dataclass
class TeamView:
    """What a scripted team decides from, world frame (m)."""

    side: str
    """``"left"`` or ``"right"``: the team attacks +x or −x."""
    ball: np.ndarray
    """The ball's (x, y)."""
    positions: dict[str, np.ndarray]
    """Each of the team's agents' torso (x, y)."""
    headings: dict[str, tuple[float, float]]
    """Each agent's heading as (cos, sin)."""
    keepers: set[str]
    """The agents that play goalkeeper."""
    play_mode: str = "PlayOn"
    """The referee's play mode (``robocup_gym.types.PLAY_MODES``)."""
    opponents: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    """The other team's players' (x, y), one row each (those known: on a server, where they
    were last seen)."""


def _walk_to(
    pos: np.ndarray,
    heading: tuple[float, float],
    target: np.ndarray,
    face: np.ndarray,
    top: float = 1.0,
) -> np.ndarray:
    """A skill action walking from ``pos`` (heading (cos, sin)) to ``target``, turning to face
    the point ``face`` once near (all world frame), at most ``top`` of the walk's speeds. Far
    from the target it faces the target and walks forwards (between 0.5 and 1.5 m away it
    turns from one to the other); it never walks backwards or sideways faster than the walk
    does without falling, and turns on the spot first when it faces more than 45° away."""
    d = target - pos
    forward, left = in_heading_frame(heading, d[0], d[1])
    final = math.atan2(face[1] - pos[1], face[0] - pos[0])
    share = min(max((float(np.hypot(*d)) - _NEAR_M) / _BLEND_M, 0.0), 1.0)
    to_target = math.atan2(d[1], d[0]) - final
    to_target = math.atan2(math.sin(to_target), math.cos(to_target))
    err = turn_to_deg(heading, final + share * to_target)
    turn = float(np.clip(1.5 * err / MAX_TURN_DPS, -1.0, 1.0))
    if abs(err) > 45.0:  # turn on the spot first: walking while turning hard falls
        return np.array([0.0, 0.0, turn, -1.0])
    if abs(err) > 20.0:
        top = min(top, 0.5)
    top *= 1.0 - 0.5 * abs(turn)  # turning, slower
    sideways = float(np.clip(1.5 * left / MAX_SIDEWAYS_MPS, -_SIDEWAYS, _SIDEWAYS) * top)
    if abs(sideways) > 0.25:  # stepping sideways, slower forward
        top = min(top, 0.5)
    return np.array(
        [np.clip(1.5 * forward / MAX_FORWARD_MPS, -min(top, _BACKWARDS), top), sideways, turn, -1.0]
    )


def _in_kick_reach(
    pos: np.ndarray, heading: tuple[float, float], ball: np.ndarray, to_goal: np.ndarray
) -> bool:
    """Whether the scripted kick from here sends the ball toward the goal: the ball 8–15 cm in
    front of the torso and 2–10 cm to its right (where kick D reaches it from the walk's
    stance), the robot facing the goal within 15°."""
    c, s = heading
    d = ball - pos
    ahead, left = in_heading_frame(heading, d[0], d[1])
    facing = c * to_goal[0] + s * to_goal[1] > math.cos(math.radians(15))
    return bool(0.08 < ahead < 0.15 and -0.10 < left < -0.02 and facing)


def _past_opponents(ball: np.ndarray, to_goal: np.ndarray, opponents: np.ndarray) -> np.ndarray:
    """Where to dribble the ball: toward the goal (``to_goal``, a unit vector), or, with an
    opponent less than 1.5 m ahead of the ball and 0.6 m of the line, past its free side (the
    side the line passes it on, or the middle of the field's)."""
    right = np.array([to_goal[1], -to_goal[0]])
    for o in opponents:
        o = np.asarray(o, dtype=float)[:2]
        d = o - ball
        ahead, lateral = float(np.dot(d, to_goal)), float(np.dot(d, right))
        if 0.0 < ahead < _BLOCKED_AHEAD_M and abs(lateral) < _BLOCKED_SIDE_M:
            sides = (-1.0, 1.0) if lateral > 0.0 else (1.0, -1.0)  # the free side first
            if abs(lateral) < 0.1:  # straight at it: the side nearer the middle of the field
                sides = tuple(sorted(sides, key=lambda k: abs(o[1] + k * _PASS_BY_M * right[1])))
            past = o + sides[0] * _PASS_BY_M * right - ball
            return past / max(float(np.hypot(*past)), 1e-6)
    return to_goal


class StandingTeam:
    """Every player stands where it is."""

    name = "standing"

    def __call__(
        self, env: Any, agents: list[str], obs: dict[str, np.ndarray] | None = None
    ) -> dict[str, np.ndarray]:
        return {a: np.zeros(4) for a in agents}


class ScriptedTeam:
    """Go to the ball, dribble it toward the goal, kick near it; the goalkeeper guards the
    goal."""

    name = "scripted"

    def __init__(self) -> None:
        self._dribbling: set[str] = set()

    def __call__(
        self, env: Any, agents: list[str], obs: dict[str, np.ndarray] | None = None
    ) -> dict[str, np.ndarray]:
        if not agents:
            return {}
        view = env.team_view(agents)
        ball, positions, headings, keepers = view.ball, view.positions, view.headings, view.keepers
        attack = 1.0 if view.side == "left" else -1.0
        goal = np.array([attack * FIELD_HALF_LENGTH, 0.0])
        own_goal = -goal
        field_players = [a for a in agents if a not in keepers]
        chaser = min(
            field_players, key=lambda a: float(np.hypot(*(positions[a] - ball))), default=None
        )
        out = {}
        to_goal = (goal - ball) / max(float(np.hypot(*(goal - ball))), 1e-6)
        restart = restart_side(view.play_mode)
        for a in agents:
            pos, heading = positions[a], headings[a]
            if a == chaser and restart not in (None, view.side):
                # the other team's kick-off or set piece: wait outside the circle it keeps free
                act = _walk_to(pos, heading, ball - _WAIT_M * to_goal, ball)
            elif a == chaser:
                act = self._chase(a, pos, heading, ball, goal, to_goal, view.opponents)
            elif a in keepers:
                d = ball - own_goal
                guard = own_goal + _GOALIE_DISTANCE_M * d / max(float(np.hypot(*d)), 1e-6)
                act = _walk_to(pos, heading, guard, ball)
            else:
                support = ball - _SUPPORT_DISTANCE_M * to_goal
                act = _walk_to(pos, heading, support, ball)
            out[a] = act
        return out

    def _chase(
        self,
        agent: str,
        pos: np.ndarray,
        heading: tuple[float, float],
        ball: np.ndarray,
        goal: np.ndarray,
        to_goal: np.ndarray,
        opponents: np.ndarray,
    ) -> np.ndarray:
        """The chaser's action: round the ball to behind it, line up behind it, then dribble
        toward the goal (past an opponent in the way, on its free side); in shooting
        range it kicks when the ball is in front of its right foot. A dribble goes on while the
        ball stays ahead (a wider cone than the one it starts from: no dithering at the edge)."""
        shooting = float(np.hypot(*(goal - ball))) < SHOOT_RANGE_M
        to_goal = _past_opponents(ball, to_goal, opponents)
        right = np.array([to_goal[1], -to_goal[0]])  # the kicker's right, facing that way
        spot = ball - KICK_SPOT_BEHIND_M * to_goal - KICK_SPOT_RIGHT_M * right
        behind = -float(np.dot(pos - ball, to_goal))  # how far behind the ball, along the line
        off_line = float(np.dot(pos - spot, right))  # right of the kicking line (+)
        err = turn_to_deg(heading, math.atan2(to_goal[1], to_goal[0]))
        if agent in self._dribbling:
            base, slope, reach, facing = _DRIBBLE_KEEP
        else:
            base, slope, reach, facing = _DRIBBLE_START
        if (
            -0.05 < behind < reach
            and abs(off_line) < base + slope * max(behind, 0.0)
            and abs(err) < facing
        ):
            self._dribbling.add(agent)
            # walk through the ball at full speed, heading for a point on the line beyond it
            aim = spot + _DRIBBLE_AIM_M * to_goal
            err = turn_to_deg(heading, math.atan2(aim[1] - pos[1], aim[0] - pos[0]))
            turn = float(np.clip(1.5 * err / MAX_TURN_DPS, -_DRIBBLE_TURN, _DRIBBLE_TURN))
            # and stepping back onto the line (the walk drifts): off it, the foot misses the ball
            _, left = in_heading_frame(heading, *(-off_line * right))
            side = float(np.clip(2.5 * left / MAX_SIDEWAYS_MPS, -_DRIBBLE_SIDE, _DRIBBLE_SIDE))
            forward = 1.0 - 0.5 * abs(turn)
            kick = -1.0
            if shooting:  # slow down onto the ball and kick it when it is before the right foot
                forward = min(forward, _CREEP + 2.0 * max(behind - 0.2, 0.0))
                if _in_kick_reach(pos, heading, ball, to_goal):
                    kick = 1.0
            return np.array([forward, side, turn, kick])
        self._dribbling.discard(agent)
        face = ball + _FACE_AHEAD_M * to_goal  # along the line it dribbles (past an opponent)
        if behind < 0.15:  # beside or in front of the ball: pass it on the side it is on
            side = 1.0 if float(np.dot(pos - ball, right)) >= 0.0 else -1.0
            via = ball - _ROUND_M * to_goal + side * _ROUND_M * right
            return _walk_to(pos, heading, via, face)
        # the further off the line, the further behind the ball it lines up (the walk drifts
        # forward when it steps sideways: lined up close, it would walk into the ball askew)
        # (but never further back than it is: it steps onto the line, not back and forth)
        back = min(_APPROACH_M + _APPROACH_PER_OFF * abs(off_line), _APPROACH_MAX_M)
        back = max(min(back, behind - KICK_SPOT_BEHIND_M), _APPROACH_M)
        return _walk_to(pos, heading, spot - back * to_goal, face)


TEAMS = {"scripted": ScriptedTeam, "standing": StandingTeam}
"""Built-in teams by name."""

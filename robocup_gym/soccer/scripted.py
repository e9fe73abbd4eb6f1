"""Scripted teams over skill actions: every learnt team's first opponents and a check of the
game.

:class:`ScriptedTeam` plays the obvious football: the player nearest the ball walks to the spot
from which the scripted kick sends the ball toward the opponent goal, turns, and kicks; the
goalkeeper (the scenario's: uniform number 1 of a team of several; the penalty's keeper) stays
between the ball and the middle of its goal; the others follow the play 3 m behind the ball. It
reads the positions of the ball and its own players from what the game tells it
(``team_view(agents)`` → :class:`TeamView`: ground truth in-process; on a server, each player's
own estimate, :mod:`robocup_gym.soccer.localisation`). :class:`StandingTeam` stands still.

A team is called with the game (an environment, or a team's connection to a server), the names
of its agents and (optionally) their observations, and returns their skill actions
(``robocup_gym.soccer.skills.SKILL_ACTION_LABELS``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from robocup_gym.envs.observations import in_heading_frame, turn_to_deg
from robocup_gym.sim.field import FIELD_HALF_LENGTH
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
_APPROACH_M = 0.35
"""The chaser first walks to this far behind the kicking spot, on the line to the goal."""
_CREEP = 0.3
"""Share of the walk's speeds for the last steps onto the kicking spot."""
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


def _walk_to(
    pos: np.ndarray,
    heading: tuple[float, float],
    target: np.ndarray,
    face: np.ndarray,
    top: float = 1.0,
) -> np.ndarray:
    """A skill action walking from ``pos`` (heading (cos, sin)) to ``target``, turning to face
    the point ``face`` on the way (all world frame), at most ``top`` of the walk's speeds."""
    d = target - pos
    forward, left = in_heading_frame(heading, d[0], d[1])
    err = turn_to_deg(heading, math.atan2(face[1] - pos[1], face[0] - pos[0]))
    if abs(err) > 45.0:  # turn first: walking fast while turning hard falls
        top = min(top, 0.3)
    return np.array(
        [
            np.clip(1.5 * forward / MAX_FORWARD_MPS, -top, top),
            np.clip(1.5 * left / MAX_SIDEWAYS_MPS, -top, top),
            np.clip(1.5 * err / MAX_TURN_DPS, -1.0, 1.0),
            -1.0,
        ]
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


class StandingTeam:
    """Every player stands where it is."""

    name = "standing"

    def __call__(
        self, env: Any, agents: list[str], obs: dict[str, np.ndarray] | None = None
    ) -> dict[str, np.ndarray]:
        return {a: np.zeros(4) for a in agents}


class ScriptedTeam:
    """Go to the ball, turn, kick toward the goal; the goalkeeper guards the goal."""

    name = "scripted"

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
        right = np.array([to_goal[1], -to_goal[0]])  # the kicker's right, facing the goal
        spot = ball - KICK_SPOT_BEHIND_M * to_goal - KICK_SPOT_RIGHT_M * right
        for a in agents:
            pos, heading = positions[a], headings[a]
            if a == chaser:
                # come from behind the ball (a robot in front of it walks round it), then
                # creep onto the kicking spot slowly (the walk overshoots) and kick
                approach = spot - _APPROACH_M * to_goal
                behind = float(np.dot(pos - ball, to_goal)) < -0.05
                off_line = abs(float(np.dot(pos - spot, right))) > 0.04
                far = float(np.hypot(*(approach - pos))) > 0.6
                if not behind or far or off_line:  # to the approach point, in line first
                    act = _walk_to(pos, heading, approach, goal, top=1.0 if far else _CREEP)
                else:
                    act = _walk_to(pos, heading, spot, goal, top=_CREEP)
                    if _in_kick_reach(pos, heading, ball, to_goal):
                        act[3] = 1.0
            elif a in keepers:
                d = ball - own_goal
                guard = own_goal + _GOALIE_DISTANCE_M * d / max(float(np.hypot(*d)), 1e-6)
                act = _walk_to(pos, heading, guard, ball)
            else:
                support = ball - _SUPPORT_DISTANCE_M * to_goal
                act = _walk_to(pos, heading, support, ball)
            out[a] = act
        return out


TEAMS = {"scripted": ScriptedTeam, "standing": StandingTeam}
"""Built-in teams by name."""

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
:class:`OverScripted` plays a learnt team that acts by correcting the scripted team (the team
option ``over_scripted``: a residual added to each player's scripted skill action).

A team is called with the game (an environment, or a team's connection to a server), the names
of its agents and (optionally) their observations, and returns their skill actions (the
game's ``skill_action_labels``; the scripted teams decide the walk and the kick, and start no
other motion skill).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robocup_gym.sim.field import FIELD_HALF_LENGTH
from robocup_gym.sim.referee import restart_side
from robocup_gym.soccer.ball_play import BallPlay, walk_to
from robocup_gym.soccer.skills import checked_action, fit_skill_actions, game_skill_labels

__all__ = [
    "TEAMS",
    "OverScripted",
    "ScriptedTeam",
    "StandingTeam",
    "TeamView",
]

SHOOT_RANGE_M = 4.0
"""The chaser kicks when the ball is this close to the opponent goal (and in front of its right
foot); farther, it only dribbles."""
_BLOCKED_AHEAD_M = 1.5
_BLOCKED_SIDE_M = 0.6
_PASS_BY_M = 0.7
"""An opponent less than ``_BLOCKED_AHEAD_M`` ahead of the ball and ``_BLOCKED_SIDE_M`` of the
line to the goal blocks a dribble; the chaser dribbles toward the point ``_PASS_BY_M`` beside it
on its free side."""
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

    @property
    def goal(self) -> np.ndarray:
        """The middle of the goal the team attacks, (x, y)."""
        return np.array([(1.0 if self.side == "left" else -1.0) * FIELD_HALF_LENGTH, 0.0])


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
        labels = game_skill_labels(env)
        return {a: np.zeros(len(labels)) for a in agents}


class ScriptedTeam:
    """Go to the ball, dribble it toward the goal, kick near it; the goalkeeper guards the
    goal."""

    name = "scripted"

    def __init__(self) -> None:
        self._play = BallPlay()

    def __call__(
        self, env: Any, agents: list[str], obs: dict[str, np.ndarray] | None = None
    ) -> dict[str, np.ndarray]:
        if not agents:
            return {}
        view = env.team_view(agents)
        ball, positions, headings, keepers = view.ball, view.positions, view.headings, view.keepers
        goal = view.goal
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
                act = walk_to(pos, heading, ball - _WAIT_M * to_goal, ball)
            elif a == chaser:
                shooting = float(np.hypot(*(goal - ball))) < SHOOT_RANGE_M
                line = _past_opponents(ball, to_goal, view.opponents)
                act = self._play.action(a, pos, heading, ball, line, shooting)
            elif a in keepers:
                d = ball - own_goal
                guard = own_goal + _GOALIE_DISTANCE_M * d / max(float(np.hypot(*d)), 1e-6)
                act = walk_to(pos, heading, guard, ball)
            else:
                support = ball - _SUPPORT_DISTANCE_M * to_goal
                act = walk_to(pos, heading, support, ball)
            out[a] = act
        return fit_skill_actions(out, env)


class OverScripted:
    """Skill actions of a team that acts by correcting the scripted team: each player's action
    (the game's skill action layout, each value in [-1, 1]) is added to what
    :class:`ScriptedTeam` decides for it this cycle, and the sum clipped to [-1, 1]. A zero
    action plays the scripted team: a policy learns a residual over it, as the shipped skills
    learn one over their reference motions."""

    def __init__(self) -> None:
        self._team = ScriptedTeam()

    def skill_actions(
        self, env: Any, agents: list[str], actions: dict[str, np.ndarray]
    ) -> dict[str, np.ndarray]:
        """The skill actions of the residual ``actions`` of ``agents`` in ``env``.

        Raises:
            ValueError: an action of the wrong shape or with a value that is not finite.
        """
        labels = game_skill_labels(env)
        what = "a residual over the scripted team's skill action: " + ", ".join(labels)
        checked = {a: checked_action(a, actions[a], labels, what) for a in agents}
        base = self._team(env, agents)
        return {a: np.clip(base[a] + checked[a], -1.0, 1.0) for a in agents}


TEAMS = {"scripted": ScriptedTeam, "standing": StandingTeam}
"""Built-in teams by name."""

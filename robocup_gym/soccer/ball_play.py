"""Playing the ball with the skill actions: walk round behind it, line up with a direction,
walk it along that direction (a dribble: the walk pushes the ball ahead faster than the scripted
kick moves it, and stays up), or, asked to shoot, kick it when it is before the right foot.

:class:`BallPlay` is the scripted team's chaser (:mod:`robocup_gym.soccer.scripted`), and the
``plays`` actions of a learning team (:data:`PLAY_ACTION_LABELS`): a policy chooses whether to
play the ball and in which direction, and :class:`BallPlay` turns that into the skill action
(:data:`~robocup_gym.soccer.skills.SKILL_ACTION_LABELS`) of each cycle's decision, from what the
team sees (:class:`~robocup_gym.soccer.scripted.TeamView`). :func:`walk_to` walks a player to a
point within what the walk does without falling.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from robocup_gym.envs.observations import in_heading_frame, turn_to_deg
from robocup_gym.soccer.skills import (
    MAX_FORWARD_MPS,
    MAX_SIDEWAYS_MPS,
    MAX_TURN_DPS,
    SKILL_ACTION_LABELS,
    checked_action,
)

if TYPE_CHECKING:
    from robocup_gym.soccer.scripted import TeamView

__all__ = [
    "KICK_SPOT_BEHIND_M",
    "KICK_SPOT_RIGHT_M",
    "PLAY_ACTION_LABELS",
    "PLAY_ACTION_WHAT",
    "BallPlay",
    "as_play_action",
    "in_kick_reach",
    "walk_to",
]

PLAY_ACTION_LABELS = (*SKILL_ACTION_LABELS, "play", "direction")
"""A ``plays`` action (each value in [-1, 1]): a skill action (``forward``, ``left``, ``turn``,
``kick``), or, with ``play`` above 0.5, the ball played instead: the player goes round behind
the ball and walks it along ``direction`` (−1 … 1: −180° … 180° from the line from the ball to
the middle of the opponent goal, counter-clockwise; 0 is straight at the goal), and with
``kick`` above 0.5 it kicks the ball when it is before its right foot instead of walking
through it. While it plays the ball the walk values are not used."""

PLAY_ACTION_WHAT = "a plays action: " + ", ".join(PLAY_ACTION_LABELS)
"""How error messages describe a plays action."""

KICK_SPOT_BEHIND_M = 0.11
"""Where the torso must be for the scripted kick: this far behind the ball, …"""
KICK_SPOT_RIGHT_M = 0.055
"""… and the ball this far to the torso's right (in front of the right foot)."""
_CREEP = 0.3
"""Share of the walk's forward speed for the last steps onto the ball before a kick."""
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
_FACE_AHEAD_M = 10.0
"""Lining up, the chaser faces the point this far beyond the ball on the line it dribbles
along."""


def walk_to(
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


def in_kick_reach(
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


def as_play_action(skill_action: np.ndarray) -> np.ndarray:
    """A skill action as the ``plays`` action that does the same (``play`` −1)."""
    return np.concatenate([np.asarray(skill_action, dtype=float), [-1.0, 0.0]])


class BallPlay:
    """Plays the ball for the players of one team: the skill action that takes a player's ball
    along a direction, one decision at a time. It remembers which players are dribbling (a
    dribble goes on in a wider cone than the one it starts from: no dithering at its edge)."""

    def __init__(self) -> None:
        self._dribbling: set[str] = set()

    def skill_actions(
        self, view: TeamView, actions: Mapping[str, np.ndarray]
    ) -> dict[str, np.ndarray]:
        """The skill actions of the ``plays`` ``actions`` (:data:`PLAY_ACTION_LABELS`) of the
        team that ``view`` shows (its side, ball, positions and headings)."""
        ball = np.asarray(view.ball, dtype=float)[:2]
        to_goal = math.atan2(-ball[1], view.goal[0] - ball[0])  # the goal's middle is at y = 0
        out: dict[str, np.ndarray] = {}
        checked = {  # every action checked before any is played
            agent: checked_action(agent, action, PLAY_ACTION_LABELS, PLAY_ACTION_WHAT)
            for agent, action in actions.items()
        }
        for agent, a in checked.items():
            if not a[4] > 0.5:
                self._dribbling.discard(agent)
                out[agent] = a[:4].copy()
                continue
            angle = to_goal + math.pi * float(a[5])
            line = np.array([math.cos(angle), math.sin(angle)])
            pos, heading = view.positions[agent], view.headings[agent]
            out[agent] = self.action(agent, pos, heading, ball, line, bool(a[3] > 0.5))
        return out

    def action(
        self,
        agent: str,
        pos: np.ndarray,
        heading: tuple[float, float],
        ball: np.ndarray,
        to_goal: np.ndarray,
        shooting: bool,
    ) -> np.ndarray:
        """The skill action of ``agent`` (torso at ``pos``, heading (cos, sin)) playing the ball
        at ``ball`` along ``to_goal`` (a unit vector; world frame): round the ball to behind it,
        line up behind it, then walk it along that line; ``shooting``, it slows down onto the
        ball and kicks when the ball is in front of its right foot."""
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
                if in_kick_reach(pos, heading, ball, to_goal):
                    kick = 1.0
            return np.array([forward, side, turn, kick])
        self._dribbling.discard(agent)
        face = ball + _FACE_AHEAD_M * to_goal  # along the line it dribbles (past an opponent)
        if behind < 0.15:  # beside or in front of the ball: pass it on the side it is on
            side = 1.0 if float(np.dot(pos - ball, right)) >= 0.0 else -1.0
            via = ball - _ROUND_M * to_goal + side * _ROUND_M * right
            return walk_to(pos, heading, via, face)
        # the further off the line, the further behind the ball it lines up (the walk drifts
        # forward when it steps sideways: lined up close, it would walk into the ball askew)
        # (but never further back than it is: it steps onto the line, not back and forth)
        back = min(_APPROACH_M + _APPROACH_PER_OFF * abs(off_line), _APPROACH_MAX_M)
        back = max(min(back, behind - KICK_SPOT_BEHIND_M), _APPROACH_M)
        return walk_to(pos, heading, spot - back * to_goal, face)

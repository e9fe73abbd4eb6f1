"""Motion skills: motions a player in a game starts from its skill action and that run to their
end (the walk takes over again afterwards), registered by name.

A game's ``skills`` option (:class:`~robocup_gym.soccer.env.SoccerConfig`) lists the motion
skills its players can start; :func:`register_motion_skill` makes a new one an action of any
game that lists it. A motion is any object with ``command(perception)`` (the cycle's joint
velocities) and ``done`` (:class:`Motion`); :class:`ScriptedMotion` plays fixed velocities,
:class:`KeyframeMotion` drives target angles as the kicking tasks do.

Registered here:

* ``kick``: rcssserver3d's scripted kick D (the fixture ``kick_D.json``: 25 cycles of open-loop
  right hip and knee velocities, then 15 at rest; from a robot standing straight 0.2 m behind
  the ball it moves the ball 2.3 m), in the direction the player faces; the player usually
  falls and gets up.
* ``kick-to`` (parameters ``distance`` and ``direction``): the kick TargetKick-v1 plays for that
  command (:func:`~robocup_gym.envs.tasks.commanded_kicks.commanded_kick`), after a prelude
  that drives the joints to the crouched pose it starts from (:func:`kick_to`).
* ``approach-kick`` (parameters ``distance`` and ``direction``): the player walks to where the
  ball lies at the spot of the kick that carries that distance best after an approach, facing
  so that it goes in that direction (:class:`Approach`), then plays that kick after
  ``kick-to``'s prelude (:class:`ApproachKick`).

A motion may first steer the walk (:class:`Motion`'s optional ``walk_command``): while it
returns a walking command the player walks with it, and an action that no longer starts the
motion stops it; once it returns ``None`` the motion plays to its end.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from typing import Protocol

import numpy as np

from robocup_gym.envs.actions import ActionMapper, ActionMode
from robocup_gym.envs.config import resolve_angles
from robocup_gym.envs.observations import heading_frame, in_heading_frame, turn_to_deg
from robocup_gym.envs.tasks.commanded_kicks import (
    CommandedKick,
    commanded_kick,
    kick_library,
    landing_cost,
)
from robocup_gym.envs.tasks.reference_kick import (
    Keyframes,
    ReferenceKickConfig,
    kick_offsets_deg,
    kick_table,
)
from robocup_gym.envs.tasks.walk import MOVING_SPEED_MPS
from robocup_gym.robot.nao import nao_model
from robocup_gym.sim.fidelity import load_data
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.types import Perception

__all__ = [
    "APPROACH_LIMITS",
    "APPROACH_MAX_S",
    "APPROACH_SPOT_CORRECTION",
    "APPROACH_TOLERANCE",
    "KICK_CYCLES",
    "KICK_FOLLOW_THROUGH_CYCLES",
    "KICK_TO_DIRECTION_DEG",
    "KICK_TO_DISTANCE_M",
    "KICK_TO_HOLD_S",
    "KICK_TO_PRELUDE_S",
    "RESERVED_NAMES",
    "WALK_ACTION_LABELS",
    "Approach",
    "ApproachKick",
    "KeyframeMotion",
    "Motion",
    "MotionSkill",
    "ScriptedMotion",
    "approach_kick_choice",
    "approach_landings",
    "checked_motion_skills",
    "kick_sequence",
    "kick_to",
    "kick_to_command",
    "kick_to_spot",
    "kick_to_values",
    "motion_skill",
    "motion_skills",
    "register_motion_skill",
    "unregister_motion_skill",
]

WALK_ACTION_LABELS = ("forward", "left", "turn")
"""The walk's part of a skill action: its velocity command, each in [-1, 1] (scaled by the
maxima of :mod:`robocup_gym.soccer.skills`), before the motion skills' values."""
RESERVED_NAMES = (*WALK_ACTION_LABELS, "walk", "get-up")
"""Names a motion skill cannot have: the walk's action values and the skills' other modes."""


@functools.cache
def _kick_blocks() -> tuple[tuple[int, tuple[tuple[str, float], ...]], ...]:
    spec = load_data("kick_D.json")
    out = []
    for block in spec["command_sequence"]:
        vel = tuple((name, float(v)) for name, v in block["velocities_rad_per_s"].items())
        if vel:  # the motion itself, without the recording's idle cycles before and after
            out.append((int(block["cycles"]), vel))
    out.append((KICK_FOLLOW_THROUGH_CYCLES, ()))
    return tuple(out)


@functools.cache
def kick_sequence(robot_type: int = 0) -> tuple[np.ndarray, ...]:
    """The scripted kick's joint velocities per cycle (rad/s, in the effector order of a Nao of
    ``robot_type``; every joint not in the script at 0)."""
    names = nao_model(robot_type).effector_names
    out = []
    for cycles, vel in _kick_blocks():
        v = dict(vel)
        row = np.array([v.get(n, 0.0) for n in names])
        row.flags.writeable = False
        out += [row] * cycles
    return tuple(out)


KICK_FOLLOW_THROUGH_CYCLES = 15
"""Cycles with the joints at rest after the kick's motion (the foot meets the ball 14 cycles
after the motion starts)."""
KICK_CYCLES = 25 + KICK_FOLLOW_THROUGH_CYCLES
"""Cycles of the scripted kick: its 25 cycles of motion and the follow-through."""


class Motion(Protocol):
    """One run of a motion skill on one player, from its start to its end."""

    def command(self, p: Perception) -> np.ndarray:
        """This cycle's joint velocities (rad/s, one per effector of the player's Nao type, in
        its effector order) from the player's perception ``p`` of the cycle; called once a
        cycle while the motion runs."""
        ...

    @property
    def done(self) -> bool:
        """Whether the motion has ended (the player then walks again)."""
        ...

    # A motion may also have ``walk_command(p) -> np.ndarray | None``, called once a cycle
    # before ``command`` with the player's perception: while it returns a walking command
    # (forward m/s, left m/s, turn deg/s) the player walks with it (the game's walk) instead
    # of playing ``command``, and stops the motion when its action no longer starts it; once
    # it returns ``None`` it is not called again and the motion plays to its end.


class ScriptedMotion:
    """An open-loop motion: given joint velocities, one row per cycle (rad/s)."""

    def __init__(self, rows: Sequence[np.ndarray]) -> None:
        if not rows:
            raise ValueError("a scripted motion needs at least one cycle")
        self.rows = rows
        self.cycle = 0

    def command(self, p: Perception) -> np.ndarray:
        row = self.rows[self.cycle]
        self.cycle += 1
        return row

    @property
    def done(self) -> bool:
        return self.cycle >= len(self.rows)


@dataclass(frozen=True)
class MotionSkill:
    """A motion skill: what a skill action's value of its name starts."""

    name: str
    start: Callable[..., Motion]
    """``start(robot_type, *parameters)``: a new run of the motion on a Nao of the given type
    (0–4), with the action's values of :attr:`parameters` (each in [-1, 1])."""
    description: str = ""
    parameters: tuple[str, ...] = ()
    """Names of the values the motion takes from the skill action besides its start value
    (e.g. a kick's ``direction``)."""

    @property
    def labels(self) -> tuple[str, ...]:
        """Its values in a skill action: its name (the start value), then ``name.parameter``
        for each parameter."""
        return (self.name, *(f"{self.name}.{p}" for p in self.parameters))


_MOTION_SKILLS: dict[str, MotionSkill] = {}


def register_motion_skill(
    name: str,
    start: Callable[..., Motion],
    description: str = "",
    parameters: Sequence[str] = (),
    replace: bool = False,
) -> MotionSkill:
    """Register a motion skill: ``start(robot_type, *parameters)`` gives a new :class:`Motion`
    (e.g. a :class:`ScriptedMotion`) each time a player starts it, from the skill action's
    values of ``parameters`` (each in [-1, 1]). A game with ``skills`` naming it then has
    ``1 + len(parameters)`` more values in its skill actions (:attr:`MotionSkill.labels`).
    A game takes its motion skills when it is made: one replaced later is the new one in games
    made after. A motion's command that is not one finite velocity per joint stops the step with
    a ``ValueError`` naming the skill and the player.

    Raises:
        ValueError: ``name`` is empty, is a walk value's name or a skill's mode (``walk``,
            ``get-up``), or is registered already (unless ``replace``).
    """
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"a motion skill needs a name, got {name!r}")
    if name in RESERVED_NAMES:
        raise ValueError(f"{name!r} is taken by the walk or the get-up; choose another name")
    if name in _MOTION_SKILLS and not replace:
        raise ValueError(
            f"a motion skill {name!r} is registered already (replace=True replaces it)"
        )
    if not callable(start):
        raise ValueError(f"motion skill {name!r}: start must be callable, got {start!r}")
    if isinstance(parameters, str) or not all(isinstance(p, str) and p for p in parameters):
        raise ValueError(f"motion skill {name!r}: parameters are names, got {parameters!r}")
    skill = MotionSkill(name, start, description, tuple(parameters))
    _MOTION_SKILLS[name] = skill
    return skill


def checked_motion_skills(names: object) -> tuple[str, ...]:
    """``names`` as a game's motion skills: a sequence of registered names, each once.

    Raises:
        ValueError: not a sequence of names (a single string included), an unknown name (the
            registered ones listed) or a name listed twice.
    """
    if isinstance(names, str) or not isinstance(names, Sequence):
        raise ValueError(f"skills must be a sequence of motion skill names, got {names!r}")
    out = tuple(names)
    for name in out:
        motion_skill(name)
    if len(set(out)) != len(out):
        raise ValueError(f"skills lists a motion skill twice: {out}")
    return out


def unregister_motion_skill(name: str) -> None:
    """Remove the motion skill ``name`` (nothing if there is none)."""
    _MOTION_SKILLS.pop(name, None)


def motion_skills() -> dict[str, MotionSkill]:
    """The registered motion skills, by name."""
    return dict(_MOTION_SKILLS)


def motion_skill(name: str) -> MotionSkill:
    """The registered motion skill ``name``.

    Raises:
        ValueError: none of that name (the message lists the registered ones).
    """
    try:
        return _MOTION_SKILLS[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"no motion skill {name!r}; registered: {', '.join(sorted(_MOTION_SKILLS))}"
        ) from None


register_motion_skill(
    "kick",
    lambda robot_type: ScriptedMotion(kick_sequence(robot_type)),
    "rcssserver3d's scripted kick D with the right foot in the direction the player faces, "
    f"{KICK_CYCLES} cycles",
)


# ---------------------------------------------------------------------------- kick-to
KICK_TO_PRELUDE_S = 1.0
"""Seconds a ``kick-to`` first drives the joints to the crouched pose its kicks start from.
Played in a game straight from the walk's stance, the kicks miss (the 10 m kick moved the ball
2.6 m once in three after a 0.6 s prelude); after 1 s they carry as from the pose."""
KICK_TO_HOLD_S = 0.5
"""Seconds a ``kick-to`` holds the pose after its kick's last keyframe."""
KICK_TO_DISTANCE_M = (2.0, 10.0)
"""The distances a ``kick-to``'s ``distance`` value spans from −1 to 1, m."""
KICK_TO_DIRECTION_DEG = 45.0
"""The direction of a ``kick-to``'s ``direction`` value of 1, deg counter-clockwise from the
player's heading (−1: clockwise)."""


class KeyframeMotion:
    """A motion of target angles: every joint driven toward a pose plus a kick's keyframed
    offsets (:data:`~robocup_gym.envs.tasks.reference_kick.Keyframes`) as the kicking tasks
    drive theirs under a zero action (velocity = ``target_gain`` × the angle error, clipped to
    the joint's maximum speed): first ``prelude_s`` toward the pose alone, then the keyframes,
    then ``hold_s`` in the pose.

    Args:
        robot_type: The player's Nao type (0–4).
        keyframes: The offsets over the pose, deg, by effector name, at times from the end
            of the prelude.
        prelude_s, hold_s: See above, s.
        pose_deg: The pose, deg by joint name (default: the kicking tasks' start pose, the
            paper's crouched standing pose).
    """

    def __init__(
        self,
        robot_type: int,
        keyframes: Keyframes,
        prelude_s: float = KICK_TO_PRELUDE_S,
        hold_s: float = KICK_TO_HOLD_S,
        pose_deg: Mapping[str, float] | None = None,
    ) -> None:
        c = ReferenceKickConfig()
        model = nao_model(robot_type)
        pose = resolve_angles(model, c.joint_start_deg if pose_deg is None else pose_deg, "pose")
        self._mapper = ActionMapper(
            model,
            np.arange(len(model.joints)),
            ActionMode.TARGET_ANGLE,
            c.target_gain,
            around_deg=pose,
            spread_deg=c.target_around_start_deg,
            stop_margin_deg=c.target_stop_margin_deg,
        )
        self._zero = np.zeros(len(model.joints))
        self._table = kick_table(keyframes)
        self._prelude = round(prelude_s / CYCLE_S)
        self._cycles = self._prelude + round((float(self._table[1][-1]) + hold_s) / CYCLE_S)
        self.cycle = 0

    def command(self, p: Perception) -> np.ndarray:
        t = (self.cycle - self._prelude) * CYCLE_S
        self._mapper.set_offsets({} if t < 0.0 else kick_offsets_deg(self._table, t))
        self.cycle += 1
        return self._mapper.command(self._zero, p.joint_angles_deg)

    @property
    def done(self) -> bool:
        return self.cycle >= self._cycles


def kick_to_command(distance: float, direction: float) -> tuple[float, float]:
    """A ``kick-to`` action's ``distance`` and ``direction`` values (each in [-1, 1]) as the
    command: (distance m, :data:`KICK_TO_DISTANCE_M`; direction deg, ±
    :data:`KICK_TO_DIRECTION_DEG`)."""
    lo, hi = KICK_TO_DISTANCE_M
    d, a = (float(np.clip(v, -1.0, 1.0)) for v in (distance, direction))
    return lo + (d + 1.0) / 2.0 * (hi - lo), a * KICK_TO_DIRECTION_DEG


def kick_to_values(distance_m: float, direction_deg: float) -> tuple[float, float]:
    """The ``kick-to`` action's ``distance`` and ``direction`` values (each in [-1, 1]) of a
    command (distance m, direction deg): the inverse of :func:`kick_to_command`."""
    lo, hi = KICK_TO_DISTANCE_M
    return 2.0 * (distance_m - lo) / (hi - lo) - 1.0, direction_deg / KICK_TO_DIRECTION_DEG


def kick_to_spot(
    distance_m: float, direction_deg: float, robot_type: int = 0
) -> tuple[float, float]:
    """Where the ball must lie for the ``kick-to`` of a command once its prelude is over: (ahead,
    left) of the torso's centre in its heading frame, m (the spot the kick was searched with).
    The prelude moves the torso (after walking: 1–3 cm forward, up to ~2 cm sideways, by where
    the walk left the feet), and the kicks are sharp: a ball 3 cm nearer goes ~1.5 m."""
    return _from_torso(commanded_kick(distance_m, direction_deg, robot_type)[1])


def _from_torso(ball_spot: tuple[float, float]) -> tuple[float, float]:
    """A kick's ball spot (world x, y, m, for a robot at the kicks' start) as (ahead, left) of
    the torso's centre, m."""
    start = ReferenceKickConfig().robot_start_pos  # the kicks were searched facing +x from here
    return float(ball_spot[0] - start[0]), float(ball_spot[1] - start[1])


def kick_to(robot_type: int, distance: float, direction: float) -> KeyframeMotion:
    """The ``kick-to`` motion for its action values (:func:`kick_to_command`): the kick that
    TargetKick-v1 plays for that command on this Nao type
    (:func:`~robocup_gym.envs.tasks.commanded_kicks.commanded_kick`), after a
    :data:`KICK_TO_PRELUDE_S` prelude to its start pose; the ball must then be at
    :func:`kick_to_spot`."""
    keyframes, _ = commanded_kick(*kick_to_command(distance, direction), robot_type)
    return KeyframeMotion(robot_type, keyframes)


register_motion_skill(
    "kick-to",
    kick_to,
    "the commanded kick of TargetKick-v1 for a distance (2-10 m) and a direction (±45°), "
    f"after {KICK_TO_PRELUDE_S:g} s to its crouched start pose; the ball at kick_to_spot then",
    parameters=("distance", "direction"),
)


# ---------------------------------------------------------------------------- approach-kick
APPROACH_STAGE_M = 0.25
"""An approach first walks to a point this far behind its pose on the kick's line, …"""
APPROACH_STAGE_TOLERANCE = (0.04, 5.0)
"""… until within this distance (m) and heading (deg) of it, …"""
APPROACH_TOLERANCE = (0.015, 3.0)
"""… then onto the pose at :data:`APPROACH_CREEP` of its speeds until within this distance (m)
and heading (deg): a kick wants the ball within ~1 cm of its spot."""
APPROACH_CREEP = 0.15
"""Share of :data:`APPROACH_LIMITS` on the last part of an approach (nearer than
:data:`APPROACH_NEAR_M` to the staging point, and after it): a faster walk overshoots."""
APPROACH_CREEP_MIN_MPS = 1.2 * MOVING_SPEED_MPS
"""Onto the pose an approach walks at least this fast (0.06 m/s; forward, backward or sideways,
whichever it walks most) until it arrives: the walk takes no step for a slower command
(:data:`~robocup_gym.envs.tasks.walk.MOVING_SPEED_MPS`), and one left the robot standing short
of the pose until the approach gave up."""
APPROACH_NEAR_M = 0.3
APPROACH_LIMITS = (0.8, 0.3, 0.3, 45.0)
"""An approach's walking command at most: forward, backward and sideways (m/s), turn (deg/s)
(within what the game's walks do without falling)."""
APPROACH_GAIN = 1.5
"""Walking speed per metre from the target point, 1/s."""
APPROACH_TURN_GAIN = 2.0
"""Turn rate per degree from the kick's direction, (deg/s)/deg."""
APPROACH_FAR_M = 1.0
"""Farther than this from the staging point an approach faces where it walks (forwards);
nearer, the kick's direction."""
APPROACH_ROUND_M = 0.5
"""A player in front of the ball (less than :data:`APPROACH_STAGE_M` behind it on the kick's
line) first walks to a point this far behind the ball and this far to the side it is on."""
APPROACH_MAX_S = 20.0
"""An approach that has not arrived after this long (s) gives up: the motion ends unplayed."""
APPROACH_SPOT_CORRECTION: dict[int, tuple[float, float]] = {3: (0.025, 0.013)}
"""Added to a kick's spot for the approach of a Nao type (ahead, left, m), so that the ball
lies at the spot when the prelude is over: where the prelude left it, measured
(``benchmarks/approach_kick.py``'s ``kick_offset_cm_median``, seeds 5000 on). Type 3's torso
moves about 3 cm forward in the prelude after the omnidirectional walk (the others' 1–1.5 cm,
about what the walk's stop leaves in front): its ball lay 2.5 cm nearer and 1.3 cm right of the
spot (with the corrected approach 0.4 cm). The other types' medians are within 1 cm of it
(uncorrected). The prelude's move depends on how the walk stops: measure again after changing
a type's walk."""


class Approach:
    """Steers a walking robot to the pose from which a ball lies at ``spot`` (ahead, left of the
    torso's centre in its heading frame, m) with the robot facing ``direction`` (world, rad):
    round the ball if it is in front of it, to a staging point :data:`APPROACH_STAGE_M`
    behind the pose, then slowly onto the pose (:data:`APPROACH_TOLERANCE`). The pose follows
    the ball if it moves. Measured with the omnidirectional ``walk`` on the default engine
    (``benchmarks/approach_kick.py``): the ball within ~1–2 cm of the spot when it arrives."""

    def __init__(self, spot: tuple[float, float], direction: float) -> None:
        self.spot = (float(spot[0]), float(spot[1]))
        self.direction = float(direction)
        self.line = np.array([math.cos(direction), math.sin(direction)])
        self.left = np.array([-self.line[1], self.line[0]])
        """The unit vector to the left of :attr:`line`."""
        self.staged = False
        """Whether it has reached the staging point (and creeps onto the pose)."""

    def pose(self, ball: np.ndarray) -> np.ndarray:
        """Where the torso's centre must be (world x, y, m) for a ball at ``ball``."""
        return ball[:2] - self.spot[0] * self.line - self.spot[1] * self.left

    def command(
        self, pos: np.ndarray, heading: tuple[float, float], ball: np.ndarray
    ) -> np.ndarray | None:
        """The walking command (forward m/s, left m/s, turn deg/s) for a torso at ``pos``
        (world x, y) with heading ``heading`` (cos, sin) and the ball at ``ball``; ``None``
        once the robot is at the pose."""
        target = self.pose(ball)
        if not self.staged:
            target = target - APPROACH_STAGE_M * self.line
            rel = pos[:2] - ball[:2]
            beside = float(np.dot(rel, self.left))
            behind = -float(np.dot(rel, self.line))
            if behind < APPROACH_STAGE_M and abs(beside) < APPROACH_ROUND_M:  # round the ball
                side = 1.0 if beside >= 0.0 else -1.0
                target = ball[:2] - APPROACH_ROUND_M * (self.line - side * self.left)
        d = target - pos[:2]
        dist = float(np.hypot(*d))
        error = turn_to_deg(heading, self.direction)
        staged = dist < APPROACH_STAGE_TOLERANCE[0] and abs(error) < APPROACH_STAGE_TOLERANCE[1]
        if not self.staged and staged:
            self.staged = True
            return self.command(pos, heading, ball)
        if self.staged and dist < APPROACH_TOLERANCE[0] and abs(error) < APPROACH_TOLERANCE[1]:
            return None
        if not self.staged and dist > APPROACH_FAR_M:  # far: face where it walks
            error = turn_to_deg(heading, math.atan2(d[1], d[0]))
        top = 1.0 if not self.staged and dist > APPROACH_NEAR_M else APPROACH_CREEP
        forward, left = in_heading_frame(heading, d[0], d[1])
        fwd_max, back_max, side_max, turn_max = APPROACH_LIMITS
        command = np.array(
            [
                np.clip(APPROACH_GAIN * forward, -back_max * top, fwd_max * top),
                np.clip(APPROACH_GAIN * left, -side_max * top, side_max * top),
                np.clip(APPROACH_TURN_GAIN * error, -turn_max, turn_max),
            ]
        )
        most = float(np.max(np.abs(command[:2])))
        if self.staged and dist >= APPROACH_TOLERANCE[0] and 0.0 < most < APPROACH_CREEP_MIN_MPS:
            command[:2] *= APPROACH_CREEP_MIN_MPS / most
        return command


APPROACH_LANDINGS_FILE = "approach_kick_landings.json"


@functools.cache
def approach_landings() -> dict[int, dict[str, np.ndarray]]:
    """Where each kick of the library lands after an approach (``approach-kick`` with that
    kick), by Nao type and kick (:attr:`CommandedKick.key`): rows of (distance m, direction deg
    from the player's heading, 1.0 if it was down 1 s later else 0.0), measured by
    ``python benchmarks/approach_kick.py --write-landings``."""
    text = resources.files("robocup_gym.data").joinpath(APPROACH_LANDINGS_FILE).read_text()
    return {
        int(t): {key: np.asarray(rows, dtype=float) for key, rows in by_kick.items()}
        for t, by_kick in json.loads(text)["landings"].items()
    }


def approach_kick_choice(distance_m: float, robot_type: int) -> tuple[CommandedKick, float]:
    """The kick ``approach-kick`` plays for a distance on a Nao type, and the direction its
    landings go from the player's heading (deg; the player faces that much to the right of the
    command's direction): of the library's kicks made for the type, the one whose landings
    after an approach (:func:`approach_landings`) miss the distance least, with their spread
    about their median direction and their falls
    (:func:`~robocup_gym.envs.tasks.commanded_kicks.landing_cost`); the player turns to where a
    kick goes, so every kick of the library serves every direction.

    Raises:
        ValueError: a distance that is not a positive finite number, or not a Nao type.
    """
    if not (math.isfinite(distance_m) and distance_m > 0.0):
        raise ValueError(f"a kick's distance must be a positive finite number, got {distance_m!r}")
    measured = approach_landings().get(robot_type)
    if measured is None:
        raise ValueError(f"approach kicks exist for Nao types 0-4, not {robot_type!r}")
    kicks = [k for k in kick_library() if robot_type in k.robot_types and k.key in measured]
    rows = np.stack([measured[k.key] for k in kicks])
    goes = np.median(rows[..., 1], axis=-1)
    best = int(np.argmin(landing_cost(rows, distance_m, goes)))
    return kicks[best], float(goes[best])


class ApproachKick:
    """``approach-kick``: walk to the ball (:class:`Approach`) so that a kick sends it
    ``direction_deg`` from the heading the player has when it starts, then play the kick (after
    ``kick-to``'s prelude): by default the kick :func:`approach_kick_choice` chooses for
    ``distance_m``, the player facing where its landings go. It needs the player's ball and
    pose (the perception's ``ground_truth``: the world's in-process, a player's estimate on a
    server); without them, or after :data:`APPROACH_MAX_S` without arriving, it ends unplayed
    (``gave_up``).

    Args:
        kick: Play this kick of the library instead, the player facing the command's
            direction (to measure where it lands).
    """

    def __init__(
        self,
        robot_type: int,
        distance_m: float,
        direction_deg: float,
        kick: CommandedKick | None = None,
    ) -> None:
        goes = 0.0
        if kick is None:
            kick, goes = approach_kick_choice(distance_m, robot_type)
        self.kick = kick
        self.kick_spot = _from_torso(kick.ball_spot)
        """Where the kick wants the ball when it starts (ahead, left of the torso, m)."""
        ahead, left = APPROACH_SPOT_CORRECTION.get(robot_type, (0.0, 0.0))
        self.spot = (self.kick_spot[0] + ahead, self.kick_spot[1] + left)
        """Where the approach brings the ball (ahead, left of the torso, m): the kick's spot,
        corrected for what the prelude does on the player's type
        (:data:`APPROACH_SPOT_CORRECTION`)."""
        self.direction_deg = float(direction_deg) - goes
        """Where the player faces, deg from its heading at the start."""
        self._kick = KeyframeMotion(robot_type, kick.keyframes_for(robot_type))
        self._approach: Approach | None = None
        self.arrived = False
        self.gave_up = False
        self.walked = 0
        """Cycles walked so far."""

    def walk_command(self, p: Perception) -> np.ndarray | None:
        gt = p.ground_truth
        if gt is None or self.walked * CYCLE_S >= APPROACH_MAX_S:
            self.gave_up = True
            return np.zeros(3)
        heading = heading_frame(gt.torso_quat)
        if self._approach is None:
            ahead = math.atan2(heading[1], heading[0])
            self._approach = Approach(self.spot, ahead + math.radians(self.direction_deg))
        command = self._approach.command(gt.torso_pos, heading, gt.ball_pos)
        if command is None:
            self.arrived = True
            return None
        self.walked += 1
        return command

    def command(self, p: Perception) -> np.ndarray:
        return self._kick.command(p)

    @property
    def done(self) -> bool:
        return self.gave_up or (self.arrived and self._kick.done)


def approach_kick(robot_type: int, distance: float, direction: float) -> ApproachKick:
    """The ``approach-kick`` motion for its action values (as ``kick-to``'s:
    :func:`kick_to_command`, the direction from the player's heading when it starts)."""
    return ApproachKick(robot_type, *kick_to_command(distance, direction))


register_motion_skill(
    "approach-kick",
    approach_kick,
    "walk to the ball, then the kick of the library that carries a distance (2-10 m) best after "
    "an approach, facing so that it goes in a direction (±45° of the heading at the start); "
    "best with the omnidirectional walk",
    parameters=("distance", "direction"),
)

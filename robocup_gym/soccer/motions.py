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
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from robocup_gym.robot.nao import nao_model
from robocup_gym.sim.fidelity import load_data
from robocup_gym.types import Perception

__all__ = [
    "KICK_CYCLES",
    "KICK_FOLLOW_THROUGH_CYCLES",
    "RESERVED_NAMES",
    "WALK_ACTION_LABELS",
    "Motion",
    "MotionSkill",
    "ScriptedMotion",
    "kick_sequence",
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

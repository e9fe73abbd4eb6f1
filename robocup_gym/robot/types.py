"""The heterogeneous Nao robot types 0–4 of rcssserver3d 0.7.3 (``naorobottypes.rb``).

Everything not listed here is identical for all types. Lengths in m, speeds in rad/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from robocup_gym.types import is_integer

#: Max speed of every hinge except the ankle joints: 351.77 °/s in rad/s, computed in the rsg
#: with π = 3.14159265.
DEFAULT_MAX_SPEED = 3.14159265 * 351.77 / 180.0


@dataclass(frozen=True)
class RobotType:
    """Parameters of one heterogeneous robot type (reference §3.2)."""

    index: int
    description: str
    hip1_rel_torso_x: float = 0.055
    """x of the hip joints from the torso centre (× ±1 for right/left), m."""
    hip1_rel_torso_z: float = -0.115
    thigh_rel_hip2_z: float = -0.04
    ankle_rel_shank_z: float = -0.055
    elbow_rel_upperarm_y: float = 0.07
    ankle_pitch_max_speed: float = 6.1395
    """Max speed of ``lle5``/``rle5`` (rad/s)."""
    ankle_roll_max_speed: float = 6.1395
    """Max speed of ``lle6``/``rle6`` (rad/s)."""
    toe_length: float | None = None
    """Length of the toe box (type 4 only), m; ``None`` for robots without toes."""

    @property
    def has_toes(self) -> bool:
        """True for type 4 (extra joints ``lle7``/``rle7`` and FRPs ``lf1``/``rf1``)."""
        return self.toe_length is not None


ROBOT_TYPES: tuple[RobotType, ...] = (
    RobotType(0, "standard"),
    RobotType(
        1,
        "longer legs and arms",
        thigh_rel_hip2_z=-0.05832,
        ankle_rel_shank_z=-0.07332,
        elbow_rel_upperarm_y=0.10664,
    ),
    RobotType(
        2,
        "faster ankle pitch, slower ankle roll",
        ankle_pitch_max_speed=8.80667,
        ankle_roll_max_speed=3.47234,
    ),
    RobotType(
        3,
        "longer legs and arms, wider hips",
        hip1_rel_torso_x=0.072954143,
        thigh_rel_hip2_z=-0.067868424,
        ankle_rel_shank_z=-0.082868424,
        elbow_rel_upperarm_y=0.125736848,
    ),
    RobotType(4, "toes", toe_length=0.035517656),
)

TYPE_NUMBERS: tuple[int, ...] = tuple(t.index for t in ROBOT_TYPES)
"""The Nao's robot type numbers, 0–4."""


def is_type_number(value: object) -> bool:
    """Whether ``value`` is a Nao type number: an integer (Python's or NumPy's, not a bool)
    among :data:`TYPE_NUMBERS`."""
    return is_integer(value) and int(value) in TYPE_NUMBERS


def robot_type(index: int) -> RobotType:
    """The :class:`RobotType` with number ``index`` (0–4).

    Raises:
        ValueError: for a number outside 0–4.
    """
    if isinstance(index, bool) or not isinstance(index, int | float) or index not in TYPE_NUMBERS:
        raise ValueError(f"robot type must be one of 0, 1, 2, 3, 4, got {index!r}")
    return ROBOT_TYPES[int(index)]


assert math.isclose(DEFAULT_MAX_SPEED, 6.13954, abs_tol=1e-5)

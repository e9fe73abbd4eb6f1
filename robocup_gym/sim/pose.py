"""Placing a robot, whatever the engine: the torso quaternion of a heading and joint angles by
name, in the units the worlds' ``place_robot`` takes (degrees; quaternions as (w, x, y, z))."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from robocup_gym.robot.nao import NaoModel

__all__ = ["heading_to_quat", "joint_angles_array", "joint_index", "placement_quat", "yaw_quat"]


def yaw_quat(yaw_rad: float) -> np.ndarray:
    """Quaternion (w, x, y, z) of a rotation by ``yaw_rad`` about world z."""
    return np.array([math.cos(yaw_rad / 2), 0.0, 0.0, math.sin(yaw_rad / 2)])


def heading_to_quat(heading_deg: float) -> np.ndarray:
    """Torso orientation for a robot whose forward (+y of the torso) points at ``heading_deg``
    (0 = world +x, counter-clockwise positive)."""
    return yaw_quat(math.radians(heading_deg - 90.0))


def placement_quat(
    x: float, y: float, z: float | None, heading_deg: float, quat: object | None
) -> np.ndarray:
    """The unit torso orientation a ``place_robot`` asks for (``quat`` (w, x, y, z), else
    upright facing ``heading_deg``), after checking that every number of the placement is
    finite (``z`` may be ``None``): both engines' ``place_robot`` check here, before they change
    anything.

    Raises:
        ValueError: naming the value that is not finite, or a quaternion that is not 4 finite
            numbers (or is zero).
    """
    for name, v in (("x", x), ("y", y), ("z", z), ("heading_deg", heading_deg)):
        if v is not None and not math.isfinite(v):
            raise ValueError(f"robot placement {name} must be finite, got {v}")
    q = np.asarray(quat, float) if quat is not None else heading_to_quat(heading_deg)
    if q.shape != (4,) or not np.all(np.isfinite(q)) or np.linalg.norm(q) == 0:
        raise ValueError(f"quat must be 4 finite numbers, got {quat!r}")
    return q / np.linalg.norm(q)


def joint_index(model: NaoModel, name: str) -> int:
    """Canonical index of the joint called ``name`` (effector, perceptor or Nao-style name).

    Raises:
        KeyError: naming the robot type and listing the valid effector names.
    """
    try:
        return model.joint_index[name]
    except KeyError:
        raise KeyError(
            f"unknown joint {name!r} for robot type {model.robot_type.index}; valid effector "
            f"names: {', '.join(model.effector_names)}"
        ) from None


def joint_angles_array(model: NaoModel, angles: Mapping[str, float] | np.ndarray) -> np.ndarray:
    """Joint angles (degrees) in canonical order, from ``{name: deg}`` (others 0) or an array.

    Raises:
        KeyError: an unknown joint name.
        ValueError: an array of the wrong shape or an angle that is not finite (naming it).
    """
    n = len(model.joints)
    if isinstance(angles, Mapping):
        out = np.zeros(n)
        for name, v in angles.items():
            out[joint_index(model, name)] = float(v)
    else:
        out = np.asarray(angles, float)
        if out.shape != (n,):
            raise ValueError(f"joint angle array must have shape ({n},), got {out.shape}")
    bad = ~np.isfinite(out)
    if bad.any():
        raise ValueError(
            f"joint angle of {model.effector_names[int(np.argmax(bad))]} is not finite"
        )
    return out

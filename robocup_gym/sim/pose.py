"""Placing a robot, whatever the engine: the torso quaternion of a heading and joint angles by
name, in the units the worlds' ``place_robot`` takes (degrees; quaternions as (w, x, y, z)), and
SimSpark's rigid moves of a robot's bodies (:func:`rigid_move`, what the trainer's ``move``,
``pos`` and ``rot``, ``beam`` and the referee's repositioning do on rcssserver3d)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from robocup_gym.robot.nao import NaoModel
from robocup_gym.sim.kinematics import resting_torso_height
from robocup_gym.sim.rotations import yaw_quat
from robocup_gym.types import float_array, is_number

__all__ = [
    "ball_placement",
    "heading_to_quat",
    "joint_angles_array",
    "joint_index",
    "placement_quat",
    "resting_torso_height",
    "rigid_move",
    "yaw_quat",
]


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
        if v is not None and not (is_number(v) and math.isfinite(v)):
            raise ValueError(f"robot placement {name} must be a finite number, got {v!r}")
    q = np.asarray(quat, float) if quat is not None else heading_to_quat(heading_deg)
    if q.shape != (4,) or not np.all(np.isfinite(q)) or np.linalg.norm(q) == 0:
        raise ValueError(f"quat must be 4 finite numbers, got {quat!r}")
    return q / np.linalg.norm(q)


def ball_placement(
    pos: object, vel: object, angular_vel: object
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ball placement a ``place_ball`` asks for, as arrays: ``pos`` (x, y[, z]) m, ``vel``
    m/s and ``angular_vel`` rad/s (3 each); both engines' ``place_ball`` check here, before
    they change anything.

    Raises:
        ValueError: naming what is not 2 or 3 (the position) or 3 (each velocity) finite
            numbers.
    """
    out = []
    for name, value, sizes in (
        ("ball position", pos, (2, 3)),
        ("ball velocity", vel, (3,)),
        ("ball angular velocity", angular_vel, (3,)),
    ):
        a = float_array(value)
        if a is None or a.ndim != 1 or len(a) not in sizes or not np.isfinite(a).all():
            want = " or ".join(map(str, sizes))
            raise ValueError(f"{name} must be {want} finite numbers, got {value!r}")
        out.append(a)
    return out[0], out[1], out[2]


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


_F32 = np.float32


def _rz(angle_deg: float) -> np.ndarray:
    """salt's ``Matrix::RotationZ(gDegToRad(angle))`` in single precision (the angle is a float;
    ``gCos``/``gSin`` round the double cosine and sine)."""
    a = _F32(float(_F32(angle_deg)) * (math.pi / 180.0))
    c, s = _F32(math.cos(float(a))), _F32(math.sin(float(a)))
    z = _F32(0.0)
    return np.array([[c, -s, z], [s, c, z], [z, z, _F32(1.0)]], dtype=_F32)


def _rxyz(rot_deg: tuple[float, float, float]) -> np.ndarray:
    """salt's identity matrix turned by ``RotateX``, ``RotateY``, ``RotateZ`` in that order
    (each multiplies from the right), single precision."""
    m = np.eye(3, dtype=_F32)
    for axis, angle in zip((0, 1, 2), rot_deg, strict=True):
        a = _F32(float(_F32(angle)) * (math.pi / 180.0))
        c, s = _F32(math.cos(float(a))), _F32(math.sin(float(a)))
        i, j = [(1, 2), (0, 2), (0, 1)][axis]
        sign = _F32(-1.0) if axis == 1 else _F32(1.0)  # RotateY's sine enters the other way
        ci, cj = m[:, i].copy(), m[:, j].copy()
        m[:, i] = c * ci + sign * s * cj
        m[:, j] = -sign * s * ci + c * cj
    return m


def _matmul3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b`` for 3×3 single-precision matrices, summed in salt's order (k = 0, 1, 2)."""
    return (a[:, 0:1] * b[0:1, :] + a[:, 1:2] * b[1:2, :]) + a[:, 2:3] * b[2:3, :]


def rigid_move(
    positions: np.ndarray,
    rotations: np.ndarray,
    pos: Sequence[float] | None = None,
    *,
    heading_deg: float | None = None,
    rot_deg: Sequence[float] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """A robot's bodies moved rigidly as rcssserver3d moves them, in its single precision.

    ``positions`` ``(n, 3)`` and ``rotations`` ``(n, 3, 3)`` are the bodies' centres and
    orientations (world, m; columns = body axes), the torso first. The whole robot keeps its
    shape as the physics left it (joint angles, and the joints' small constraint errors):

    * ``pos`` alone (``SoccerBase::MoveAgent``, the trainer's ``pos``): every body translated so
      that the torso centre is at ``pos``; orientations untouched;
    * ``pos`` and ``heading_deg`` (``MoveAndRotateAgent``: the trainer's ``move``, ``beam``, the
      referee's repositioning): turned about the torso so that the torso stands upright facing
      ``heading_deg`` (0 = world +x, counter-clockwise), the torso centre at ``pos``;
    * ``rot_deg`` (``RotateAgent``, the SPL fork's ``rot``): turned about the torso centre so
      that the torso's orientation is x-, then y-, then z-rotations by these angles (degrees).

    SimSpark does this arithmetic with ``float`` (salt's ``Matrix`` and ``Vector3f``): positions
    and changed orientations come back rounded as its do. Velocities are for the caller to zero.

    Returns:
        ``(positions, rotations)``, new arrays (float64).
    """
    p = np.asarray(positions, float).astype(_F32)
    r = np.asarray(rotations, float).astype(_F32)
    agent = p[0].copy()
    if heading_deg is None and rot_deg is None:
        if pos is None:
            raise ValueError("rigid_move needs pos, heading_deg or rot_deg")
        target = np.asarray(pos, float).astype(_F32)
        return (target + (p - agent)).astype(float), np.asarray(rotations, float).copy()
    turn = _rz(float(heading_deg) - 90.0) if heading_deg is not None else _rxyz(tuple(rot_deg))
    mat = _matmul3(turn, r[0].T)
    target = agent if pos is None else np.asarray(pos, float).astype(_F32)
    d = p - agent
    rotated = (d[:, 0:1] * mat[:, 0] + d[:, 1:2] * mat[:, 1]) + d[:, 2:3] * mat[:, 2]
    new_r = np.stack([_matmul3(mat, ri) for ri in r])
    return (target + rotated).astype(float), new_r.astype(float)

"""Rotations, one place: quaternions ``(w, x, y, z)`` and 3×3 matrices (columns = the rotated
frame's axes), computed by MuJoCo's own functions (``mju_*``), so that every part of the package
turns things the same way to the last bit."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = ["axis_angle_quat", "matrix_to_quat", "quat_multiply", "quat_to_matrix", "yaw_quat"]


def _mujoco():
    import mujoco  # not at import time: importing mujoco fails on a bad MUJOCO_GL

    return mujoco


def quat_to_matrix(quat: Sequence[float]) -> np.ndarray:
    """The 3×3 matrix of a unit quaternion (``mju_quat2Mat``)."""
    m = np.zeros(9)
    _mujoco().mju_quat2Mat(m, np.asarray(quat, dtype=float))
    return m.reshape(3, 3)


def matrix_to_quat(matrix: np.ndarray) -> np.ndarray:
    """The unit quaternion of a rotation matrix, ``w >= 0`` (``mju_mat2Quat``, normalised: a
    matrix read off the wire with 6 significant digits is not quite orthonormal)."""
    q = np.zeros(4)
    _mujoco().mju_mat2Quat(q, np.ascontiguousarray(matrix, dtype=float).ravel())
    q /= np.linalg.norm(q)
    return -q if q[0] < 0 else q


def axis_angle_quat(axis: Sequence[float], angle_rad: float) -> np.ndarray:
    """The unit quaternion of a rotation by ``angle_rad`` about unit ``axis``
    (``mju_axisAngle2Quat``)."""
    q = np.zeros(4)
    _mujoco().mju_axisAngle2Quat(q, np.asarray(axis, dtype=float), float(angle_rad))
    return q


def quat_multiply(a: Sequence[float], b: Sequence[float]) -> np.ndarray:
    """The rotation ``b`` followed by ``a`` (``mju_mulQuat``: ``a · b``)."""
    q = np.zeros(4)
    _mujoco().mju_mulQuat(q, np.asarray(a, dtype=float), np.asarray(b, dtype=float))
    return q


def yaw_quat(yaw_rad: float) -> np.ndarray:
    """The quaternion of a rotation by ``yaw_rad`` about world z."""
    return np.array([math.cos(yaw_rad / 2), 0.0, 0.0, math.sin(yaw_rad / 2)])

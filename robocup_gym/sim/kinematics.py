"""The Nao's geometry, from MuJoCo's kinematics of its model (no physics runs)."""

from __future__ import annotations

import functools
import threading
from collections.abc import Sequence

import numpy as np

from robocup_gym.robot.nao import nao_model

__all__ = ["resting_height_and_feet", "resting_torso_height"]

_KINEMATICS_WORLDS: dict[int, object] = {}
"""One MuJoCo world per Nao type, for :func:`resting_torso_height` (kinematics only)."""
_KINEMATICS_LOCK = threading.Lock()
"""The worlds are shared by every thread: one thread's placing must not meet another's reading
(a team's players on a server, two teams of a match in one process: a player's odometry read
the other team's joints)."""


def _placed(robot_type: int, joint_angles_deg: np.ndarray, quat: Sequence[float] | None):
    """The kinematics world of ``robot_type`` with the robot placed (hold the lock)."""
    world = _KINEMATICS_WORLDS.get(robot_type)
    if world is None:
        # not at import time: importing mujoco fails on a bad MUJOCO_GL, which must not stop
        # the package from loading (it says so where MuJoCo draws)
        from robocup_gym.sim.engines.mujoco.world import World

        world = _KINEMATICS_WORLDS[robot_type] = World([robot_type])
    world.place_robot(  # type: ignore[attr-defined]
        0, 0.0, 0.0, joint_angles_deg=np.asarray(joint_angles_deg, float), quat=quat, forward=False
    )
    return world


def resting_torso_height(
    robot_type: int, joint_angles_deg: np.ndarray, quat: Sequence[float] | None = None
) -> float:
    """Torso centre height (m) of a Nao of ``robot_type`` with these joint angles (canonical
    order) and torso orientation (``quat`` (w, x, y, z); ``None``: upright) when its lowest point
    rests on the ground 1 mm deep (ODE's surface layer), as ``place_robot(z=None)`` puts it:
    the kinematics alone, read off a MuJoCo world (no physics runs)."""
    with _KINEMATICS_LOCK:
        world = _placed(robot_type, joint_angles_deg, quat)
        return float(world.torso_position(0)[2])  # type: ignore[attr-defined]


def resting_height_and_feet(
    robot_type: int, joint_angles_deg: np.ndarray, quat: Sequence[float] | None = None
) -> tuple[float, np.ndarray]:
    """:func:`resting_torso_height`, and where the feet are: the left and the right foot's
    centre relative to the torso centre, torso frame, m (shape (2, 3)), for the same joint
    angles (the orientation does not change them)."""
    with _KINEMATICS_LOCK:
        world = _placed(robot_type, joint_angles_deg, quat)
        height = float(world.torso_position(0)[2])  # type: ignore[attr-defined]
        pos, rot = world.body_frames(0)  # type: ignore[attr-defined]
        return height, (pos[_feet(robot_type)] - pos[0]) @ rot[0]


@functools.cache
def _feet(robot_type: int) -> list[int]:
    """The left and the right foot's places among the bodies (``body_frames``' order, the
    model's, torso first)."""
    names = [b.name for b in nao_model(robot_type).bodies]
    return [names.index("lfoot"), names.index("rfoot")]

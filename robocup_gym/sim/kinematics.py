"""The Nao's geometry, from MuJoCo's kinematics of its model (no physics runs)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["resting_height_and_feet", "resting_torso_height"]

_KINEMATICS_WORLDS: dict[int, object] = {}
"""One MuJoCo world per Nao type, for :func:`resting_torso_height` (kinematics only)."""


def resting_torso_height(
    robot_type: int, joint_angles_deg: np.ndarray, quat: Sequence[float] | None = None
) -> float:
    """Torso centre height (m) of a Nao of ``robot_type`` with these joint angles (canonical
    order) and torso orientation (``quat`` (w, x, y, z); ``None``: upright) when its lowest point
    rests on the ground 1 mm deep (ODE's surface layer), as ``place_robot(z=None)`` puts it:
    the kinematics alone, read off a MuJoCo world (no physics runs)."""
    world = _KINEMATICS_WORLDS.get(robot_type)
    if world is None:
        # not at import time: importing mujoco fails on a bad MUJOCO_GL, which must not stop
        # the package from loading (it says so where MuJoCo draws)
        from robocup_gym.sim.engines.mujoco.world import World

        world = _KINEMATICS_WORLDS[robot_type] = World([robot_type])
    world.place_robot(  # type: ignore[attr-defined]
        0, 0.0, 0.0, joint_angles_deg=np.asarray(joint_angles_deg, float), quat=quat, forward=False
    )
    return float(world.torso_position(0)[2])  # type: ignore[attr-defined]


def resting_height_and_feet(
    robot_type: int, joint_angles_deg: np.ndarray, quat: Sequence[float] | None = None
) -> tuple[float, np.ndarray]:
    """:func:`resting_torso_height`, and where the feet are: the left and the right foot's
    centre relative to the torso centre, world-aligned axes, m (shape (2, 3)), for the same
    joint angles and torso orientation."""
    height = resting_torso_height(robot_type, joint_angles_deg, quat)
    world = _KINEMATICS_WORLDS[robot_type]
    r = world.robot(0)  # type: ignore[attr-defined]
    xpos = world.data.xpos  # type: ignore[attr-defined]
    torso = xpos[r.torso_body]
    from robocup_gym.sim.vision import PLAYER_PARTS

    left, right = (r.part_bodies[PLAYER_PARTS.index(f)] for f in ("lfoot", "rfoot"))
    feet = np.array([xpos[left] - torso, xpos[right] - torso])
    return height, feet

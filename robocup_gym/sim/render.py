"""Pictures of a world, whatever its engine: MuJoCo's renderer draws the scene.

The MuJoCo world is drawn directly. A world on another engine (ODE) is shown through a MuJoCo
world of the same robots posed like it (:class:`ScenePoser`: each torso's position and
orientation, every joint angle, the ball), so videos and ``render()`` look the same on both.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["FollowCamera", "ScenePoser"]


class ScenePoser:
    """A MuJoCo :class:`~robocup_gym.sim.engines.mujoco.world.World` with ``robot_types``, posed on
    demand like
    another world (anything with ``torso_position``, ``torso_quat``, ``joint_angles_deg`` and
    ``ball_position``)."""

    def __init__(self, robot_types: Sequence[int]) -> None:
        from robocup_gym.sim.engines.mujoco.world import World

        self.scene = World(list(robot_types), compiled=False)

    def pose(self, world: Any):
        """The scene world showing ``world``'s current state (positions only)."""
        import mujoco

        scene = self.scene
        for i in range(scene.n_robots):
            x, y, z = world.torso_position(i)
            scene.place_robot(
                i,
                float(x),
                float(y),
                z=float(z),
                quat=world.torso_quat(i),
                joint_angles_deg=world.joint_angles_deg(i),
                forward=False,
            )
        scene.place_ball(world.ball_position(), forward=False)
        mujoco.mj_kinematics(scene.model, scene.data)
        return scene


class FollowCamera:
    """Renders a MuJoCo world from a camera that follows robot 0 (the environments'
    ``render()``), or the ball with ``follow="ball"`` (a game seen from the side); needs an
    OpenGL context, e.g. ``MUJOCO_GL=egl`` on a headless machine. ``distance`` m, ``elevation``
    and ``azimuth`` deg."""

    def __init__(
        self,
        distance: float = 1.6,
        elevation: float = -20.0,
        azimuth: float = 135.0,
        follow: str = "robot",
    ):
        if follow not in ("robot", "ball"):
            raise ValueError(f"follow must be 'robot' or 'ball', got {follow!r}")
        self.view = (distance, elevation, azimuth)
        self.follow = follow
        self._renderer: Any = None
        self._camera: Any = None

    def render(self, world: Any, width: int, height: int) -> np.ndarray:
        """RGB image ``(height, width, 3)`` of MuJoCo world ``world``."""
        import mujoco

        r = self._renderer
        if r is None or (r.width, r.height) != (width, height):
            self.close()
            self._renderer = mujoco.Renderer(world.model, height, width)
            self._camera = mujoco.MjvCamera()
            self._camera.distance, self._camera.elevation, self._camera.azimuth = self.view
        target = world.ball_position() if self.follow == "ball" else world.torso_position(0)
        self._camera.lookat[:] = np.asarray(target) * (1.0, 1.0, 0.0) + (0.0, 0.0, 0.25)
        self._renderer.update_scene(world.data, self._camera)
        return self._renderer.render().copy()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

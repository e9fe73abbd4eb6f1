"""The embedded SimSpark world on MuJoCo (:class:`robocup_gym.sim.engines.mujoco.world.World`) as a
backend.

Resets are instant: the robot (joint angles included) and the ball are teleported with
:meth:`World.place_robot` / :meth:`World.place_ball`; no warm-up cycles, no controller loop.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from robocup_gym.backends.base import Backend, BackendDivergedError, RobotPose
from robocup_gym.robot.nao import NaoModel
from robocup_gym.sim.engines.mujoco.world import SimulationDivergedError, World
from robocup_gym.sim.physics import PhysicsConfig
from robocup_gym.sim.render import FollowCamera
from robocup_gym.sim.vision import VisionConfig
from robocup_gym.types import AgentCommand, Perception

__all__ = ["MujocoBackend"]


class MujocoBackend(Backend):
    """One learning robot (index 0, left team) and the ball in the embedded world.

    Args:
        robot_type: Nao type 0–4.
        seed: Seed of the world's vision noise and calibration offsets.
        vision: Compute the ``See`` perceptor (every ``vision_config.interval``-th cycle, and
            once at every reset). Off by default because it is the costliest perceptor.
        vision_config: Noise, view cone, interval and ground-truth extensions of ``See``.
        physics: MuJoCo settings of the world.
        dead_time_cycles: Cycles between a command and its effect (1 as on rcssserver3d).
    """

    name = "mujoco"

    def __init__(
        self,
        *,
        robot_type: int = 0,
        seed: int | None = None,
        vision: bool = False,
        vision_config: VisionConfig | None = None,
        physics: PhysicsConfig | None = None,
        dead_time_cycles: int = 1,
    ) -> None:
        super().__init__(robot_type=robot_type, seed=seed, vision=vision)
        self.world = World(
            [robot_type],
            physics=physics,
            dead_time_cycles=dead_time_cycles,
            vision=vision_config,
            seed=seed,
        )
        self._model = self.world.robots[0].model
        self._diverged = False
        self._camera = FollowCamera()

    @property
    def robot_model(self) -> NaoModel:
        return self._model

    # ------------------------------------------------------------------ episode control
    def reset_episode(
        self,
        pose: RobotPose,
        ball_pos: Sequence[float],
        ball_vel: Sequence[float] = (0.0, 0.0, 0.0),
        *,
        play_mode: str = "PlayOn",
        seed: int | None = None,
    ) -> Perception:
        w = self.world
        if seed is not None or self._diverged:
            # full reset: clears a diverged state, re-seeds noise and calibration
            w.reset(seed=seed)
            self._diverged = False
        # An episode depends only on its start state: place_robot forgets the solver warm start
        # and restores the robot's motor rows (relaxed at joint stops by the last cycle).
        pose.place(w)
        w.place_ball(ball_pos, ball_vel)
        w.set_game(play_mode=play_mode, game_time=0.0)
        return w.perceive(0, vision=self.vision)

    def step(self, command: AgentCommand) -> Perception:
        w = self.world
        try:
            w.step({0: command})
        except SimulationDivergedError as e:
            self._diverged = True
            raise BackendDivergedError(str(e)) from e
        return w.perceive(0, vision=None if self.vision else False)

    def advance(self, cycles: int, command: AgentCommand | None = None) -> Perception:
        if cycles < 1:
            raise ValueError(f"cycles must be >= 1, got {cycles}")
        w = self.world
        try:
            w.step({0: command} if command is not None else None)
            for _ in range(cycles - 1):
                w.step()
        except SimulationDivergedError as e:
            self._diverged = True
            raise BackendDivergedError(str(e)) from e
        return w.perceive(0, vision=None if self.vision else False)

    def set_torso_force(self, force: Sequence[float]) -> None:
        self.world.set_torso_force(0, force)

    # ------------------------------------------------------------------ misc
    def scene_world(self):
        """The MuJoCo world itself (what videos draw)."""
        return self.world

    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """RGB image of the scene from a camera that follows the robot (needs an OpenGL context,
        e.g. ``MUJOCO_GL=egl`` on a headless machine)."""
        return self._camera.render(self.world, width, height)

    def close(self) -> None:
        self._camera.close()

    def describe(self) -> dict[str, Any]:
        d = super().describe()
        d.update(substeps=self.world.substeps, dead_time_cycles=self.world.dead_time_cycles)
        return d

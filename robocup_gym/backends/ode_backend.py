"""The world on SimSpark's physics step on ODE itself
(:class:`robocup_gym.sim.engines.ode.world.OdeWorld`) as a backend: the default engine of the
environments, ``engine="ode"``.

rcssserver3d advances ODE 0.16 once per 20 ms cycle; so does this backend, with the same bodies,
joints, contact handlers and surface mixing, walls and goals, so that what a policy learns here
works on the real server (docs/training.md, *Which engine*). It needs the system library
``libode`` (Debian/Ubuntu: ``apt-get install libode8``; macOS: ``brew install ode``); without
it the backend says so and names ``engine="mujoco"``.

What it has: the robot of any type 0–4, the ball and the field's walls and goals; the hinge
effector's rules and the one-cycle dead time; every perceptor (joint angles, gyro,
accelerometer, the foot force perceptors from ODE's contact feedback as SimSpark computes them,
vision and hearing, :mod:`robocup_gym.sim.senses`) and exact ground truth. What it lacks: the
referee (the play mode is set and kept, the game clock runs). Resets are instant teleports, as
on the MuJoCo backend; ``render()`` and videos draw a MuJoCo scene posed like this world.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from robocup_gym.backends.base import (
    Backend,
    BackendDivergedError,
    BackendNotAvailableError,
    RobotPose,
)
from robocup_gym.robot.nao import NaoModel
from robocup_gym.sim import SimulationDivergedError
from robocup_gym.sim.render import FollowCamera, ScenePoser
from robocup_gym.sim.vision import VisionConfig
from robocup_gym.types import AgentCommand, Perception

__all__ = ["OdeBackend"]


class OdeBackend(Backend):
    """One learning robot and the ball, stepped by ODE 0.16 as rcssserver3d steps them.

    Args:
        robot_type: Nao type 0–4.
        seed: Seed of the vision noise and calibration offsets.
        vision: Compute the ``See`` perceptor (every ``vision_config.interval``-th cycle, and
            once at every reset), as on the MuJoCo backend.
        vision_config: Noise, view cone, interval and ground-truth extensions of ``See``.
        dead_time_cycles: Cycles between a command and its effect (1 as on rcssserver3d).

    Raises:
        BackendNotAvailableError: ``libode`` is missing or unsuitable (the message says how to
            install it and that ``engine="mujoco"`` needs no libode).
    """

    name = "ode"

    def __init__(
        self,
        *,
        robot_type: int = 0,
        seed: int | None = None,
        vision: bool = False,
        vision_config: VisionConfig | None = None,
        dead_time_cycles: int = 1,
    ) -> None:
        super().__init__(robot_type=robot_type, seed=seed, vision=vision)
        from robocup_gym.sim.engines.ode import OdeUnavailableError, OdeWorld

        try:
            self.world = OdeWorld(
                [robot_type], dead_time_cycles=dead_time_cycles, vision=vision_config, seed=seed
            )
        except OdeUnavailableError as exc:
            raise BackendNotAvailableError(
                f"the ODE engine (SimSpark's physics, the default) is not available here: {exc}. "
                "Or choose the MuJoCo engine: engine='mujoco' (--engine mujoco)"
            ) from exc
        self._model = self.world.robots[0].model
        self._poser: ScenePoser | None = None
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
        if seed is not None:
            w.reseed(seed)
        pose.place(w)
        w.place_ball(ball_pos, ball_vel)
        w.sense_contacts()  # the first perception shows the feet loaded, as the world's does
        w.set_game(play_mode=play_mode, game_time=0.0)
        return w.perceive(0, vision=self.vision)

    def step(self, command: AgentCommand) -> Perception:
        return self.advance(1, command)

    def advance(self, cycles: int, command: AgentCommand | None = None) -> Perception:
        """``cycles`` cycles (``command`` in the first; targets are sticky), perceiving only
        after the last one, as the MuJoCo backend does."""
        if cycles < 1:
            raise ValueError(f"cycles must be >= 1, got {cycles}")
        w = self.world
        velocities = command.joint_velocities if command is not None else ()
        try:
            w.step({0: velocities} if len(velocities) else None)
            for _ in range(cycles - 1):
                w.step()
        except SimulationDivergedError as e:
            raise BackendDivergedError(str(e)) from e
        if command is not None and command.say is not None:
            w.say(0, command.say)
        p = w.perceive(0, vision=None if self.vision else False)
        if not (
            np.isfinite(p.ground_truth.torso_pos).all() and np.isfinite(p.joint_angles_deg).all()
        ):
            raise BackendDivergedError(
                f"the ODE world produced a NaN/inf state at t = {p.time:.2f} s"
            )
        return p

    def set_torso_force(self, force: Sequence[float]) -> None:
        self.world.set_torso_force(0, force)

    # ------------------------------------------------------------------ misc
    def scene_world(self):
        """A MuJoCo world posed like this one, for drawing (videos, :meth:`render`)."""
        if self._poser is None:
            self._poser = ScenePoser([self.robot_type])
        return self._poser.pose(self.world)

    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """RGB image of the scene from a camera that follows the robot, drawn by MuJoCo from
        this world's state (needs an OpenGL context, e.g. ``MUJOCO_GL=egl`` when headless)."""
        return self._camera.render(self.scene_world(), width, height)

    def close(self) -> None:
        self._camera.close()
        self.world.close()

    def describe(self) -> dict[str, Any]:
        d = super().describe()
        d.update(dead_time_cycles=self.world.dead_time_cycles, engine="ODE 0.16 (libode)")
        return d

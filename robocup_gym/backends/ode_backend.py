"""SimSpark's physics step on ODE itself (:class:`robocup_gym.sim.ode.world.OdeWorld`) as a
backend: run a policy closed-loop on the engine rcssserver3d runs on.

The embedded MuJoCo world is the fast simulator (~4× the environment steps per second, PPO
twice as fast end to end). This backend answers whether what was learnt there works under
ODE's own solver, contacts, joint stops and motor rules: ``robocup-gym eval RUN --backend ode``
evaluates a trained policy here. It is also a training backend for policies that must work on
rcssserver3d (``robocup-gym train TASK --backend ode``: 1M PPO steps in ~13 min on 2 cores),
since session 9 found that learnt kicks do not yet carry over between the two engines
(docs/training.md). It needs the system library ``libode`` (Debian/Ubuntu: ``apt-get install
libode8``).

What it has: the robot of any type 0–4 and the ball on the ground, the hinge effector's rules
and the one-cycle dead time, and the perceptors a kick policy reads. These are joint angles,
gyro, accelerometer and the foot force perceptors (from ODE's contact feedback, as SimSpark
computes them), plus exact ground truth. What it lacks: vision, hearing, the referee (the
play mode is set and kept, the game clock runs), and the field's walls and goals. Resets are
instant teleports, as on the MuJoCo backend.
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
from robocup_gym.sim.world import PAUSED_MODES
from robocup_gym.types import AgentCommand, GameState, GroundTruth, Perception

__all__ = ["OdeBackend"]


class OdeBackend(Backend):
    """One learning robot and the ball, stepped by ODE 0.16 as rcssserver3d steps them.

    Args:
        robot_type: Nao type 0–4.
        seed: Accepted for interface compatibility; the backend has no randomness.
        vision: Must be False: the backend has no ``See`` perceptor.
        dead_time_cycles: Cycles between a command and its effect (1 as on rcssserver3d).

    Raises:
        BackendNotAvailableError: ``libode`` is missing (the message says how to install it),
            or vision was asked for.
    """

    name = "ode"

    def __init__(
        self,
        *,
        robot_type: int = 0,
        seed: int | None = None,
        vision: bool = False,
        dead_time_cycles: int = 1,
    ) -> None:
        super().__init__(robot_type=robot_type, seed=seed, vision=vision)
        if vision:
            raise BackendNotAvailableError(
                "the 'ode' backend has no vision (See) perceptor; use observations without "
                "vision, or the 'mujoco' or 'rcssserver3d' backend"
            )
        from robocup_gym.sim.ode import OdeUnavailableError, OdeWorld

        try:
            self.world = OdeWorld([robot_type], dead_time_cycles=dead_time_cycles)
        except OdeUnavailableError as exc:
            raise BackendNotAvailableError(f"backend 'ode' is not available here: {exc}") from exc
        self._model = self.world.robots[0].model
        self._game = GameState(play_mode="PlayOn")

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
        w.place_robot(
            0,
            pose.x,
            pose.y,
            heading_deg=pose.heading_deg,
            z=pose.z,
            joint_angles_deg=pose.joint_angles_deg,
        )
        w.place_ball(ball_pos, ball_vel)
        w.sense_contacts()  # the first perception shows the feet loaded, as the world's does
        self._game = GameState(play_mode=play_mode, game_time=0.0)
        return self._perceive()

    def step(self, command: AgentCommand) -> Perception:
        velocities = command.joint_velocities
        self.world.step({0: velocities} if len(velocities) else None)
        if self._game.play_mode not in PAUSED_MODES:
            self._game.game_time = round(self._game.game_time + 0.02, 10)
        p = self._perceive()
        if not (
            np.isfinite(p.ground_truth.torso_pos).all() and np.isfinite(p.joint_angles_deg).all()
        ):
            raise BackendDivergedError(
                f"the ODE world produced a NaN/inf state at t = {p.time:.2f} s"
            )
        return p

    def _perceive(self) -> Perception:
        w = self.world
        game = GameState(play_mode=self._game.play_mode, game_time=self._game.game_time)
        return Perception(
            time=round(w.time, 10),
            game=game,
            gyro=w.gyro(0),
            accel=w.accelerometer(0),
            joint_names=self._model.perceptor_names,
            joint_angles_deg=w.joint_angles_deg(0),
            force_sensors=w.force_sensors(0),
            ground_truth=GroundTruth(
                ball_pos=w.ball_position(),
                ball_vel=w.ball_velocity(),
                torso_pos=w.torso_position(0),
                torso_quat=w.torso_quat(0),
                torso_vel=w.torso_velocity(0),
                torso_ang_vel=w.torso_angular_velocity(0),
            ),
        )

    # ------------------------------------------------------------------ misc
    def close(self) -> None:
        self.world.close()

    def describe(self) -> dict[str, Any]:
        d = super().describe()
        d.update(dead_time_cycles=self.world.dead_time_cycles, engine="ODE 0.16 (libode)")
        return d

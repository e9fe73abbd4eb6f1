"""The in-process world as a backend, on either physics engine: one learning robot (index 0,
left team) and the ball.

``"ode"`` (:class:`OdeBackend`, the default) steps SimSpark's own physics on ODE 0.16, as
rcssserver3d does, so that what a policy learns here works on the real server
(``docs/training.md``, *Which engine*); it needs the system library ``libode`` (Debian/Ubuntu:
``apt-get install libode8``; macOS: ``brew install ode``) and without it says so and names
``engine="mujoco"``. ``"mujoco"`` (:class:`MujocoBackend`) is the fast approximation. Both have
the robot of any type 0–4, the ball, the field's walls and goals, the hinge effector's rules and
the one-cycle dead time, every perceptor and exact ground truth; neither runs the referee (the
play mode is set and kept, the game clock runs).

Resets are instant: the robot (joint angles included) and the ball are placed, no cycles run.
A reset with ``settle_cycles`` lets the placed robot come to rest under zero joint velocities
first, as a real server must; the settled state of a start is kept and restored on the next
reset from the same start (exactly what simulating it again gives: the worlds are deterministic),
so settling costs cycles only the first time.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from robocup_gym.backends.base import (
    Backend,
    BackendDivergedError,
    BackendNotAvailableError,
    EpisodeSetup,
    RobotPose,
)
from robocup_gym.robot.nao import NaoModel
from robocup_gym.sim import SimulationDivergedError
from robocup_gym.sim.physics import CYCLE_S, PhysicsConfig
from robocup_gym.sim.render import FollowCamera, ScenePoser
from robocup_gym.sim.vision import VisionConfig
from robocup_gym.types import AgentCommand, Perception

__all__ = ["InProcessBackend", "MujocoBackend", "OdeBackend"]

_SETTLED_KEPT = 256
"""Most settled starts a backend keeps (a task with more distinct starts simulates the rest)."""


class InProcessBackend(Backend):
    """What both engines' backends share; the subclasses build their world.

    Args:
        robot_type: Nao type 0–4.
        seed: Seed of the world's vision noise and calibration offsets.
        vision: Compute the ``See`` perceptor (every ``vision_config.interval``-th cycle, and
            once at every reset). Off by default because it is the costliest perceptor.
    """

    def __init__(self, world: Any, *, robot_type: int, seed: int | None, vision: bool) -> None:
        super().__init__(robot_type=robot_type, seed=seed, vision=vision)
        self.world = world
        self._model: NaoModel = world.robots[0].model
        self._diverged = False
        self._camera = FollowCamera()
        self._settled: dict[tuple, tuple[dict, tuple]] = {}
        """Settled starts: key of (pose, ball, settle cycles) → (robot state, ball state)."""

    @property
    def robot_model(self) -> NaoModel:
        return self._model

    # ------------------------------------------------------------------ episode control
    def _place(self, start: EpisodeSetup) -> tuple[Perception, int]:
        pose, ball_pos, ball_vel = start.pose, start.ball_pos, start.ball_vel
        settle_cycles = start.settle_cycles
        w = self.world
        self._restart(start.seed)
        key = _start_key(pose, ball_pos, ball_vel, settle_cycles) if settle_cycles else None
        if key is None or key not in self._settled:
            # An episode depends only on its start state: placing forgets the solver's warm
            # start and the motors' history.
            pose.place(w)
            w.place_ball(ball_pos, ball_vel)
            self._sense_placement()
        if key is not None:
            if key not in self._settled:
                self.advance(settle_cycles, self.hold_command())
                if len(self._settled) >= _SETTLED_KEPT:
                    self._settled.pop(next(iter(self._settled)))
                ball = (w.ball_position(), w.ball_velocity(), w.ball_angular_velocity())
                self._settled[key] = (w.export_robot_state(0), ball)
            # every episode from this start, the first too, begins from the kept state
            robot, ball = self._settled[key]
            w.import_robot_state(0, robot)
            w.place_ball(*ball)
        w.set_game(play_mode=start.play_mode, game_time=settle_cycles * CYCLE_S)
        return w.perceive(0, vision=self.vision), settle_cycles

    def _restart(self, seed: int | None) -> None:
        """Before a reset: re-seed the world's randomness (``seed``), recover a diverged state."""

    def _sense_placement(self) -> None:
        """After a placement: what the world must compute for the first perception."""

    def step(self, command: AgentCommand) -> Perception:
        return self.advance(1, command)

    def advance(self, cycles: int, command: AgentCommand | None = None) -> Perception:
        """``cycles`` cycles (``command`` in the first; targets are sticky), perceiving only
        after the last one."""
        if cycles < 1:
            raise ValueError(f"cycles must be >= 1, got {cycles}")
        w = self.world
        if command is not None:
            w.command(0, command)  # (validated before anything runs; say and beam act now)
        try:
            for _ in range(cycles):
                w.step()
        except SimulationDivergedError as e:
            self._diverged = True
            raise BackendDivergedError(str(e)) from e
        p = w.perceive(0, vision=None if self.vision else False)
        gt = p.ground_truth
        if not (np.isfinite(gt.torso_pos).all() and np.isfinite(p.joint_angles_deg).all()):
            self._diverged = True
            raise BackendDivergedError(f"the world produced a NaN/inf state at t = {p.time:.2f} s")
        return p

    def set_torso_force(self, force: Sequence[float]) -> None:
        self.world.set_torso_force(0, force)

    # ------------------------------------------------------------------ misc
    def scene_world(self):
        """A MuJoCo world posed like this one, for drawing (videos, :meth:`render`)."""
        return self.world

    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """RGB image of the scene from a camera that follows the robot, drawn by MuJoCo (needs
        an OpenGL context, e.g. ``MUJOCO_GL=egl`` on a headless machine)."""
        return self._camera.render(self.scene_world(), width, height)

    def close(self) -> None:
        self._camera.close()


def _start_key(
    pose: RobotPose, ball_pos: Sequence[float], ball_vel: Sequence[float], settle: int
) -> tuple:
    """A start as a hashable key (every number exactly)."""
    angles = pose.joint_angles_deg
    if angles is not None and not isinstance(angles, np.ndarray):
        angles = tuple(sorted((str(k), float(v)) for k, v in dict(angles).items()))
    elif angles is not None:
        angles = np.asarray(angles, float).tobytes()
    quat = None if pose.quat is None else np.asarray(pose.quat, float).tobytes()
    return (
        float(pose.x),
        float(pose.y),
        float(pose.heading_deg),
        None if pose.z is None else float(pose.z),
        angles,
        quat,
        np.asarray(ball_pos, float).tobytes(),
        np.asarray(ball_vel, float).tobytes(),
        int(settle),
    )


class OdeBackend(InProcessBackend):
    """The world on SimSpark's physics step, ODE 0.16 itself (:class:`~robocup_gym.sim.engines.
    ode.world.OdeWorld`): the default engine.

    Args:
        robot_type, seed, vision: As :class:`InProcessBackend`.
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
        from robocup_gym.sim.engines.ode import OdeUnavailableError, OdeWorld

        try:
            world = OdeWorld(
                [robot_type], dead_time_cycles=dead_time_cycles, vision=vision_config, seed=seed
            )
        except OdeUnavailableError as exc:
            raise BackendNotAvailableError(
                f"the ODE engine (SimSpark's physics, the default) is not available here: {exc}. "
                "Or choose the MuJoCo engine: engine='mujoco' (--engine mujoco)"
            ) from exc
        super().__init__(world, robot_type=robot_type, seed=seed, vision=vision)
        self._poser: ScenePoser | None = None

    def _restart(self, seed: int | None) -> None:
        if seed is not None:
            self.world.reseed(seed)
        self._diverged = False  # placing every body again recovers the state

    def _sense_placement(self) -> None:
        self.world.sense_contacts()  # the first perception shows the feet loaded

    def scene_world(self):
        if self._poser is None:
            self._poser = ScenePoser([self.robot_type])
        return self._poser.pose(self.world)

    def close(self) -> None:
        super().close()
        self.world.close()

    def describe(self) -> dict[str, Any]:
        d = super().describe()
        d.update(dead_time_cycles=self.world.dead_time_cycles, engine="ODE 0.16 (libode)")
        return d


class MujocoBackend(InProcessBackend):
    """The MuJoCo world (:class:`~robocup_gym.sim.engines.mujoco.world.World`): the fast
    approximation.

    Args:
        robot_type, seed, vision: As :class:`InProcessBackend`.
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
        from robocup_gym.sim.engines.mujoco.world import World

        world = World(
            [robot_type],
            physics=physics,
            dead_time_cycles=dead_time_cycles,
            vision=vision_config,
            seed=seed,
        )
        super().__init__(world, robot_type=robot_type, seed=seed, vision=vision)

    def _restart(self, seed: int | None) -> None:
        if seed is not None or self._diverged:
            # a full reset clears a diverged state and re-seeds noise and calibration
            self.world.reset(seed=seed)
            self._diverged = False

    def describe(self) -> dict[str, Any]:
        d = super().describe()
        d.update(substeps=self.world.substeps, dead_time_cycles=self.world.dead_time_cycles)
        return d

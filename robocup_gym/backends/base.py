"""The seam between an environment and a simulator: the :class:`Backend` interface.

An environment (:mod:`robocup_gym.envs`) drives exactly one learning robot through a backend and
never looks behind it. Only the shared types cross this seam:

* into the backend: a :class:`RobotPose` and a ball state at the start of an episode, and one
  :class:`~robocup_gym.types.AgentCommand` per 20 ms agent cycle;
* out of it: one :class:`~robocup_gym.types.Perception` per cycle, in SimSpark's units and frames,
  with the exact world state in :attr:`Perception.ground_truth` when the backend knows it.

Backends are created by name through :func:`robocup_gym.backends.make_backend` (``"mujoco"``, the
embedded world, is the default; ``"rcssserver3d"`` drives the real server over TCP).

Writing a backend: subclass :class:`Backend`, implement :attr:`~Backend.robot_model`,
:meth:`~Backend.reset_episode` and :meth:`~Backend.step` (and :meth:`~Backend.close` if it holds
resources), then add one entry to the registry in :mod:`robocup_gym.backends`.
"""

from __future__ import annotations

import abc
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from robocup_gym.robot.nao import NaoModel
from robocup_gym.types import AgentCommand, Perception

__all__ = [
    "Backend",
    "BackendDivergedError",
    "BackendError",
    "BackendNotAvailableError",
    "RobotPose",
]


class BackendError(RuntimeError):
    """Base class of the errors a backend raises."""


class BackendDivergedError(BackendError):
    """The simulation behind the backend blew up (NaN/inf state or a solver instability).

    The backend stays usable: the next :meth:`Backend.reset_episode` restores a valid state.
    Environments end the episode (truncated, ``info["diverged"] = True``) when they see it.
    """


class BackendNotAvailableError(ValueError):
    """The requested backend name is unknown or not implemented (yet)."""


@dataclass(frozen=True)
class RobotPose:
    """Where and how the learning robot starts an episode.

    Attributes:
        x, y: Torso centre in world coordinates, m (field centre origin, x towards the right
            team's goal).
        heading_deg: Direction the robot faces, degrees (0 = world +x, counter-clockwise positive).
        joint_angles_deg: Joint angles in degrees, canonical order (see
            :mod:`robocup_gym.robot.nao`) or by effector/perceptor name (others 0); ``None``:
            all 0.
        z: Torso centre height, m; ``None`` puts the robot's lowest point on the ground.
        quat: Full torso orientation ``(w, x, y, z)`` instead of an upright robot facing
            ``heading_deg`` (e.g. lying on its back); the in-process engines place it, a real
            server cannot (only upright).
    """

    x: float
    y: float
    heading_deg: float = 0.0
    joint_angles_deg: np.ndarray | Mapping[str, float] | None = None
    z: float | None = None
    quat: np.ndarray | None = None

    def place(self, world: Any, index: int = 0) -> None:
        """Put robot ``index`` of an in-process world (either engine) in this pose, instantly;
        ``joint_angles_deg=None`` means all 0 here (a world's own ``None`` keeps the current
        angles)."""
        angles = self.joint_angles_deg
        if angles is None:
            angles = np.zeros(len(world.robots[index].model.joints))
        world.place_robot(
            index,
            self.x,
            self.y,
            heading_deg=self.heading_deg,
            z=self.z,
            joint_angles_deg=angles,
            quat=self.quat,
        )


@dataclass(frozen=True)
class EpisodeSetup:
    """What :meth:`Backend.reset_episode` was asked for, checked (see its arguments)."""

    pose: RobotPose
    ball_pos: tuple[float, ...]
    ball_vel: tuple[float, ...]
    play_mode: str
    seed: int | None
    settle_cycles: int


class Backend(abc.ABC):
    """One simulated learning robot (plus the ball and the rest of the world it lives in).

    Every backend offers the same cycle-level interface; one :meth:`step` is one 20 ms agent
    cycle, with the simulator's own dead time between a command and its effect (one cycle on
    rcssserver3d and, by default, on the embedded world).

    Args:
        robot_type: Heterogeneous Nao type 0–4 of the learning robot.
        seed: Seed of the backend's own randomness (vision noise, calibration), if it has any.
        vision: Whether the environment needs the ``See`` perceptor. A backend may skip computing
            vision when False (the embedded world does: it is its most expensive perceptor).
    """

    name: ClassVar[str] = "abstract"
    """Registry name of the backend (``"mujoco"``, ``"rcssserver3d"``, …)."""

    deterministic: ClassVar[bool] = True
    """Whether the same commands from the same :meth:`reset_episode` give the same perceptions
    every time. The in-process worlds do; a real server does not (its solver carries warm
    starts and contacts from one episode to the next, its noise has its own seed), and
    environments on it say so (``env.spec.nondeterministic``)."""

    def __init__(self, *, robot_type: int = 0, seed: int | None = None, vision: bool = False):
        self.robot_type = int(robot_type)
        self.seed = seed
        self.vision = bool(vision)

    # ------------------------------------------------------------------ description
    @property
    @abc.abstractmethod
    def robot_model(self) -> NaoModel:
        """The learning robot's joints and bodies (names, limits, max speeds)."""

    @property
    def has_ground_truth(self) -> bool:
        """True if every :class:`Perception` carries :attr:`Perception.ground_truth`."""
        return True

    @property
    def places_any_orientation(self) -> bool:
        """True if :meth:`reset_episode` can put the robot down in any orientation
        (``RobotPose.quat``: a robot lying on its back, say), not only upright. The in-process
        engines can; a real server only where its trainer can turn a robot."""
        return True

    # ------------------------------------------------------------------ episode control
    def reset_episode(
        self,
        pose: RobotPose,
        ball_pos: Sequence[float],
        ball_vel: Sequence[float] = (0.0, 0.0, 0.0),
        *,
        play_mode: str = "PlayOn",
        seed: int | None = None,
        settle_cycles: int = 0,
    ) -> Perception:
        """Start an episode: teleport the robot (joint angles included) and the ball, set the play
        mode and restart the game clock, zero all velocities and joint targets. Runs no
        simulation cycles where the simulator allows it.

        Args:
            pose: Robot placement and joint angles.
            ball_pos: Ball centre ``(x, y, z)`` in m (world frame).
            ball_vel: Ball linear velocity in m/s (world frame).
            play_mode: Play mode to set (wire name).
            seed: Re-seed the backend's randomness (``None`` continues the current stream).
            settle_cycles: Cycles the placed robot then spends under :meth:`hold_command` (a
                Nao: every joint velocity 0) before the episode starts, e.g. to come to rest
                after being dropped. A real server needs cycles of its own after a placement
                and counts them in; the in-process worlds simulate a start's settling once and
                restore the result afterwards. The game clock starts at the placement.

        Returns:
            The perception of the start state (the first observation of the episode).

        Raises:
            ValueError: ``settle_cycles`` is not a whole number >= 0.
        """
        if isinstance(settle_cycles, bool) or not isinstance(settle_cycles, int | np.integer):
            raise ValueError(f"settle_cycles must be a whole number >= 0, got {settle_cycles!r}")
        if settle_cycles < 0:
            raise ValueError(f"settle_cycles must be a whole number >= 0, got {settle_cycles}")
        start = EpisodeSetup(
            pose,
            tuple(float(v) for v in ball_pos),
            tuple(float(v) for v in ball_vel),
            play_mode,
            seed,
            int(settle_cycles),
        )
        p, ran = self._place(start)
        if start.settle_cycles > ran:
            p = self.advance(start.settle_cycles - ran, self.hold_command())
        return p

    @abc.abstractmethod
    def _place(self, start: EpisodeSetup) -> tuple[Perception, int]:
        """Put the robot and the ball in place for :meth:`reset_episode` (arguments checked);
        return the first perception and how many of ``start.settle_cycles`` already ran (a
        real server's placement takes cycles; an in-process world may restore a settled start
        it kept: all of them). :meth:`reset_episode` runs the rest."""

    def hold_command(self) -> AgentCommand:
        """The command that holds the robot still while a start settles: every joint velocity
        0 (a league robot's PD backends keep the reset's targets instead)."""
        return AgentCommand(np.zeros(len(self.robot_model.joints)))

    @abc.abstractmethod
    def step(self, command: AgentCommand) -> Perception:
        """Send one cycle's command, advance one 20 ms cycle, return what the robot perceives.

        Raises:
            BackendDivergedError: the simulation blew up; call :meth:`reset_episode`.
        """

    def advance(self, cycles: int, command: AgentCommand | None = None) -> Perception:
        """Run ``cycles`` cycles (``command`` in the first, nothing new after: targets are sticky)
        and return the perception after the last one. Backends may skip building the
        perceptions in between (the embedded world does)."""
        if cycles < 1:
            raise ValueError(f"cycles must be >= 1, got {cycles}")
        p = self.step(command if command is not None else AgentCommand())
        for _ in range(cycles - 1):
            p = self.step(AgentCommand())
        return p

    def set_torso_force(self, force: Sequence[float]) -> None:
        """Push the learning robot's torso with ``force`` (N, world frame) in every cycle until
        it is changed; ``(0, 0, 0)`` ends it. A training aid of the in-process engines
        (``TrainConfig.assist_force``); no server has such a force.

        Raises:
            BackendNotAvailableError: this backend cannot push a robot.
        """
        raise BackendNotAvailableError(
            f"the {self.name!r} backend cannot push the robot (an assist force exists only in "
            "the in-process engines 'ode', 'mujoco' and 'rcsssmj'); train with assist_force=0 "
            "here"
        )

    # ------------------------------------------------------------------ misc
    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """An RGB image ``(height, width, 3)`` of the scene, if the backend can draw one."""
        raise NotImplementedError(f"the {self.name!r} backend cannot render images")

    def close(self) -> None:  # noqa: B027 - optional hook with a no-op default
        """Release processes, sockets and renderers. Idempotent."""

    def describe(self) -> dict[str, Any]:
        """A small JSON-able description (name, robot type, options) for logs."""
        return {"backend": self.name, "robot_type": self.robot_type, "vision": self.vision}

    def __enter__(self) -> Backend:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

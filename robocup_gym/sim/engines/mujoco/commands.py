"""Joint commands in the MuJoCo world as SimSpark's hinge effector takes them: validated targets
(rad/s, by name or as an array in canonical order), waiting out the dead time, then realised
(clipped to the joint's maximum speed, ignored while the joint is not strictly inside its
limits); the motor targets set directly (a rebuild's import) and the training aid of a push on
the torso.

:class:`WorldCommands` is a part of :class:`~robocup_gym.sim.engines.mujoco.world.World`."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from robocup_gym.sim import physics as phys
from robocup_gym.sim.engines.mujoco.motors import _clip
from robocup_gym.sim.engines.mujoco.robot import RobotState
from robocup_gym.sim.pose import joint_index
from robocup_gym.types import AgentCommand


class WorldCommands:
    """The motor commands of :class:`~robocup_gym.sim.engines.mujoco.world.World`."""

    def command_array(self, index: int, velocities: Mapping[str, float] | np.ndarray) -> np.ndarray:
        """Validate a joint-velocity command (rad/s) and return it as a canonical-order array in
        which NaN marks "no command for this joint" (targets are sticky).

        Raises:
            KeyError: unknown effector name (lists the valid ones).
            ValueError: NaN/inf value (names the joint) or wrong array shape.
        """
        r = self.robot(index)
        n = len(r.max_speeds)
        if type(velocities) is np.ndarray and velocities.shape == (n,):  # the hot path
            out = velocities.astype(float)  # a copy: the caller may reuse its array
            if not math.isfinite(out.dot(out)):  # one check for any NaN/inf (or a huge value)
                self._raise_not_finite(r, out)
            return out
        if isinstance(velocities, Mapping):
            out = np.full(n, np.nan)
            for name, v in velocities.items():
                i = joint_index(r.model, name)
                v = float(v)
                if not math.isfinite(v):
                    raise ValueError(f"velocity command for joint {r.effector_names[i]} is {v}")
                out[i] = v
            return out
        out = np.array(velocities, dtype=float)  # a copy: the caller may reuse its array
        if out.shape != (n,):
            raise ValueError(
                f"velocity array must have shape ({n},) in effector order "
                f"{', '.join(r.effector_names)}; got {out.shape}"
            )
        if not math.isfinite(out.dot(out)):
            self._raise_not_finite(r, out)
        return out

    @staticmethod
    def _raise_not_finite(r: RobotState, velocities: np.ndarray) -> None:
        """Raise ``ValueError`` naming the first joint whose command is NaN/inf (if any: a
        finite command whose squares overflow is left alone)."""
        bad = ~np.isfinite(velocities)
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(f"velocity command for joint {r.effector_names[i]} is {velocities[i]}")

    def command(self, index: int, command: AgentCommand | Mapping[str, float] | np.ndarray) -> None:
        """Queue one cycle's command for robot ``index`` (it acts after the dead time)."""
        r = self.robot(index)
        if isinstance(command, AgentCommand):
            velocities = command.joint_velocities
            vel = self.command_array(index, velocities)
            if command.beam is not None:
                self.beam(index, *command.beam)
            if command.say is not None:
                self.say(index, command.say)
        else:
            velocities = command
            vel = self.command_array(index, velocities)
        # only a mapping can leave joints without a command (NaN): an array names them all
        full = type(velocities) is np.ndarray or not np.isnan(vel).any()
        r.pending.append((self.cycle + self.dead_time_cycles, vel, full))

    def _realise_commands(self, r: RobotState, inside: np.ndarray | None) -> None:
        """Write robot ``r``'s due commands into its motors (SimSpark's hinge effector, spec
        §8.3): a command is taken only by joints strictly inside their limits (``inside``, this
        robot's slice, ``None`` when all are); the others keep their previous target. Commands
        are clipped to each joint's maximum speed."""
        while r.pending and r.pending[0][0] <= self.cycle:
            _, vel, full = r.pending.pop(0)
            vel = self._frozen_to_zero(r.index, vel)
            if inside is None and full:
                _clip(vel, r.min_speeds, r.max_speeds, out=r.targets)  # every joint takes it
                continue
            clipped = _clip(vel, r.min_speeds, r.max_speeds)
            if full:
                take = inside
            else:
                # NaN (no command for that joint) compares False: the old target stays
                take = vel == vel
                if inside is not None:
                    take &= inside
            np.copyto(r.targets, clipped, where=take)

    def set_torso_force(self, index: int, force: Sequence[float]) -> None:
        """Push robot ``index``'s torso with ``force`` (N, world frame, at the torso's origin,
        through its free joint) in every step until it is changed or :meth:`reset`;
        ``(0, 0, 0)`` ends it. SimSpark has no such force: it is a training aid
        (``TrainConfig.assist_force``), never part of an evaluation.

        Raises:
            ValueError: ``force`` is not three finite numbers.
        """
        f = phys.finite_force(force)
        a = self.robot(index).qvel_root
        self._data.qfrc_applied[a : a + 3] = f

    def set_motor_targets(self, index: int, targets: np.ndarray) -> None:
        """Set robot ``index``'s motor targets (rad/s, canonical order) as they are, without the
        hinge effector's rules: to restore what :meth:`motor_targets` returned after a placement
        (which zeroes them)."""
        self.robot(index).targets[:] = targets

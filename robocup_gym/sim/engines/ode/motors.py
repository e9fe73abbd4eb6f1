"""Joint commands in the ODE world as SimSpark's hinge effector takes them: validated targets
(rad/s, by name or as an array in canonical order) queued for the next step, then realised
after the dead time (clipped to the joint's maximum speed, ignored while the joint is not
strictly inside its limits, a non-zero one waking the joint's child body), and the training
aid of a push on the torso.

:class:`OdeMotors` is a part of :class:`~robocup_gym.sim.engines.ode.world.OdeWorld`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from robocup_gym.sim import physics as phys
from robocup_gym.sim.engines.ode import lib as ode
from robocup_gym.sim.engines.ode.robot import OdeRobot
from robocup_gym.sim.pose import joint_index
from robocup_gym.types import AgentCommand


class OdeMotors:
    """The motor side of :class:`~robocup_gym.sim.engines.ode.world.OdeWorld`."""

    def command(self, index: int, command: AgentCommand | Mapping[str, float] | np.ndarray) -> None:
        """Give robot ``index`` its command for the next :meth:`step` (as the MuJoCo world's
        ``command``): joint velocities in rad/s (by name, or an array in canonical order), or an
        :class:`~robocup_gym.types.AgentCommand` whose ``beam`` and ``say`` act at once. A
        second command before the step overrides the first joint by joint.

        Raises:
            KeyError: an unknown joint name (listing the valid ones).
            ValueError: a NaN/inf velocity (naming the joint) or an array of the wrong shape.
        """
        r = self.robot(index)
        if isinstance(command, AgentCommand):
            arr = self._command_array(r, command.joint_velocities)
            if command.beam is not None:
                self.beam(index, *command.beam)
            if command.say is not None:
                self.say(index, command.say)
        else:
            arr = self._command_array(r, command)
        old = self._queued.get(index)
        if old is not None:
            arr = np.where(np.isnan(arr), old, arr)
        self._queued[index] = arr

    def _command_array(self, r: OdeRobot, cmd: Mapping[str, float] | np.ndarray) -> np.ndarray:
        """Targets in canonical order, rad/s; NaN marks a joint the command leaves alone.

        Raises:
            KeyError: an unknown joint name (listing the valid ones).
            ValueError: a NaN/inf velocity (naming the joint) or an array of the wrong shape.
        """
        names = r.model.effector_names
        if isinstance(cmd, np.ndarray) and cmd.shape == (len(names),):  # the common case
            out = cmd.astype(float)  # a copy: the queue keeps it
            if not np.isfinite(out).all():
                k = int(np.argmin(np.isfinite(out)))
                raise ValueError(f"velocity command for joint {names[k]} is {out[k]}")
            return out
        out = np.full(len(names), np.nan)
        if isinstance(cmd, Mapping):
            given = np.zeros(len(names), dtype=bool)
            for name, v in cmd.items():
                k = joint_index(r.model, name)
                out[k] = float(v)
                given[k] = True
        else:
            arr = np.asarray(cmd, dtype=float)
            if arr.shape != out.shape:
                raise ValueError(f"command array must have shape {out.shape}, got {arr.shape}")
            out[:] = arr
            given = np.ones(len(names), dtype=bool)
        bad = given & ~np.isfinite(out)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise ValueError(f"velocity command for joint {names[k]} is {out[k]}")
        return out

    def _realise(self, r: OdeRobot, targets: np.ndarray) -> None:
        lib = self._lib
        vmax = r.model.max_speeds
        for k, h in enumerate(r.joints):
            v = targets[k]
            if math.isnan(v):
                continue
            angle = lib.dJointGetHingeAngle(h)
            lo, hi = r.limits[k]
            if not lo < angle < hi:
                continue  # SimSpark's hinge effector: the previous target stays
            v = min(max(float(v), -vmax[k]), vmax[k])
            lib.dJointSetHingeParam(h, ode.PARAM_VEL, v)
            if v != 0.0:
                lib.dBodyEnable(r.child_body[k])

    def set_torso_force(self, index: int, force: Sequence[float]) -> None:
        """Push robot ``index``'s torso with ``force`` (N, world frame, at its centre of mass)
        in every cycle until it is changed; ``(0, 0, 0)`` ends it. SimSpark has no such force:
        it is a training aid (``TrainConfig.assist_force``, which lifts a robot that learns to
        get up), never part of an evaluation.

        Raises:
            ValueError: ``force`` is not three finite numbers.
        """
        f = phys.finite_force(force)
        self.robots[index]  # IndexError for an unknown robot
        if any(f):
            self._pushes[index] = f
        else:
            self._pushes.pop(index, None)

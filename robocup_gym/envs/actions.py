"""From a policy action in [-1, 1] to joint commands, per action mode: velocities (rad/s) for
the Nao (:class:`ActionMapper`), PD commands for the league's robots (:class:`PDActionMapper`)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from robocup_gym.envs.config import ActionMode
from robocup_gym.robot.nao import NaoModel
from robocup_gym.types import AgentCommand, PDCommand

__all__ = ["ActionMapper", "PDActionMapper"]


class ActionMapper:
    """Scales actions to each controlled joint's range and turns them into a full
    canonical-order velocity command (uncontrolled joints get 0 rad/s).

    Args:
        model: The robot.
        joints: Canonical indices of the controlled joints, in action order.
        mode: The action mode.
        gain: Proportional gain (1/s) of the target-angle modes.
        mirror: One action value per left/right pair of controlled joints: the right joint does
            the mirror image of the left one (:attr:`NaoModel.mirror_pairs`), so the robot moves
            symmetrically and the action has fewer values (``velocity`` and ``target_angle``
            modes).
        around_deg: Target-angle modes: the pose (deg, canonical order, every joint) that action
            0 holds, with ``spread_deg``; ``None``: action 0 is the middle of each joint's range.
        spread_deg: With ``around_deg``: an action of ±1 is ``around_deg`` ± this many degrees,
            clipped to the joint's range.
        stop_margin_deg: Target angles stay this far inside each joint's stops (deg): a joint
            exactly on a stop obeys or ignores rcssserver3d's next command on rounding.
    """

    def __init__(
        self,
        model: NaoModel,
        joints: np.ndarray,
        mode: ActionMode,
        gain: float,
        mirror: bool = False,
        around_deg: np.ndarray | None = None,
        spread_deg: float | None = None,
        stop_margin_deg: float = 0.0,
    ):
        self.model = model
        self.joints = np.asarray(joints, dtype=int)
        self.mode = ActionMode(mode)
        self.gain = float(gain)
        n = len(self.joints)
        self.n_joints = n
        self.size = 2 * n if self.mode is ActionMode.TARGET_ANGLE_MAX_SPEED else n
        self._free: np.ndarray | None = None
        if mirror:
            if self.mode is ActionMode.TARGET_ANGLE_MAX_SPEED:
                raise ValueError(
                    "mirrored actions work with the 'velocity' and 'target_angle' action modes"
                )
            where = {int(j): k for k, j in enumerate(self.joints)}
            pairs = [
                (where[i], where[r], sign)
                for i, r, sign in model.mirror_pairs
                if i in where and r in where
            ]
            derived = {r for _, r, _ in pairs}
            self._free = np.array([k for k in range(n) if k not in derived], dtype=int)
            self._mirror_right = np.array([r for _, r, _ in pairs], dtype=int)
            self._mirror_left = np.array([left for left, _, _ in pairs], dtype=int)
            self._mirror_sign = np.array([sign for _, _, sign in pairs])
            self.size = len(self._free)
            self._full = np.zeros(n)
        self.max_speed = model.max_speeds[self.joints].astype(float)
        lo, hi = model.ranges_deg[self.joints].T.astype(float)
        self.angle_mid, self.angle_half, self._limits = _target_window(
            lo, hi, self.joints, around_deg, spread_deg
        )
        self._limits = (self._limits[0] + stop_margin_deg, self._limits[1] - stop_margin_deg)
        self._slots = {model.effector_names[j]: k for k, j in enumerate(self.joints)}
        """Action slot of each controlled joint by effector name."""
        self.target_offset_deg = np.zeros(n)
        """Added to every target angle (deg, per controlled joint, in action order) before the
        clip to the joint's range: a task's reference motion (Walk's gait), set each step."""
        self._command = np.zeros(len(model.joints))

    def set_offsets(self, offsets_deg: Mapping[str, float]) -> None:
        """Set :attr:`target_offset_deg` for the next step from offsets by effector name (deg):
        the joints named get theirs, every other controlled joint 0; a name this mapper does
        not control is ignored (a reference motion may move joints the action leaves out)."""
        slots = self._slots
        offsets = self.target_offset_deg
        offsets[:] = 0.0
        for name, value in offsets_deg.items():
            k = slots.get(name)
            if k is not None:
                offsets[k] = value

    def set_window(self, centre_deg: float | np.ndarray, half_deg: float | np.ndarray) -> None:
        """Let an action of ±1 span ``centre_deg`` ± ``half_deg`` (deg, per controlled joint or
        one for all; still shifted by :attr:`target_offset_deg` and clipped to the ranges): a
        task whose reference motion sets the offsets (GetUp's script) centres the window on 0."""
        self.angle_mid = np.broadcast_to(np.asarray(centre_deg, float), (self.n_joints,)).copy()
        self.angle_half = np.broadcast_to(np.asarray(half_deg, float), (self.n_joints,)).copy()

    def expand(self, action: np.ndarray) -> np.ndarray:
        """The action over every controlled joint (with mirrored actions: the right joints'
        values made from their left partners'; otherwise ``action`` itself)."""
        if self._free is None:
            return action
        full = self._full.copy()
        full[self._free] = action
        full[self._mirror_right] = self._mirror_sign * full[self._mirror_left]
        return full

    def targets_deg(self, action: np.ndarray) -> np.ndarray:
        """Target angles (deg) of the target-angle modes for ``action``."""
        a = action[0::2] if self.mode is ActionMode.TARGET_ANGLE_MAX_SPEED else self.expand(action)
        return _targets(self, a)

    def velocities(self, action: np.ndarray, joint_angles_deg: np.ndarray) -> np.ndarray:
        """Velocities (rad/s) of the controlled joints for a clipped ``action`` given the current
        angles (deg, canonical order)."""
        mode = self.mode
        action = self.expand(action)
        if mode is ActionMode.VELOCITY:
            return action * self.max_speed
        if mode is ActionMode.TARGET_ANGLE:
            target = _targets(self, action)
            limit = self.max_speed
        else:
            target = _targets(self, action[0::2])
            limit = (action[1::2] + 1.0) * (0.5 * self.max_speed)
        err = np.radians(target - joint_angles_deg[self.joints])
        v = self.gain * err  # clipped to ±limit (np.clip's values, cheaper on small arrays)
        np.maximum(v, -limit, out=v)
        np.minimum(v, limit, out=v)
        return v

    def command(self, action: np.ndarray, joint_angles_deg: np.ndarray) -> np.ndarray:
        """Full canonical-order velocity command (rad/s); a fresh array each call."""
        out = self._command.copy()
        out[self.joints] = self.velocities(action, joint_angles_deg)
        return out

    def agent_command(self, action: np.ndarray, joint_angles_deg: np.ndarray):
        """The :class:`~robocup_gym.types.AgentCommand` for a clipped ``action``."""
        return AgentCommand(self.command(action, joint_angles_deg))

    def start_episode(self, joint_angles_deg: np.ndarray) -> None:
        """Nothing to remember at an episode's start (see :class:`PDActionMapper`)."""

    def stop_command(self, joint_angles_deg: np.ndarray) -> AgentCommand:
        """The command of the wait cycles after an episode: every joint at 0 rad/s."""
        return AgentCommand(np.zeros(len(self.model.joints)))

    def labels(self) -> list[str]:
        """One label per action value."""
        names = [self.model.effector_names[i] for i in self.joints]
        if self._free is not None:
            for left, right in zip(self._mirror_left, self._mirror_right, strict=True):
                names[left] = f"{names[left]}+{names[right]}"
            return [names[k] for k in self._free]
        if self.mode is ActionMode.TARGET_ANGLE_MAX_SPEED:
            return [f"{n}/{part}" for n in names for part in ("angle", "speed")]
        return list(names)


class PDActionMapper:
    """Actions in [-1, 1] to the league robots' PD joint commands
    (:class:`~robocup_gym.types.PDCommand`), per action mode; joints not controlled are held at
    the episode's start angles with their default gains.

    Default gains per joint: ``kp = τ_max / radians(saturation_deg)`` (the actuator's whole
    torque at that angle error) and ``kd = kp × damping_s``.

    Args:
        model: The :class:`~robocup_gym.robot.league.LeagueRobot`.
        joints: Indices (model order) of the controlled joints, in action order.
        mode: ``TARGET_ANGLE``, ``TARGET_ANGLE_GAINS`` or ``TORQUE``.
        saturation_deg: See above, degrees.
        damping_s: See above, seconds.
        around_deg, spread_deg: As :class:`ActionMapper`'s (model order).
    """

    def __init__(
        self,
        model,
        joints: np.ndarray,
        mode: ActionMode,
        saturation_deg: float,
        damping_s: float,
        around_deg: np.ndarray | None = None,
        spread_deg: float | None = None,
    ) -> None:
        self.model = model
        self.joints = np.asarray(joints, dtype=int)
        self.mode = ActionMode(mode)
        if self.mode not in (
            ActionMode.TARGET_ANGLE,
            ActionMode.TARGET_ANGLE_GAINS,
            ActionMode.TORQUE,
        ):
            raise ValueError(f"action mode {self.mode.value!r} is not a PD mode")
        n = len(self.joints)
        self.n_joints = n
        self.size = 3 * n if self.mode is ActionMode.TARGET_ANGLE_GAINS else n
        tmax = np.abs(model.torque_limits).max(axis=1)
        self.kp = tmax / np.radians(saturation_deg)
        """Default proportional gain per joint (model order), N·m/rad."""
        self.kd = self.kp * float(damping_s)
        """Default derivative gain per joint (model order), N·m·s/rad."""
        self.tau_max = tmax
        lo, hi = model.ranges_deg[self.joints].T.astype(float)
        self.angle_mid, self.angle_half, self._limits = _target_window(
            lo, hi, self.joints, around_deg, spread_deg
        )
        self.target_offset_deg = np.zeros(n)
        """As :attr:`ActionMapper.target_offset_deg`."""
        self._names = model.effector_names
        self._lo, self._hi = model.ranges_deg.T.astype(float)
        self._others = np.setdiff1d(np.arange(len(model.joints)), self.joints)
        self._held: dict[str, PDCommand] = {}
        self.start_episode(np.zeros(len(model.joints)))

    def start_episode(self, joint_angles_deg: np.ndarray) -> None:
        """Hold the joints not controlled at these angles (deg, model order) this episode."""
        held = self.hold(joint_angles_deg)
        self._held = {self._names[i]: held[self._names[i]] for i in self._others}

    def targets_deg(self, action: np.ndarray) -> np.ndarray:
        """Target angles (deg) of the target-angle modes for ``action``."""
        a = action[0::3] if self.mode is ActionMode.TARGET_ANGLE_GAINS else action
        return _targets(self, a)

    def command(self, action: np.ndarray, joint_angles_deg: np.ndarray | None = None):
        """The PD commands (effector name → :class:`PDCommand`) for a clipped ``action``, every
        joint named (uncontrolled ones held)."""
        names, j = self._names, self.joints
        out = dict(self._held)
        mode = self.mode
        if mode is ActionMode.TORQUE:
            tau = action * self.tau_max[j]
            for k, i in enumerate(j):
                out[names[i]] = PDCommand(0.0, 0.0, 0.0, 0.0, float(tau[k]))
            return out
        target = self.targets_deg(action)
        if mode is ActionMode.TARGET_ANGLE:
            kp, kd = self.kp[j], self.kd[j]
        else:
            kp = (action[1::3] + 1.0) * self.kp[j]
            kd = (action[2::3] + 1.0) * self.kd[j]
        for k, i in enumerate(j):
            out[names[i]] = PDCommand(float(target[k]), 0.0, float(kp[k]), float(kd[k]))
        return out

    def hold(self, angles_deg: np.ndarray):
        """Commands holding every joint at ``angles_deg`` (model order, clipped to the joints'
        ranges: a perceived angle can lie a little beyond a limit, MuJoCo's limits are soft)
        with default gains."""
        angles_deg = np.clip(np.asarray(angles_deg, dtype=float), self._lo, self._hi)
        return {
            n: PDCommand(float(a), 0.0, float(p), float(d))
            for n, a, p, d in zip(self._names, angles_deg, self.kp, self.kd, strict=True)
        }

    def agent_command(self, action: np.ndarray, joint_angles_deg: np.ndarray):
        """The :class:`~robocup_gym.types.AgentCommand` for a clipped ``action``."""
        return AgentCommand(joint_pd=self.command(action, joint_angles_deg))

    def stop_command(self, joint_angles_deg: np.ndarray) -> AgentCommand:
        """The command of the wait cycles after an episode: every joint held where it is."""
        return AgentCommand(joint_pd=self.hold(joint_angles_deg))

    def labels(self) -> list[str]:
        """One label per action value."""
        names = [self._names[i] for i in self.joints]
        if self.mode is ActionMode.TARGET_ANGLE_GAINS:
            return [f"{n}/{part}" for n in names for part in ("angle", "kp", "kd")]
        return list(names)


def _target_window(
    lo: np.ndarray,
    hi: np.ndarray,
    joints: np.ndarray,
    around_deg: np.ndarray | None,
    spread_deg: float | None,
) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """(centre, half width, clip limits) of the target angles an action in [-1, 1] spans, per
    controlled joint (deg): the joint's whole range, or ``around_deg`` ± ``spread_deg`` clipped
    to it."""
    if around_deg is None:
        return (lo + hi) / 2.0, (hi - lo) / 2.0, (lo, hi)
    if spread_deg is None or not (np.isfinite(spread_deg) and spread_deg > 0):
        raise ValueError(f"spread_deg must be a number > 0 with around_deg, got {spread_deg!r}")
    centre = np.asarray(around_deg, dtype=float)[joints]
    return centre, np.full(len(joints), float(spread_deg)), (lo, hi)


def _targets(mapper, a: np.ndarray) -> np.ndarray:
    """Target angles (deg) of a mapper's target window for action values ``a``, shifted by its
    ``target_offset_deg`` and clipped to the joints' ranges."""
    target = mapper.angle_mid + a * mapper.angle_half + mapper.target_offset_deg
    lo, hi = mapper._limits  # np.clip's values, cheaper on small arrays
    np.maximum(target, lo, out=target)
    np.minimum(target, hi, out=target)
    return target

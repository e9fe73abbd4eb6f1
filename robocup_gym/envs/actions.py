"""From a policy action in [-1, 1] to joint velocity commands (rad/s), per action mode."""

from __future__ import annotations

import numpy as np

from robocup_gym.envs.config import ActionMode
from robocup_gym.robot.nao import NaoModel

__all__ = ["ActionMapper"]


class ActionMapper:
    """Scales actions to each controlled joint's range and turns them into a full
    canonical-order velocity command (uncontrolled joints get 0 rad/s).

    Args:
        model: The robot.
        joints: Canonical indices of the controlled joints, in action order.
        mode: The action mode.
        gain: Proportional gain (1/s) of the target-angle modes.
    """

    def __init__(self, model: NaoModel, joints: np.ndarray, mode: ActionMode, gain: float):
        self.model = model
        self.joints = np.asarray(joints, dtype=int)
        self.mode = ActionMode(mode)
        self.gain = float(gain)
        n = len(self.joints)
        self.n_joints = n
        self.size = 2 * n if self.mode is ActionMode.TARGET_ANGLE_MAX_SPEED else n
        self.max_speed = model.max_speeds[self.joints].astype(float)
        lo, hi = model.ranges_deg[self.joints].T.astype(float)
        self.angle_mid = (lo + hi) / 2.0
        self.angle_half = (hi - lo) / 2.0
        self._command = np.zeros(len(model.joints))

    def targets_deg(self, action: np.ndarray) -> np.ndarray:
        """Target angles (deg) of the target-angle modes for ``action``."""
        a = action[0::2] if self.mode is ActionMode.TARGET_ANGLE_MAX_SPEED else action
        return self.angle_mid + a * self.angle_half

    def velocities(self, action: np.ndarray, joint_angles_deg: np.ndarray) -> np.ndarray:
        """Velocities (rad/s) of the controlled joints for a clipped ``action`` given the current
        angles (deg, canonical order)."""
        mode = self.mode
        if mode is ActionMode.VELOCITY:
            return action * self.max_speed
        if mode is ActionMode.TARGET_ANGLE:
            target = self.angle_mid + action * self.angle_half
            limit = self.max_speed
        else:
            target = self.angle_mid + action[0::2] * self.angle_half
            limit = (action[1::2] + 1.0) * (0.5 * self.max_speed)
        err = np.radians(target - joint_angles_deg[self.joints])
        return np.clip(self.gain * err, -limit, limit)

    def command(self, action: np.ndarray, joint_angles_deg: np.ndarray) -> np.ndarray:
        """Full canonical-order velocity command (rad/s); a fresh array each call."""
        out = self._command.copy()
        out[self.joints] = self.velocities(action, joint_angles_deg)
        return out

    def labels(self) -> list[str]:
        """One label per action value."""
        names = [self.model.effector_names[i] for i in self.joints]
        if self.mode is ActionMode.TARGET_ANGLE_MAX_SPEED:
            return [f"{n}/{part}" for n in names for part in ("angle", "speed")]
        return list(names)

"""A standing kick for the Nao, as target-angle offsets over time: the reference motion the
kicking tasks (TargetKick, LongKick) add their actions to.

From the crouched standing pose (:data:`~robocup_gym.envs.config.PAPER_STANDING_POSE_DEG`) the
robot leans onto its left foot, draws the right foot back, swings it through the ball, brings it
back and returns to the stance. Played alone (zero actions) on the default engine, with the
ball 0.16 m ahead of the right foot, it moves the ball about 2.7 m and the robot stands still
1 s later (``tests/envs/test_reference_kick.py``); the policy learns the corrections that aim and
lengthen it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robocup_gym.envs.config import PAPER_STANDING_POSE_DEG, ActionMode, EnvConfig, EnvConfigError
from robocup_gym.sim.physics import CYCLE_S

__all__ = [
    "KICK_BALL_START_POS",
    "REFERENCE_KICK_KEYFRAMES",
    "ReferenceKickConfig",
    "ReferenceKickTask",
    "reference_kick_deg",
]

_LEAN_LEFT = {"lle2": -8.0, "rle2": -8.0, "lle6": 8.0, "rle6": 8.0}
"""Both hip rolls −8° and both ankle rolls +8°: the weight onto the left foot."""

REFERENCE_KICK_KEYFRAMES: tuple[tuple[float, dict[str, float]], ...] = (
    (0.00, {}),
    (0.30, dict(_LEAN_LEFT)),
    (0.50, {**_LEAN_LEFT, "rle3": 10.0, "rle4": -40.0, "rle5": 10.0}),  # right foot up, back
    (0.56, {**_LEAN_LEFT, "rle3": 50.0, "rle4": 20.0, "rle5": -10.0}),  # the swing through
    (0.76, {**_LEAN_LEFT, "rle3": 10.0, "rle4": -10.0, "rle5": 0.0}),  # the foot comes back
    (1.06, {}),  # the stance again
)
"""The reference kick: (time from the episode's start in s, offsets in deg by Nao effector name
over the start pose); linear between keyframes, 0 for a joint a keyframe leaves out and after
the last. Effectors: ``rle3``/``rle4``/``rle5`` the right hip pitch, knee and ankle pitch,
``lle2``/``rle2`` the hip rolls, ``lle6``/``rle6`` the ankle rolls."""

_NAMES = sorted({n for _, k in REFERENCE_KICK_KEYFRAMES for n in k})
_TIMES = np.array([t for t, _ in REFERENCE_KICK_KEYFRAMES])
_VALUES = np.array([[k.get(n, 0.0) for n in _NAMES] for _, k in REFERENCE_KICK_KEYFRAMES])

KICK_BALL_START_POS = (-0.84, -0.055)
"""Where the kicking tasks place the ball (x, y, m): 0.16 m + the ball's radius ahead of the
right foot of a robot at the default start (4 cm closer than the paper's kicks: the reference
swing reaches it on every Nao type)."""


def reference_kick_deg(t_s: float) -> dict[str, float]:
    """The reference kick's target-angle offsets (deg, by Nao effector name) ``t_s`` seconds
    into the episode (:data:`REFERENCE_KICK_KEYFRAMES`, interpolated)."""
    row = [float(np.interp(t_s, _TIMES, _VALUES[:, k])) for k in range(len(_NAMES))]
    return dict(zip(_NAMES, row, strict=True))


@dataclass
class ReferenceKickConfig(EnvConfig):
    """:class:`EnvConfig` with the reference kick's options and the defaults it needs."""

    reference_kick: bool = True
    """Add the reference kick (:func:`reference_kick_deg`) to the target angles: the action
    corrects it (a residual policy; zero actions kick and stay up). The Nao with a target-angle
    ``action_mode`` only."""
    action_mode: ActionMode | str = ActionMode.TARGET_ANGLE
    """Target angles (on the Nao: velocity = ``target_gain`` × error), …"""
    target_around_start_deg: float | None = 30.0
    """… spanning the start pose (plus the reference kick) ± 30°."""
    joint_start_deg: Any = field(default_factory=lambda: dict(PAPER_STANDING_POSE_DEG))
    """The crouched pose the kick starts from (the paper's standing pose), deg by name."""
    ball_start_pos: tuple[float, float, float] | tuple[float, float] = KICK_BALL_START_POS

    def validate(self) -> None:
        super().validate()
        if self.reference_kick and self.robot != "nao":
            raise EnvConfigError(
                f"reference_kick is a motion of the Nao, not the {self.robot}; pass "
                "reference_kick=False"
            )
        if self.reference_kick and self.action_mode is ActionMode.VELOCITY:
            raise EnvConfigError(
                "reference_kick adds to target angles; the 'velocity' action mode has none: pass "
                "reference_kick=False or a target-angle action_mode"
            )


class ReferenceKickTask:
    """Plays the reference kick under a task's actions (put before the task's environment class:
    ``class TargetKick(ReferenceKickTask, BaseEnv)``)."""

    config: ReferenceKickConfig

    def _before_action(self) -> None:
        super()._before_action()  # type: ignore[misc]
        if self.config.reference_kick:
            self._actions.set_offsets(reference_kick_deg(self.episode_step * CYCLE_S))  # type: ignore[attr-defined]

    @classmethod
    def league_defaults(cls, robot: str) -> dict[str, Any]:
        """The task's league defaults, plus no reference kick (a motion of the Nao)."""
        out = super().league_defaults(robot)  # type: ignore[misc]
        out["reference_kick"] = False
        return out

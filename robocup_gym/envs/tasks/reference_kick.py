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

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robocup_gym.envs.config import PAPER_STANDING_POSE_DEG, ActionMode, EnvConfig, EnvConfigError
from robocup_gym.robot.nao import nao_model
from robocup_gym.sim.physics import CYCLE_S

__all__ = [
    "KICK_BALL_START_POS",
    "REFERENCE_KICK_KEYFRAMES",
    "Keyframes",
    "ReferenceKickConfig",
    "ReferenceKickTask",
    "kick_offsets_deg",
    "kick_table",
    "mirror_keyframes",
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

KICK_BALL_START_POS = (-0.84, -0.055)
"""Where the kicking tasks place the ball (x, y, m): 0.16 m + the ball's radius ahead of the
right foot of a robot at the default start (4 cm closer than the paper's kicks: the reference
swing reaches it on every Nao type)."""

Keyframes = tuple[tuple[float, dict[str, float]], ...]
"""A kick as (time from the episode's start in s, offsets in deg by Nao effector name) rows."""


def kick_table(keyframes: Keyframes) -> tuple[tuple[str, ...], np.ndarray, np.ndarray]:
    """``keyframes`` as arrays: (effector names, keyframe times in s, offsets in deg with a row
    per keyframe and a column per name, 0 where a keyframe leaves a joint out)."""
    names = tuple(sorted({n for _, k in keyframes for n in k}))
    times = np.array([t for t, _ in keyframes], dtype=float)
    values = np.array([[k.get(n, 0.0) for n in names] for _, k in keyframes], dtype=float)
    return names, times, values


def kick_offsets_deg(
    table: tuple[tuple[str, ...], np.ndarray, np.ndarray], t_s: float
) -> dict[str, float]:
    """A kick's target-angle offsets (deg, by effector name) ``t_s`` seconds into it, from its
    :func:`kick_table`: linear between keyframes, the last keyframe's after it."""
    names, times, values = table
    return {n: float(np.interp(t_s, times, values[:, k])) for k, n in enumerate(names)}


def reference_kick_deg(
    t_s: float, keyframes: Keyframes = REFERENCE_KICK_KEYFRAMES
) -> dict[str, float]:
    """A kick's target-angle offsets (deg, by Nao effector name) ``t_s`` seconds into the
    episode: ``keyframes`` (default :data:`REFERENCE_KICK_KEYFRAMES`) interpolated linearly,
    0 for a joint a keyframe leaves out and after the last."""
    return kick_offsets_deg(kick_table(keyframes), t_s)


def mirror_keyframes(keyframes: Keyframes, robot_type: int = 0) -> Keyframes:
    """``keyframes`` mirrored across the robot's sagittal plane: a right-foot kick becomes the
    same kick with the left foot. Each joint's offset goes to its twin on the other side (a joint
    without one keeps its own), its sign as :attr:`NaoModel.mirror_effectors` gives it (hip and
    ankle rolls, shoulder rolls and the elbows change sign, the pitches and hip yaw-pitches do
    not; the head's yaw does)."""
    twin = nao_model(robot_type).mirror_effectors
    return tuple(
        (t, {twin[n][0]: twin[n][1] * v for n, v in offsets.items()}) for t, offsets in keyframes
    )


def _check_keyframes(keyframes: Keyframes) -> None:
    """Raises :class:`EnvConfigError` unless ``keyframes`` are (time s, {effector: deg}) rows
    with increasing finite times and finite offsets of Nao effectors."""
    rows = list(keyframes or ())
    if not all(
        isinstance(row, tuple | list)
        and len(row) == 2
        and isinstance(row[0], int | float)
        and isinstance(row[1], Mapping)
        for row in rows
    ):
        raise EnvConfigError(
            f"kick_keyframes must be (time s, {{effector: offset deg}}) rows, got {keyframes!r}"
        )
    times = [float(row[0]) for row in rows]
    if (
        not times
        or any(not math.isfinite(t) for t in times)
        or any(b <= a for a, b in itertools.pairwise(times))
    ):
        raise EnvConfigError(
            "kick_keyframes must be (time s, offsets) rows with increasing finite times, "
            f"got times {times!r}"
        )
    names = set(nao_model(0).effector_names)
    for _, offsets in rows:
        unknown = sorted(set(offsets) - names)
        if unknown:
            raise EnvConfigError(f"kick_keyframes: unknown Nao effectors {unknown}")
        if not all(math.isfinite(v) for v in offsets.values()):
            raise EnvConfigError(f"kick_keyframes: offsets must be finite, got {offsets!r}")


@dataclass
class ReferenceKickConfig(EnvConfig):
    """:class:`EnvConfig` with the reference kick's options and the defaults it needs."""

    policy_options = EnvConfig.policy_options | {
        "reference_kick", "kick_keyframes", "kick_keyframes_by_type",
    }  # fmt: skip
    """:class:`EnvConfig`'s and the kick the actions correct."""

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
    kick_keyframes: Keyframes = REFERENCE_KICK_KEYFRAMES
    """The kick played under the actions, as :data:`REFERENCE_KICK_KEYFRAMES` is written: (time
    in s, offsets in deg by Nao effector name) rows, times increasing."""
    kick_keyframes_by_type: Mapping[int, Keyframes] | None = None
    """Kicks of their own for some Nao types (type → keyframes, written as ``kick_keyframes``),
    played instead of ``kick_keyframes`` by a robot of a type listed."""

    def validate(self) -> None:
        super().validate()
        by_type = self.kick_keyframes_by_type or {}
        if not isinstance(by_type, Mapping) or not all(
            str(k).isdigit() and int(k) <= 4 for k in by_type
        ):
            raise EnvConfigError(
                f"kick_keyframes_by_type must map Nao types 0-4 to keyframes, got {by_type!r}"
            )
        for keyframes in (self.kick_keyframes, *by_type.values()):
            _check_keyframes(keyframes)
        if by_type:  # keys as JSON writes them ("4") become types
            self.kick_keyframes_by_type = {int(k): v for k, v in by_type.items()}
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

    def kick_keyframes(self) -> Keyframes:
        """The kick this robot plays: its type's in ``kick_keyframes_by_type``, else
        ``kick_keyframes``."""
        c = self.config
        return (c.kick_keyframes_by_type or {}).get(c.robot_type, c.kick_keyframes)

    def _initial_state(self, options):
        start = super()._initial_state(options)  # type: ignore[misc]
        self._kick_table = kick_table(self.kick_keyframes())
        """This episode's kick as arrays (:func:`kick_table`; a task whose kick depends on the
        episode's command sets its own)."""
        return start

    def _before_action(self) -> None:
        super()._before_action()  # type: ignore[misc]
        if self.config.reference_kick:
            t = self.episode_step * CYCLE_S  # type: ignore[attr-defined]
            self._actions.set_offsets(kick_offsets_deg(self._kick_table, t))  # type: ignore[attr-defined]

    @classmethod
    def league_defaults(cls, robot: str) -> dict[str, Any]:
        """The task's league defaults, plus no reference kick (a motion of the Nao)."""
        out = super().league_defaults(robot)  # type: ignore[misc]
        out["reference_kick"] = False
        return out

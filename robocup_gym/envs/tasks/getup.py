"""GetUp: stand up from lying on the front or the back, fast, and stay up.

The lying poses are made the way a robot comes to lie: by dropping it in the world. At the
first reset for each side the environment lets the robot fall from a tilted pose onto its front
(or back) with its joints held still (a league robot: from flat, limp) and records where it
comes to rest (torso position and orientation, joint angles); every episode then starts from
that pose, placed instantly. So no part starts inside the ground, on any engine.

On the Nao the actions correct a scripted get-up (:data:`GETUP_KEYFRAMES_BY_TYPE`: type 0's
:data:`GETUP_KEYFRAMES` and the other types' own), as Walk's correct its reference gait: the
script alone already gets the robot up from most lying poses on the default engine, and a
policy learns what it misses.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from robocup_gym.backends.base import RobotPose
from robocup_gym.envs.base_env import BaseEnv
from robocup_gym.envs.config import BALL_REST_Z, ActionMode, EnvConfig, EnvConfigError
from robocup_gym.envs.observations import up_z
from robocup_gym.robot.types import is_type_number
from robocup_gym.sim.kinematics import resting_torso_height
from robocup_gym.sim.rotations import axis_angle_quat, quat_multiply

__all__ = [
    "GETUP_FRONT_WITH_SELF_COLLISIONS",
    "GETUP_KEYFRAMES",
    "GETUP_KEYFRAMES_BY_TYPE",
    "GETUP_OBSERVATIONS",
    "GetUp",
    "GetUpConfig",
    "getup_keyframes",
    "reference_targets",
    "scripted_target",
]

GETUP_OBSERVATIONS = (
    "joint_pos",
    "joint_vel",
    "gyro",
    "accel",
    "foot_force",
    "torso_orientation",
    "torso_height",
    "last_action",
    "time",
)
"""What a get-up policy sees by default: its body, the torso's pose, and the episode's step
(where the scripted get-up is)."""

SIDES = ("front", "back")

_KEYFRAME_JOINTS = ("lae1", "lae2", "lae3", "lae4", "lle1", "lle2", "lle3", "lle4", "lle5", "lle6")
GETUP_KEYFRAMES: dict[str, tuple[tuple[float, tuple[float, ...]], ...]] = {
    "front": (
        (17, (-118.2, 4.6, 116.5, 0.0, -63.2, 29.7, 94.5, -126.7, 75.0, -37.5)),
        (29, (-109.1, 11.0, 118.4, 0.1, -89.9, 29.3, 99.1, -22.2, -44.8, 24.3)),
        (18, (115.1, -0.3, 71.6, -4.9, -8.0, 44.8, -24.9, -1.0, -41.7, -15.7)),
        (23, (-119.8, 1.8, -54.7, 1.0, -11.1, 45.0, -24.5, -9.5, 3.2, 20.9)),
    ),
    "back": (
        (15, (-86.5, 94.4, -118.9, -77.0, -72.5, -25.0, 96.2, 1.0, 74.7, -43.6)),
        (11, (-94.9, 0.1, -116.5, -11.9, -4.1, 41.0, -19.6, -25.3, -44.9, 20.3)),
        (27, (119.5, -0.7, -116.7, 0.2, -86.4, -1.4, 99.5, -6.7, -43.7, 24.6)),
        (19, (-65.0, -0.6, -114.0, 0.3, -3.0, 44.8, 8.1, -22.2, 18.1, 20.6)),
    ),
}
"""The Nao's scripted get-ups (``GetUpConfig.reference_motion``), per side: keyframes of
(cycles held, target angles in deg of ``lae1 lae2 lae3 lae4 lle1 lle2 lle3 lle4 lle5 lle6``; the
right joints mirror them); the last is held to the episode's end. Found by an open-loop search
(CMA-ES) on the ODE engine, Nao type 0, from the first trained policies' motions: over lying
poses 0–15, then 0–13 each played clean and with 1.5° of noise on every target, so that the
script stands a policy's exploration (docs/training.md, *Get-up*)."""
GETUP_KEYFRAMES_BY_TYPE: dict[int, dict[str, tuple[tuple[float, tuple[float, ...]], ...]]] = {
    0: GETUP_KEYFRAMES,
    1: {
        "front": (
            (23, (-71.0, 10.2, 120.0, 1.0, -62.9, 15.3, 74.3, -130.0, 60.4, -45.0)),
            (28, (-103.6, 36.5, 120.0, -29.2, -90.0, 12.5, 100.0, -36.4, -38.1, 23.8)),
            (20, (120.0, -1.0, 83.8, -16.3, -16.8, 40.7, -8.4, -16.3, -29.8, -11.7)),
            (21, (-108.7, 5.6, -70.1, -15.6, 1.0, 42.3, -10.6, -6.7, 7.0, -8.7)),
        ),
        "back": (
            (19, (-101.7, 95.0, -91.1, -52.5, -90.0, -25.0, 100.0, -26.9, 66.4, -3.4)),
            (13, (-97.5, 32.2, -120.0, -15.4, -22.6, 25.0, -25.0, -8.9, -38.2, 25.0)),
            (32, (81.4, -1.0, -94.6, -6.0, -64.5, 25.8, 96.3, -24.7, -43.3, -9.0)),
            (14, (-40.1, 4.8, -120.0, 1.0, -4.1, 45.0, 22.3, -42.4, 18.8, -8.3)),
        ),
    },
    2: {
        "front": (
            (19, (-113.8, 11.9, 120.0, 0.5, -70.1, 39.0, 97.9, -130.0, 72.9, -20.1)),
            (29, (-109.1, 13.5, 114.2, 1.0, -90.0, 25.8, 100.0, -18.8, -45.0, 25.0)),
            (16, (116.5, -1.0, 65.3, -14.7, 1.0, 45.0, -25.0, 1.0, -31.8, -7.5)),
            (25, (-107.7, 5.6, -53.5, 1.0, -11.8, 38.8, -12.5, -5.9, -2.2, 0.8)),
        ),
        "back": GETUP_KEYFRAMES["back"],
    },
    3: {
        "front": (
            (17, (-109.5, 26.3, 120.0, -50.1, -67.6, 16.2, 84.2, -130.0, 75.0, -39.2)),
            (29, (-120.0, 49.9, 120.0, 1.0, -90.0, 31.6, 95.4, -31.2, -37.3, 21.5)),
            (19, (120.0, 8.4, 65.6, -17.3, -26.4, 45.0, -22.0, -2.7, -45.0, -13.5)),
            (18, (-114.5, 29.5, -61.9, 1.0, -1.7, 45.0, -23.1, -16.6, 11.0, 25.0)),
        ),
        "back": (
            (24, (-109.1, 95.0, -75.5, -85.6, -60.7, -12.1, 95.0, -14.0, 75.0, -28.8)),
            (9, (-101.6, -1.0, -120.0, 1.0, -5.3, 5.1, -15.4, -6.7, -34.0, 25.0)),
            (30, (98.6, -1.0, -111.0, 1.0, -66.0, 30.9, 100.0, -29.8, -30.6, 15.4)),
            (3, (-41.6, -0.8, -85.0, -31.9, 1.0, 45.0, 17.4, -26.9, 10.6, 22.1)),
        ),
    },
    4: {
        "front": (
            (22, (-117.5, 2.9, 114.7, -0.4, -76.5, 31.8, 86.9, -127.2, 72.4, -37.1)),
            (27, (-107.8, 25.5, 115.2, 1.0, -90.0, 27.9, 100.0, -19.7, -45.0, 17.4)),
            (18, (116.7, 12.3, 70.9, -3.1, 1.0, 43.5, -25.0, -0.1, -40.6, -23.3)),
            (23, (-109.3, 3.3, -63.2, -13.8, 1.0, 45.0, -25.0, -10.8, 5.8, 24.7)),
        ),
        "back": GETUP_KEYFRAMES["back"],
    },
}
"""The scripted get-up of every Nao type (same layout as :data:`GETUP_KEYFRAMES`, type 0's;
angles within the joints' ranges; type 4's toes stay at 0). Types 1 and 3 (longer legs: type
0's script gets them up from the back from none of 16 lying poses) have their own for both
sides, types 2 and 4 from the front; their backs are type 0's. Found by the same open-loop
CMA-ES on the ODE engine as type 0's, started from type 0's script: over lying poses 0–11, each
played clean and with 1.5° of target noise, for the task's return and then for getting up
within 80 cycles; type 3's back again with the targets kept 0.5° off the stops
(``target_stop_margin_deg``), on which its first script leant. Over lying poses 0–63 each gets
its type up within 80 cycles from 58 to 64 poses a side (docs/results.md)."""


GETUP_FRONT_WITH_SELF_COLLISIONS: dict[int, tuple[tuple[float, tuple[float, ...]], ...]] = {
    0: (
        (17, (-119.5, -0.5, 119.5, 0.5, -70.2, 29.9, 94.2, -105.6, 74.5, -43.2)),
        (29, (-106.5, -0.5, 108.7, 0.5, -89.9, 38.7, 99.5, -15.4, -42.4, 24.5)),
        (18, (115.1, -0.3, 71.6, -4.9, -8.0, 44.5, -24.5, -1.0, -41.7, -15.7)),
        (23, (-119.5, 1.8, -54.7, 0.5, -11.1, 44.5, -24.5, -9.5, 3.2, 20.9)),
    ),
    1: (
        (23, (-69.7, 10.5, 115.4, 0.5, -75.6, 21.3, 71.0, -116.1, 74.5, -33.7)),
        (28, (-89.7, 30.1, 93.1, -19.5, -88.3, 10.0, 99.5, -43.8, -43.3, 24.5)),
        (20, (119.5, -0.5, 83.8, -16.3, -16.8, 40.7, -8.4, -16.3, -29.8, -11.7)),
        (21, (-108.7, 5.6, -70.1, -15.6, 0.5, 42.3, -10.6, -6.7, 7.0, -8.7)),
    ),
    2: (
        (19, (-119.4, 20.9, 117.1, 0.5, -69.3, 37.5, 87.0, -129.5, 70.7, -21.4)),
        (29, (-94.4, 9.5, 109.2, -8.4, -83.5, 21.7, 97.4, -22.1, -44.5, 15.1)),
        (16, (116.5, -0.5, 65.3, -14.7, 0.5, 44.5, -24.5, 0.5, -31.8, -7.5)),
        (25, (-107.7, 5.6, -53.5, 0.5, -11.8, 38.8, -12.5, -5.9, -2.2, 0.8)),
    ),
    3: (
        (17, (-80.9, 40.7, 119.5, -50.4, -66.4, 7.7, 99.5, -113.2, 74.5, -31.2)),
        (29, (-110.8, 37.0, 119.5, 0.5, -87.0, 32.9, 99.5, -40.2, -24.7, 24.5)),
        (19, (119.5, 8.4, 65.6, -17.3, -26.4, 44.5, -22.0, -2.7, -44.5, -13.5)),
        (18, (-114.5, 29.5, -61.9, 0.5, -1.7, 44.5, -23.1, -16.6, 11.0, 24.5)),
    ),
    4: (
        (22, (-119.5, 3.1, 117.4, 0.5, -75.0, 43.9, 85.6, -129.5, 74.5, -44.5)),
        (27, (-115.4, -0.5, 103.5, 0.5, -89.9, 35.7, 99.5, -36.1, -24.8, 10.3)),
        (18, (116.7, 12.3, 70.9, -3.1, 0.5, 43.5, -24.5, -0.1, -40.6, -23.3)),
        (23, (-109.3, 3.3, -63.2, -13.8, 0.5, 44.5, -24.5, -10.8, 5.8, 24.5)),
    ),
}
"""The get-ups from the front where the self-collision rule runs (``self_collisions=True``,
``GetUp-v1``; reference §9.7), per Nao type (the same layout as :data:`GETUP_KEYFRAMES`; a type
not listed plays its own script). Pushing up, the scripts of :data:`GETUP_KEYFRAMES_BY_TYPE` put
the lower arms into the shanks or thighs; a real server then freezes those arms and legs for a
second and the robot falls back (type 0's script alone gets up from 30 of 64 lying poses). These
keep the forearms out of the legs: found by the same CMA-ES over the first two keyframes, from
the old script, on lying poses 0–15 with the rule (type 3: 40 generations in two runs; types 0,
1 and 4 again over poses 0–31, every other one with 1.5° of target noise); over poses 0–63
(docs/results.md)."""


def getup_keyframes(
    robot_type: int, self_collisions: bool = False
) -> dict[str, tuple[tuple[float, tuple[float, ...]], ...]]:
    """The scripted get-up (keyframes per side) that Nao type ``robot_type`` (0–4) plays, in a
    world without or with the self-collision rule (``self_collisions``).

    Raises:
        ValueError: for another number.
    """
    frames = GETUP_KEYFRAMES_BY_TYPE.get(robot_type)
    if frames is None:
        raise ValueError(f"Nao types are 0-4, got {robot_type!r}")
    front = GETUP_FRONT_WITH_SELF_COLLISIONS.get(robot_type)
    if self_collisions and front is not None:
        return {**frames, "front": front}
    return frames


DROP_CYCLES = 100
"""Cycles a dropped robot is given to come to rest (2 s) before an episode starts."""
LYING_POSE_STOP_MARGIN_DEG = 1.0
"""How far inside its stops every joint angle of a lying pose stays, deg."""


@dataclass
class GetUpConfig(EnvConfig):
    """:class:`EnvConfig` plus GetUp's start and reward options."""

    policy_options = EnvConfig.policy_options | {
        "reference_motion", "script_robot_type", "reference_reach_deg",
    }  # fmt: skip
    """:class:`EnvConfig`'s and the scripted get-up the actions correct."""

    observations: tuple[str, ...] = GETUP_OBSERVATIONS
    action_mode: ActionMode | str = ActionMode.TARGET_ANGLE
    """Target angles (a get-up is a sequence of poses): learns far faster than velocities here
    (unassisted evaluation return ~150 after 300k steps against ~15 after 2M with velocities)."""
    mirror_actions: bool = True
    """Left and right joints mirror each other (a get-up is symmetric; 10 action values)."""
    ball_start_pos: tuple[float, float, float] = (1.0, 0.0, BALL_REST_Z)
    """2 m ahead of the robot, out of its way (at the kicks' default spot it lay on the ball)."""
    max_episode_steps: int = 150
    """3 s to get up (the reference team's get-up takes 55–66 cycles)."""
    terminate_on_fall: bool = False
    """The robot starts on the ground: lying is not an end here."""
    start_side: str = "random"
    """``"front"``, ``"back"`` or ``"random"`` (each episode one of the two)."""
    lying_poses: int = 16
    """Distinct lying poses per side; each episode starts from one drawn at random. Pose 0 is
    the drop from 80° with every joint at 0; poses 1… come from drops with the tilt and every
    joint angle drawn within ± ``lying_pose_spread_deg`` of that (a fixed draw per pose, the
    same in every environment), so that a policy meets, and a benchmark measures, more than
    one way of lying."""
    reference_motion: bool = True
    """The Nao: zero actions play a scripted get-up (:data:`GETUP_KEYFRAMES_BY_TYPE`, one per
    type and side: target angles held for a number of cycles, the right side mirroring the
    left) and the action corrects it, ± ``reference_reach_deg`` around each target (a residual
    policy, as Walk's over its reference gait). ``False``, or the ``velocity`` action mode: the
    action alone sets the targets (velocities), over the window of ``target_around_start_deg``
    (by default each joint's whole range)."""
    script_robot_type: int | None = None
    """With ``reference_motion``: which Nao type's scripted get-up plays
    (:data:`GETUP_KEYFRAMES_BY_TYPE`; ``None``: the robot's own type's). The shipped ``get-up``,
    a small residual learnt over type 0's script, does better on types 1 and 3 over their own
    scripts than over type 0's (docs/training.md, *Get-up*), so ``None`` serves it
    too; a number pins one script."""
    reference_reach_deg: float = 5.0
    """With ``reference_motion``: how far an action of ±1 moves a target from the scripted
    one, deg (clipped to the joint's range). Small: the script stands random noise of 1–2°
    on its targets but not a policy's steady offsets of a few degrees (residual policies
    with 20° of reach got up from the back less often than zero actions)."""
    lying_pose_spread_deg: float = 10.0
    """How far poses 1… are drawn from pose 0: tilt and joint angles, ± deg (joint angles
    kept in range)."""
    success_height: float = 0.28
    """Torso centre height above which the robot counts as up, m."""
    success_tilt_deg: float = 30.0
    """…with the torso inclined less than this, deg…"""
    success_hold_steps: int = 50
    """…for this many consecutive steps (1 s): then the episode ends with success."""
    w_height: float = 6.0
    """Weight of the torso height (m, up to ``height_cap``), every step: large against
    ``w_upright``, so that sitting upright (0.16 m) pays much less than standing."""
    height_cap: float = 0.40
    """Torso heights above this pay no more, m (a little above the standing Nao's 0.385 m):
    jumping is not getting up, and without the cap PPO learns to spring off the ground."""
    w_upright: float = 0.5
    """Weight of the world z of the torso's up axis, every step."""
    w_time: float = -0.5
    """Paid every step the robot is not up (hurry)."""
    w_action_rate: float = -0.01
    """Weight of |a_t − a_{t−1}|²."""
    success_bonus: float = 50.0
    """Paid once on success, scaled by the share of the episode left (faster = more)."""

    def validate(self) -> None:
        super().validate()
        if self.start_side not in (*SIDES, "random"):
            raise EnvConfigError(
                f"start_side must be 'front', 'back' or 'random', got {self.start_side!r}"
            )
        if not (isinstance(self.lying_poses, int | np.integer) and 1 <= self.lying_poses <= 64):
            raise EnvConfigError(
                f"lying_poses must be an integer in 1..64, got {self.lying_poses!r}"
            )
        if not (
            math.isfinite(self.lying_pose_spread_deg) and 0.0 <= self.lying_pose_spread_deg <= 45.0
        ):
            raise EnvConfigError("lying_pose_spread_deg must be between 0 and 45 deg")
        if not (math.isfinite(self.reference_reach_deg) and self.reference_reach_deg > 0.0):
            raise EnvConfigError(
                f"reference_reach_deg must be > 0 deg, got {self.reference_reach_deg!r}"
            )
        st = self.script_robot_type
        if st is not None and not is_type_number(st):
            raise EnvConfigError(
                f"script_robot_type must be one of the integers 0, 1, 2, 3, 4 or None, got {st!r}"
            )
        if self.reference_motion and self.robot != "nao":
            raise EnvConfigError(
                f"reference_motion is a scripted get-up for the Nao, not the {self.robot}; pass "
                "reference_motion=False"
            )
        if not (math.isfinite(self.height_cap) and self.height_cap > 0.0):
            raise EnvConfigError(f"height_cap must be > 0 m, got {self.height_cap!r}")
        if not (0.0 < self.success_height < 1.5):
            raise EnvConfigError("success_height must be between 0 and 1.5 m")
        if not (0.0 < self.success_tilt_deg < 90.0):
            raise EnvConfigError("success_tilt_deg must be between 0 and 90 deg")
        if not (
            isinstance(self.success_hold_steps, int | np.integer) and self.success_hold_steps >= 1
        ):
            raise EnvConfigError("success_hold_steps must be an integer >= 1")
        for name in ("w_height", "w_upright", "w_time", "w_action_rate", "success_bonus"):
            if not math.isfinite(getattr(self, name)):
                raise EnvConfigError(f"{name} must be finite, got {getattr(self, name)!r}")


class GetUp(BaseEnv):
    """Get up from lying on the front or the back.

    Each episode starts from a lying pose made by dropping the robot (see the module docstring),
    on its front or back (``start_side``). The robot is *up* when its torso centre is above
    ``success_height`` (0.28 m) and inclined less than ``success_tilt_deg`` (30°); up for
    ``success_hold_steps`` (50 = 1 s) in a row ends the episode with success (``info["success"]``,
    ``info["steps_to_up"]``: the step at which it got up for good). Every step pays:

    ===================  =========  ===========================================================
    term                 default w  value
    ===================  =========  ===========================================================
    ``height``           6.0        torso centre height, m, at most ``height_cap`` (0.40)
    ``upright``          0.5        world z of the torso's up axis
    ``time``             −0.5       while not up
    ``action_rate``      −0.01      |a_t − a_{t−1}|²
    ``success``          50         once, × (1 + share of the episode left)
    ===================  =========  ===========================================================

    Actions are target angles of mirrored left/right joint pairs (10 values on the Nao:
    ``action_mode="target_angle"``, ``mirror_actions=True``); on the Nao they correct a scripted
    get-up (``reference_motion``: a zero action plays the robot type's script,
    :data:`GETUP_KEYFRAMES_BY_TYPE`, or ``script_robot_type``'s; ±1 moves each target
    ``reference_reach_deg`` from it). ``reset(options={"start_side":
    "back", "lying_pose": 3})`` picks the side (and the lying pose, any of 0–63 whatever
    ``lying_poses`` is) of one episode; ``lying_poses`` > 1 varies the lying pose. Works on
    every Nao type, on both in-process engines, on the league's robots, and on a real
    rcssserver3d whose trainer turns robots (the SPL fork's ``rot``; the lying poses are then
    dropped on the ODE engine). ``TorsoAssist`` (``robocup-gym train get-up --assist-force …``)
    helps while training.

    Version history:

    * v1: rcssserver3d's self-collision rule runs (``self_collisions=True``), as on a real
      server and in a game, with the get-ups from the front that keep clear of it
      (:data:`GETUP_FRONT_WITH_SELF_COLLISIONS`).
    * v0: first release (robocup-gym 0.2.0).
    """

    config_class = GetUpConfig

    @classmethod
    def league_defaults(cls, robot: str) -> dict[str, Any]:
        """:meth:`BaseEnv.league_defaults`, plus: ``success_height`` 0.73 × the robot's
        standing torso height (as 0.28 m is of the Nao's 0.384 m), ``height_cap`` 1.04 × it
        (as 0.40 m is of the Nao's), and the ball 2 m ahead of
        the robot, out of the way (``rcsssmj`` 0.2.1 fails when the ball touches the K1's
        unnamed body parts)."""
        from robocup_gym.envs.config import league_robot_of

        out = super().league_defaults(robot)
        r = league_robot_of(robot)
        x, y = cls.config_class().robot_start_pos
        out["success_height"] = round(0.73 * r.standing_torso_height, 3)
        out["height_cap"] = round(1.04 * r.standing_torso_height, 3)
        out["mirror_actions"] = False  # the Nao's option
        out["reference_motion"] = False  # a script for the Nao
        out["ball_start_pos"] = (x + 2.0, y, r.ball_radius)
        return out

    config: GetUpConfig
    task_reset_options = frozenset({"start_side", "lying_pose"})

    """Backends whose worlds the lying poses are dropped in; for a real server they are dropped
    on the ODE engine (SimSpark's own step), which it runs."""

    def __init__(self, config: GetUpConfig | None = None, **kwargs: Any) -> None:
        super().__init__(config, **kwargs)
        self._script: dict[str, list[tuple[float, np.ndarray]]] | None = None
        if self.config.reference_motion and self._actions.mode is not ActionMode.VELOCITY:
            script_type = self.config.script_robot_type
            keyframes = getup_keyframes(
                self.config.robot_type if script_type is None else script_type,
                self.config.self_collisions,
            )
            self._script = {
                side: reference_targets(self.robot_model, self._actions.joints, side, keyframes)
                for side in SIDES
            }
            self._actions.set_window(0.0, self.config.reference_reach_deg)
        if not self.backend.places_any_orientation:
            name = self.backend.name
            self.close()
            raise EnvConfigError(
                f"GetUp starts the robot lying down, which the {name!r} backend cannot place "
                "(a real rcssserver3d can only where its trainer turns robots: the SPL fork's "
                "(rot …)); train and evaluate it in-process (the default), or place the robot "
                "yourself"
            )
        self._lying: dict[tuple[str, int], tuple[float, np.ndarray, np.ndarray]] = {}
        self.side = "front"
        self.pose_index = 0
        self._up_steps = 0
        self._prev_action = np.zeros(self.action_space.shape)
        self.success = False
        self._pay_bonus = False
        self.steps_to_up: int | None = None

    # ------------------------------------------------------------------ lying poses
    def lying_pose(self, side: str, index: int = 0) -> tuple[float | None, np.ndarray, np.ndarray]:
        """``(torso z m, torso quat, joint angles deg)`` from which the robot is dropped to lie
        on ``side`` (lying pose ``index``, see ``GetUpConfig.lying_poses``): tilted forward
        (front) or backward (back), its lowest point resting 1 mm deep; every episode from it
        first settles :data:`DROP_CYCLES` cycles with the joints held (``EpisodeStart.
        settle_cycles``), on an in-process engine and on a real server alike. Joint angles stay
        :data:`LYING_POSE_STOP_MARGIN_DEG` inside each joint's stops, where a real server can
        drive them (it ignores a joint's commands on a stop). ``z`` is ``None`` for a league
        robot (its backend puts its lowest point on the ground)."""
        key = (side, int(index))
        if key not in self._lying:
            # tilted forward (front) or backward (back): upright facing +x (the torso's forward
            # axis is its +y: turned -90° about z), then pitched about the world's y axis (+: the
            # top goes forward, +x). The Nao by 80°, joints held; a league robot flat (90°, its
            # lowest point on the ground) and limp: held stiff, the tall T1 and K1 come to rest
            # propped on toes and hands, differently on different MuJoCo versions.
            tilt_deg = 90.0 if self.league else 80.0
            n = len(self.robot_model.joints)
            start = np.zeros(n)
            if index > 0:  # a fixed draw per pose: the same poses in every environment
                rng = np.random.default_rng([int(index), SIDES.index(side)])
                spread = self.config.lying_pose_spread_deg
                tilt_deg = min(90.0, tilt_deg + rng.uniform(-spread, spread))
                lo, hi = np.asarray(self.robot_model.ranges_deg, dtype=float).T
                margin = LYING_POSE_STOP_MARGIN_DEG
                start = np.clip(rng.uniform(-spread, spread, n), lo + margin, hi - margin)
            tilt = math.radians(tilt_deg) * (1.0 if side == "front" else -1.0)
            yaw = axis_angle_quat((0.0, 0.0, 1.0), -math.pi / 2)
            pitch = axis_angle_quat((0.0, 1.0, 0.0), tilt)
            quat = quat_multiply(pitch, yaw)
            z = None if self.league else resting_torso_height(self.config.robot_type, start, quat)
            self._lying[key] = (z, quat, start)
        return self._lying[key]

    # ------------------------------------------------------------------ episode
    def _initial_state(self, options):
        side = options.get("start_side", self.config.start_side)
        if side == "random":
            side = SIDES[int(self.np_random.integers(2))]
        if side not in SIDES:
            raise ValueError(f"reset option start_side must be 'front' or 'back', got {side!r}")
        start = super()._initial_state(options)
        n_poses = self.config.lying_poses
        k = int(self.np_random.integers(n_poses)) if n_poses > 1 else 0
        if options.get("lying_pose") is not None:
            k = options["lying_pose"]
            if not (isinstance(k, int | np.integer) and 0 <= k < 64):
                raise ValueError(f"reset option lying_pose must be an integer in 0..63, got {k!r}")
            k = int(k)
        z, quat, angles = self.lying_pose(side, k)
        if self._start_noise.any():  # joint_start_noise_deg varies the drop (inside the stops)
            lo, hi = self._ranges[:, 0], self._ranges[:, 1]
            noisy = angles + self.np_random.normal(0.0, 1.0, angles.shape) * self._start_noise
            margin = LYING_POSE_STOP_MARGIN_DEG
            angles = np.clip(noisy, lo + margin, hi - margin)
            if z is not None:
                z = resting_torso_height(self.config.robot_type, angles, quat)
        self.side = side
        self.pose_index = k
        self._up_steps = 0
        self._prev_action = np.zeros(self.action_space.shape)
        self.success = False
        self._pay_bonus = False
        self.steps_to_up = None
        start.pose = RobotPose(
            start.pose.x, start.pose.y, joint_angles_deg=angles.copy(), z=z, quat=quat.copy()
        )
        start.settle_cycles = DROP_CYCLES
        return start

    def _before_action(self) -> None:
        if self._script is not None:
            self._actions.target_offset_deg[:] = scripted_target(
                self._script[self.side], self.episode_step
            )

    def _is_up(self) -> bool:
        gt = self.ground_truth
        c = self.config
        return bool(
            gt.torso_pos[2] > c.success_height
            and up_z(gt.torso_quat) > math.cos(math.radians(c.success_tilt_deg))
        )

    def _is_terminated(self) -> bool:
        return self.success

    def _reward_terms(self, action: np.ndarray) -> dict[str, float]:
        c = self.config
        gt = self.ground_truth
        up = self._is_up()
        terms = {
            "height": c.w_height * min(float(gt.torso_pos[2]), c.height_cap),
            "upright": c.w_upright * up_z(gt.torso_quat),
            "time": 0.0 if up else c.w_time,
            "action_rate": c.w_action_rate * float(np.sum((action - self._prev_action) ** 2)),
            "success": 0.0,
        }
        self._prev_action = np.array(action, dtype=float)
        if self._pay_bonus:
            self._pay_bonus = False
            left = 1.0 - self.episode_step / c.max_episode_steps
            terms["success"] = c.success_bonus * (1.0 + left)
        return terms

    def _set_perception(self, p, cycles: int = 1, episode_over: bool = False) -> None:
        super()._set_perception(p, cycles, episode_over)
        if episode_over or self.ground_truth is None or self.episode_step < 1:
            return  # counted over the episode's steps (not its first observation)
        if self._is_up():
            self._up_steps += 1
            if self._up_steps >= self.config.success_hold_steps and not self.success:
                self.success = True
                self._pay_bonus = True
                self.steps_to_up = self.episode_step - self._up_steps + 1
        else:
            self._up_steps = 0

    def _info(self) -> dict[str, Any]:
        info = super()._info()
        info["start_side"] = self.side
        info["lying_pose"] = self.pose_index
        info["success"] = self.success
        info["steps_to_up"] = self.steps_to_up
        return info


def reference_targets(
    model: Any, joints: np.ndarray, side: str, keyframes: Mapping[str, Any] | None = None
) -> list[tuple[float, np.ndarray]]:
    """The scripted get-up for ``side`` as ``(end cycle, target deg per controlled joint)``
    (``joints``: canonical indices in action order; a right joint mirrors its left one's target
    by :attr:`~robocup_gym.robot.nao.NaoModel.mirror_pairs`; joints the script does not name,
    the head, get 0). ``keyframes``: a table like :data:`GETUP_KEYFRAMES` (default: the
    model's robot type's, :func:`getup_keyframes`)."""
    if keyframes is None:
        keyframes = getup_keyframes(model.robot_type.index)
    index = {n: i for i, n in enumerate(model.effector_names)}
    sign = {left: (right, sg) for left, right, sg in model.mirror_pairs}
    where = {int(j): k for k, j in enumerate(joints)}
    out: list[tuple[float, np.ndarray]] = []
    end = 0.0
    for cycles, angles in keyframes[side]:
        targets = np.zeros(len(joints))
        for name, deg in zip(_KEYFRAME_JOINTS, angles, strict=True):
            left = index[name]
            if left in where:
                targets[where[left]] = deg
            right, sg = sign[left]
            if right in where:
                targets[where[right]] = sg * deg
        end += float(cycles)
        out.append((end, targets))
    return out


def scripted_target(script: list[tuple[float, np.ndarray]], step: int) -> np.ndarray:
    """The script's target angles (deg) at episode step ``step``: the keyframe whose cycles it
    falls in, or the last."""
    for end, targets in script:
        if step < end:
            return targets
    return script[-1][1]

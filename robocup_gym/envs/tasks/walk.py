"""Walk: follow a commanded planar velocity (forward, sideways, turn) without falling.

The reward is a sum of small named terms in the style of the best locomotion environments
(MuJoCo Playground's, legged_gym's): Gaussian kernels for tracking the commanded velocity, an
upright torso, foot-contact timing, and penalties on the action rate and the joint speeds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robocup_gym.envs.base_env import BaseEnv, reset_numbers
from robocup_gym.envs.config import (
    PAPER_STANDING_POSE_DEG,
    ActionMode,
    EnvConfig,
    EnvConfigError,
)
from robocup_gym.envs.observations import heading_frame, in_heading_frame, up_z
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.types import Perception

__all__ = [
    "MOVING_SPEED_MPS",
    "MOVING_TURN_DPS",
    "WALK_OBSERVATIONS",
    "Walk",
    "WalkConfig",
    "asks_to_move",
    "reference_gait_deg",
    "walk_reward_terms",
]

WALK_OBSERVATIONS = (
    "joint_pos",
    "joint_vel",
    "gyro",
    "accel",
    "foot_force",
    "torso_orientation",
    "torso_height",
    "torso_velocity",
    "velocity_command",
    "gait_phase",
    "last_action",
)
"""What a walking policy sees by default: its body, the torso's pose and velocity, the command,
the gait clock and its last action."""


@dataclass
class WalkConfig(EnvConfig):
    """:class:`EnvConfig` plus Walk's command and reward options."""

    policy_options = EnvConfig.policy_options | {
        "gait_frequency_hz", "swing_share", "reference_gait", "gait_sway_deg", "gait_lift_deg",
        "gait_stride_deg_per_mps", "gait_stride_max_deg", "gait_side_deg_per_mps",
        "gait_side_max_deg", "gait_turn_deg_per_dps", "gait_turn_max_deg", "gait_lead_s",
        "command_feedback_gain", "command_accel_limit", "track_told_command", "forward_speed_range",
        "sideways_speed_range", "turn_rate_range",
    }  # fmt: skip
    """:class:`EnvConfig`'s, the reference gait's, how the walk takes its command and the
    commands it knows (their ranges also bound the command loop's)."""

    observations: tuple[str, ...] = WALK_OBSERVATIONS
    max_episode_steps: int = 500
    """10 s episodes."""
    joint_start_deg: Any = field(default_factory=lambda: dict(PAPER_STANDING_POSE_DEG))
    """The crouched pose walking starts from (the paper's standing pose), deg by name."""
    action_mode: ActionMode | str = ActionMode.TARGET_ANGLE
    """Target angles (on the Nao: velocity = ``target_gain`` × error), …"""
    target_around_start_deg: float | None = 30.0
    """… spanning the start pose ± 30°: action 0 stands in the walking pose."""
    gait_frequency_hz: float = 3.0
    """Gait cycles (one step of each foot) per second: the clock of the ``gait_phase``
    observation, of the reference gait and of the ``feet_phase`` reward; each episode starts it
    at a random phase."""
    swing_share: float = 0.4
    """Share of a gait cycle each foot is meant to be in the air while the command asks to move:
    the left foot for φ within ``swing_share``/2 of 0.25, the right within it of 0.75."""
    reference_gait: bool = True
    """Add an open-loop stepping pattern, clocked by the gait phase, to the target angles while
    the command asks to move (:func:`reference_gait_deg`): the action corrects it (a residual
    policy; zero actions step). The Nao with a target-angle ``action_mode`` only (the velocity
    mode has no targets to add to, and ignores it)."""
    gait_sway_deg: float = 0.0
    """Reference gait: amplitude of the hip and ankle roll that shifts the weight onto the
    standing foot, deg (at 3 Hz the steps are short enough to need none: 3° fell once in 16
    zero-action episodes at 0.5 m/s, 0° never)."""
    gait_lift_deg: float = 16.0
    """Reference gait: peak leg lift of the swinging foot (hip and ankle pitch + this, knee pitch
    − twice this), deg."""
    gait_stride_deg_per_mps: float = 40.0
    """Reference gait: amplitude of the fore-aft hip/ankle pitch swing per m/s of commanded
    forward speed, deg per m/s (open loop on ODE at 3 Hz, zero actions walk ~1.07 × the command
    up to the largest stride)."""
    gait_stride_max_deg: float = 20.0
    """Reference gait: largest stride amplitude, deg (20°: 0.54 m/s open loop; 25° falls)."""
    gait_side_deg_per_mps: float = 40.0
    """Reference gait: amplitude of the sideways hip roll swing (the ankles keep the feet flat)
    per m/s of commanded leftward speed, deg per m/s (open loop: ~0.025 m/s per degree)."""
    gait_side_max_deg: float = 12.0
    """Reference gait: largest sideways swing, deg (12°: 0.30 m/s open loop; 14° falls)."""
    gait_turn_deg_per_dps: float = 0.3
    """Reference gait: amplitude of the hip yaw-pitch swing per deg/s of commanded turn rate,
    deg per (deg/s) (open loop: 4° turns ~16°/s)."""
    gait_turn_max_deg: float = 10.0
    """Reference gait: largest hip yaw-pitch swing, deg."""
    gait_lead_s: float = 0.05
    """Reference gait: how far ahead of the gait clock the pattern plays, s: a foot leaves the
    ground about this long after its lift is commanded (the joints' lag), so a lead lets the
    feet swing when the clock (and ``feet_phase``) asks."""
    feet_air_time_target_s: float | None = None
    """Air time above which a step is paid (``feet_air_time``), s; ``None``: the swing the
    clock asks for, ``swing_share`` / ``gait_frequency_hz`` (0.133 s at 3 Hz)."""
    forward_speed_range: tuple[float, float] = (-0.3, 0.8)
    """Commanded forward speed, m/s, drawn uniformly."""
    sideways_speed_range: tuple[float, float] = (-0.3, 0.3)
    """Commanded leftward speed, m/s."""
    turn_rate_range: tuple[float, float] = (-45.0, 45.0)
    """Commanded turn rate, deg/s (CCW positive)."""
    single_axis_command_prob: float = 0.0
    """Probability that a moving command has one component only (forward, sideways or turning,
    each as likely, drawn from its range): the pure motions at the ranges' ends, which a
    uniform draw over all three rarely gives."""
    command_feedback_gain: float = 0.0
    """Closes the loop around the command, 1/s (0: the policy and the reference gait get the
    command as given). Above 0 they get the command plus the integral of (command − measured
    planar velocity) × this gain, and a turn toward the heading the command asks for (the
    heading error × this gain, the error held within ±45°), clipped to the command ranges: a
    walk that drifts or falls short of the command goes where it is told, as far as those ranges
    allow. The velocity and heading are the torso's, as the ``torso_velocity`` and
    ``torso_orientation`` observations give them; a new command starts the loop afresh."""
    command_accel_limit: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """How fast the command the walk works for may grow toward the command given: forward and
    sideways in m/s², turn in deg/s² (0: at once). A command asking for less than the last one
    (slower, or standing) takes effect at once; one of the other sign starts again from zero.
    Every episode starts from a standing command, so the walk sets off gradually (setting off
    at once at 0.5 m/s, the shipped walk fell within 1.5 s in 3 of 100 starts on Nao type 1).
    The command loop (``command_feedback_gain``) works for the command so limited."""
    track_told_command: bool = False
    """The tracking terms pay for following the command the policy is told (``policy_command``:
    with ``command_feedback_gain``, the command corrected by the loop) instead of the command
    given. A policy trained so obeys the loop's corrections, turns toward the commanded heading
    included, rather than learning to ignore them; the loop then takes it where the command
    asks. Without a loop the two commands are the same."""
    command_change_steps: int = 250
    """A new command is drawn every this many steps (0 = one command per episode)."""
    standing_command_prob: float = 0.2
    """Probability that a drawn command is zero (stand still); at 0.1 a walk learns standing
    still less well (docs/training.md, *Walk*)."""
    tracking_sigma: float = 0.1
    """Width of the tracking kernels exp(−error² / σ), (m/s)² and (rad/s)² (MuJoCo Playground:
    0.25; at 0.25 standing still pays much of what walking does, and the policy stands)."""
    tracking_turn_sigma: float | None = None
    """Width of the turn tracking kernel, (rad/s)²; ``None``: ``tracking_sigma``."""
    w_tracking_linear: float = 1.5
    """Weight of exp(−|v_xy − command_xy|² / σ) per step."""
    w_tracking_turn: float = 0.8
    """Weight of exp(−(ω − command_ω)² / σ) per step (ω in rad/s)."""
    w_progress: float = 0.0
    """Weight of the torso's speed along the heading it started the episode with, m/s (the
    distance covered that way: FC Portugal's running reward); 0 in Walk, which tracks the
    command instead."""
    progress_cap_mps: float | None = None
    """The speed beyond which ``progress`` pays no more, m/s (``None``: no cap). With a cap a
    policy that already runs that fast gains nothing by running faster and can trade the rest
    for not falling."""
    w_upright: float = 0.3
    """Weight of the torso's up axis z component (1 upright)."""
    w_feet_phase: float = 0.5
    """Weight of the share of feet (0, ½ or 1) whose ground contact is what the gait clock asks
    for (both down while the command is to stand)."""
    w_feet_air_time: float = 1.0
    """Weight of Σ (air time − ``feet_air_time_target_s``) over the feet that touch down this
    step (only while the command asks to move): rewards steps of a useful length."""
    w_action_rate: float = -0.02
    """Weight of |a_t − a_{t−1}|² (actions in [-1, 1])."""
    w_joint_speed: float = -2e-4
    """Weight of Σ joint speed² (rad/s)², a proxy for effort."""
    w_vertical_speed: float = -0.5
    """Weight of the torso's vertical speed² (m/s)² (bouncing)."""
    w_alive: float = 0.2
    """Paid every step the robot is up."""
    fall_penalty: float = 10.0
    """Subtracted once when the robot falls (the episode ends)."""

    def validate(self) -> None:
        super().validate()
        for name in ("forward_speed_range", "sideways_speed_range", "turn_rate_range"):
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
                raise EnvConfigError(f"{name} must be finite (low, high) with low <= high")
        if not (
            isinstance(self.command_change_steps, int | np.integer)
            and self.command_change_steps >= 0
        ):
            raise EnvConfigError("command_change_steps must be an integer >= 0")
        accel = self.command_accel_limit
        if not all(math.isfinite(a) and a >= 0.0 for a in accel):  # 3 numbers: checked before
            raise EnvConfigError(
                "command_accel_limit must be 3 finite numbers >= 0 (forward m/s², sideways "
                f"m/s², turn deg/s²; 0: no limit), got {accel!r}"
            )
        gain = self.command_feedback_gain
        if not (math.isfinite(gain) and 0.0 <= gain <= 100.0):
            raise EnvConfigError(f"command_feedback_gain must be in [0, 100] 1/s, got {gain!r}")
        for name in ("standing_command_prob", "single_axis_command_prob"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise EnvConfigError(f"{name} must be in [0, 1]")
        if not (math.isfinite(self.tracking_sigma) and self.tracking_sigma > 0):
            raise EnvConfigError("tracking_sigma must be > 0")
        turn_sigma = self.tracking_turn_sigma
        if turn_sigma is not None and not (math.isfinite(turn_sigma) and turn_sigma > 0):
            raise EnvConfigError(f"tracking_turn_sigma must be > 0 or None, got {turn_sigma!r}")
        if not (math.isfinite(self.gait_frequency_hz) and 0.0 < self.gait_frequency_hz <= 10.0):
            raise EnvConfigError(
                f"gait_frequency_hz must be in (0, 10] Hz, got {self.gait_frequency_hz!r}"
            )
        if not 0.0 <= self.swing_share <= 0.5:
            raise EnvConfigError(f"swing_share must be in [0, 0.5], got {self.swing_share!r}")
        for name in (
            "gait_sway_deg", "gait_lift_deg", "gait_stride_deg_per_mps", "gait_side_deg_per_mps",
            "gait_turn_deg_per_dps",
        ):  # fmt: skip
            value = getattr(self, name)
            if not (math.isfinite(value) and abs(value) <= 90.0):
                raise EnvConfigError(
                    f"{name} must be a number of degrees within ±90, got {value!r}"
                )
        for name in ("gait_stride_max_deg", "gait_side_max_deg", "gait_turn_max_deg"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value <= 90.0):
                raise EnvConfigError(f"{name} must be in [0, 90] deg, got {value!r}")
        if not (math.isfinite(self.gait_lead_s) and abs(self.gait_lead_s) <= 1.0):
            raise EnvConfigError(f"gait_lead_s must be within ±1 s, got {self.gait_lead_s!r}")
        cap = self.progress_cap_mps
        if cap is not None and not (math.isfinite(cap) and cap > 0.0):
            raise EnvConfigError(f"progress_cap_mps must be > 0 m/s or None, got {cap!r}")
        target = self.feet_air_time_target_s
        if target is not None and not (math.isfinite(target) and target >= 0.0):
            raise EnvConfigError(f"feet_air_time_target_s must be >= 0 s, got {target!r}")
        if self.reference_gait and self.robot != "nao":
            raise EnvConfigError(
                f"reference_gait is a stepping pattern for the Nao, not the {self.robot}; pass "
                "reference_gait=False"
            )
        for name in (
            "w_tracking_linear", "w_tracking_turn", "w_progress", "w_upright", "w_feet_phase",
            "w_feet_air_time", "w_action_rate", "w_joint_speed", "w_vertical_speed", "w_alive",
            "fall_penalty",
        ):  # fmt: skip
            if not math.isfinite(getattr(self, name)):
                raise EnvConfigError(f"{name} must be finite, got {getattr(self, name)!r}")


def capped(value: float, cap: float | None) -> float:
    """``value`` up to ``cap`` (``None``: no cap)."""
    return value if cap is None else min(value, cap)


MOVING_SPEED_MPS = 0.05
"""A command asks the walk to step when its forward or sideways speed is above this (m/s) …"""
MOVING_TURN_DPS = 3.0
"""… or its turn rate above this (deg/s); otherwise the reference gait eases out and it stands."""


def asks_to_move(command: np.ndarray) -> bool:
    """Whether a command (forward m/s, left m/s, turn deg/s) asks to move: more than
    :data:`MOVING_SPEED_MPS` forward or sideways, or :data:`MOVING_TURN_DPS`."""
    return bool(
        abs(command[0]) > MOVING_SPEED_MPS
        or abs(command[1]) > MOVING_SPEED_MPS
        or abs(command[2]) > MOVING_TURN_DPS
    )


def reference_gait_deg(
    config: WalkConfig, phase: float, command: np.ndarray, ramp: float = 1.0
) -> dict[str, float]:
    """The reference gait's target-angle offsets (deg, by Nao effector name) at gait phase
    ``phase`` for ``command`` (forward m/s, left m/s, turn deg/s), at level ``ramp``.

    With s = sin 2πφ and c = cos 2πφ: both hip rolls + ``gait_sway_deg``·s and both ankle
    rolls − it (the weight moves onto the standing foot); the left leg lifts while s > 0 and the
    right while s < 0 (hip and ankle pitch + ``gait_lift_deg``·|s|, knee − twice that); the hips
    and ankles swing fore and aft with c, the stride ``gait_stride_deg_per_mps`` × the forward
    command (at most ``gait_stride_max_deg``); the hip rolls swing sideways with c (left −, right
    +, the ankle rolls keeping the feet flat), ``gait_side_deg_per_mps`` × the leftward command
    (at most ``gait_side_max_deg``); both hip yaw-pitches swing with c, ``gait_turn_deg_per_dps``
    × the turn command (at most ``gait_turn_max_deg``). Each swing carries the lifted foot one
    way and the standing foot back, so the body moves the other. A command that asks for more
    than one swing's largest amplitude at once is scaled down until the three shares of their
    largest (stride, side, turn) have a Euclidean norm of 1: a step does not both stride and
    side-step its fullest.

    ``ramp`` (0–1) scales every amplitude: :class:`Walk` eases the pattern in over a gait cycle
    when the command asks to move and out over one when it asks to stand; 0 gives no pattern
    (an empty dict)."""
    if ramp <= 0.0:
        return {}
    c = config

    def share(per_unit: float, value: float, largest: float) -> float:
        return per_unit * value / largest if largest > 0.0 else 0.0

    shares = np.array(
        [
            share(c.gait_stride_deg_per_mps, command[0], c.gait_stride_max_deg),
            share(c.gait_side_deg_per_mps, command[1], c.gait_side_max_deg),
            share(c.gait_turn_deg_per_dps, command[2], c.gait_turn_max_deg),
        ]
    )
    norm = float(np.linalg.norm(shares))
    if norm > 1.0:
        shares /= norm
    largest = (c.gait_stride_max_deg, c.gait_side_max_deg, c.gait_turn_max_deg)
    stride_amp, side_amp, turn_amp = (float(x) * m for x, m in zip(shares, largest, strict=True))
    angle = 2.0 * math.pi * phase
    s, co = math.sin(angle) * ramp, math.cos(angle) * ramp
    sway = c.gait_sway_deg * s
    stride, side, turn = stride_amp * co, side_amp * co, turn_amp * co
    out = {
        "lle1": turn,
        "rle1": turn,
        "lle2": sway - side,
        "rle2": sway + side,
        "lle6": -sway + side,
        "rle6": -sway - side,
    }
    for leg, lift in (("l", max(0.0, s)), ("r", max(0.0, -s))):
        lift *= c.gait_lift_deg
        out[f"{leg}le3"] = lift
        out[f"{leg}le4"] = -2.0 * lift
        out[f"{leg}le5"] = lift
    out["lle3"] -= stride
    out["rle3"] += stride
    out["lle5"] += stride
    out["rle5"] -= stride
    return out


def _within(phase: float, centre: float, half: float) -> bool:
    """Whether ``phase`` lies less than ``half`` from ``centre`` on the unit circle."""
    return abs((phase - centre + 0.5) % 1.0 - 0.5) < half


def walk_reward_terms(
    config: WalkConfig,
    *,
    velocity: np.ndarray,
    turn_rate: float,
    command: np.ndarray,
    up_z: float,
    touchdown_air_times: list[float],
    action: np.ndarray,
    last_action: np.ndarray,
    joint_speeds: np.ndarray,
    fallen: bool,
    phase: float = 0.0,
    feet_down: tuple[bool, bool] | None = None,
    progress: float = 0.0,
) -> dict[str, float]:
    """Walk's reward as named terms (already weighted), for one step.

    Args:
        velocity: Torso velocity in the heading frame (forward, left, up), m/s.
        turn_rate: Torso turn rate about the world's up axis, rad/s.
        command: (forward m/s, left m/s, turn deg/s).
        up_z: World z of the torso's up axis.
        touchdown_air_times: Air time (s) of each foot that touched down this step.
        action, last_action: This and the previous action, [-1, 1].
        joint_speeds: Joint speeds, rad/s.
        fallen: Whether the robot fell this step.
        phase: The gait clock's phase in [0, 1).
        feet_down: Whether the (left, right) foot touches the ground; ``None``: no
            ``feet_phase`` term (0).
        progress: The torso's speed along its heading at the episode's start, m/s (paid up
            to ``progress_cap_mps``).
    """
    c = config
    lin_err = float((velocity[0] - command[0]) ** 2 + (velocity[1] - command[1]) ** 2)
    turn_sigma = c.tracking_sigma if c.tracking_turn_sigma is None else c.tracking_turn_sigma
    turn_err = float((turn_rate - math.radians(command[2])) ** 2)
    moving = asks_to_move(command)
    target = (
        c.feet_air_time_target_s
        if c.feet_air_time_target_s is not None
        else c.swing_share / c.gait_frequency_hz
    )
    air = sum(t - target for t in touchdown_air_times) if moving else 0.0
    feet_phase = 0.0
    if feet_down is not None:
        half = c.swing_share / 2.0
        swing = (
            (_within(phase, 0.25, half), _within(phase, 0.75, half)) if moving else (False, False)
        )
        feet_phase = sum(down != up for down, up in zip(feet_down, swing, strict=True)) / 2.0
    return {
        "tracking_linear": c.w_tracking_linear * math.exp(-lin_err / c.tracking_sigma),
        "tracking_turn": c.w_tracking_turn * math.exp(-turn_err / turn_sigma),
        "progress": c.w_progress * capped(float(progress), c.progress_cap_mps),
        "upright": c.w_upright * float(up_z),
        "feet_phase": c.w_feet_phase * feet_phase,
        "feet_air_time": c.w_feet_air_time * air,
        "action_rate": c.w_action_rate * float(np.sum((action - last_action) ** 2)),
        "joint_speed": c.w_joint_speed * float(np.sum(joint_speeds**2)),
        "vertical_speed": c.w_vertical_speed * float(velocity[2] ** 2),
        "alive": 0.0 if fallen else c.w_alive,
        "fall": -c.fall_penalty if fallen else 0.0,
    }


_LOOP_HEADING_ERROR = math.radians(45.0)
"""``command_feedback_gain``: the largest heading error the loop turns against, rad."""


class Walk(BaseEnv):
    """Walk at a commanded planar velocity: forward, sideways and turning.

    The episode samples a command (uniform in the configured ranges, zero with probability
    ``standing_command_prob``, one component alone with ``single_axis_command_prob``) and
    draws a new one every ``command_change_steps`` steps; the command is part of the
    observation (``velocity_command``; with ``command_feedback_gain`` the command corrected by
    the measured motion, ``policy_command``; with ``command_accel_limit`` the command grows to
    the one given gradually). The robot starts standing in the crouched walking
    pose, placed instantly. A fall ends the episode (``terminate_on_fall``).
    Actions are target angles around that pose (± ``target_around_start_deg``) added to a
    reference gait (``reference_gait``: an open-loop stepping pattern, :func:`reference_gait_deg`)
    while the command asks to move, so zero actions walk and the policy learns corrections. A
    gait clock (``gait_frequency_hz``, observed as ``gait_phase``) drives the pattern and says
    when each foot should swing, as in MuJoCo Playground's humanoid joystick tasks.
    Every step pays the sum of these terms (each documented in :class:`WalkConfig`; ``info``
    holds them under ``reward_terms``):

    ====================  ===========  ==========================================================
    term                  default w    value
    ====================  ===========  ==========================================================
    ``tracking_linear``   1.5          exp(−|v_xy − cmd_xy|² / σ), heading frame, σ = 0.1
    ``tracking_turn``     0.8          exp(−(ω_z − cmd_ω)² / σ_turn), rad/s, σ_turn = σ
    ``progress``          0            speed along the heading the episode started with, m/s
    ``upright``           0.3          world z of the torso's up axis
    ``feet_phase``        0.5          share of feet in contact as the gait clock asks
    ``feet_air_time``     1.0          Σ (air time − swing share / f) of feet touching down
    ``action_rate``       −0.02        |a_t − a_{t−1}|²
    ``joint_speed``       −2e-4        Σ joint speed², (rad/s)²
    ``vertical_speed``    −0.5         torso vertical speed², (m/s)²
    ``alive``             0.2          every step up
    ``fall``              −10          once, when the robot falls
    ====================  ===========  ==========================================================

    Foot contact is read from the foot force perceptors (``FRP``) a policy has too.
    ``reset(options={"velocity_command": (vx, vy, turn_deg_s)})`` fixes the episode's first
    command (evaluation, the benchmark).

    Version history:

    * v0: first release (robocup-gym 0.2.0).
    """

    config_class = WalkConfig
    config: WalkConfig
    task_reset_options = frozenset({"velocity_command"})

    def __init__(self, config: WalkConfig | None = None, **kwargs: Any) -> None:
        self._forward = [0.0, 0.0, 0]
        super().__init__(config, **kwargs)
        self._gait = (
            self.config.reference_gait and self.config.action_mode is not ActionMode.VELOCITY
        )
        """Whether the reference gait is added to the target angles."""
        self._air = {"lf": 0.0, "rf": 0.0}
        self._prev_action = np.zeros(self.action_space.shape)
        self._loop_command = np.zeros(3)
        """The command given when the loop (``command_feedback_gain``) last started: a change
        restarts it."""
        self._working_command = np.zeros(3)
        """The command the walk works for: the given one, its growth limited
        (``command_accel_limit``)."""
        self._loop_integral = np.zeros(2)
        self._loop_heading: float | None = None
        """The heading the command asks for, rad (``None``: the torso's at the next update)."""
        self._acted_command = np.zeros(3)
        """The command the policy was told when it chose this step's action."""

    def _draw_command(self) -> None:
        c, rng = self.config, self.np_random
        if rng.uniform() < c.standing_command_prob:
            self.velocity_command[:] = 0.0
        else:
            self.velocity_command[:] = (
                rng.uniform(*c.forward_speed_range),
                rng.uniform(*c.sideways_speed_range),
                rng.uniform(*c.turn_rate_range),
            )
            if c.single_axis_command_prob and rng.uniform() < c.single_axis_command_prob:
                keep = rng.integers(3)
                self.velocity_command[np.arange(3) != keep] = 0.0

    def _initial_state(self, options):
        start = super()._initial_state(options)
        self._air = {"lf": 0.0, "rf": 0.0}
        self._prev_action = np.zeros(self.action_space.shape)
        self._forward = [0.0, 0.0, 0]  # sum of forward speeds, of |forward error|, steps
        self._start_heading: tuple[float, float] | None = None  # read at the first step
        self.gait_clock = (float(self.np_random.uniform()), float(self.config.gait_frequency_hz))
        self._phase_acted = 0.0
        self._gait_level = 0.0
        """The reference gait's level (0–1, :func:`reference_gait_deg`'s ``ramp``)."""
        command = options.get("velocity_command")
        if command is None:
            self._draw_command()
        else:
            what = "be 3 finite numbers (forward m/s, left m/s, turn deg/s)"
            cmd = reset_numbers(options, "velocity_command", (3,), what, finite=True)
            self.velocity_command[:] = cmd
        self._loop_command[:] = np.nan  # the loop starts afresh at the first perception
        # the command grows from standing at the first perception
        self._working_command[:] = self.velocity_command if not self._limits_growth else 0.0
        # read at each reset: the config may have been replaced since the last
        if not self._tells_its_own_command:
            self.policy_command = self.velocity_command
        elif self.policy_command is self.velocity_command:
            self.policy_command = self.velocity_command.copy()
        self.policy_command[:] = self._working_command
        self._gait_command = self.policy_command.copy()
        """The command the reference gait follows (the command, low-pass filtered)."""
        return start

    @classmethod
    def league_defaults(cls, robot: str) -> dict[str, Any]:
        """:meth:`BaseEnv.league_defaults`, plus no reference gait (a pattern for the Nao)."""
        out = super().league_defaults(robot)
        out["reference_gait"] = False
        return out

    def _before_action(self) -> None:
        c = self.config
        self._phase_acted = self.gait_phase  # the phase the policy saw when choosing the action
        if c.track_told_command:  # the command the policy saw, for the tracking terms
            self._acted_command[:] = self.policy_command
        if self._gait:
            # the pattern eases in and out over a gait cycle, and follows command changes with a
            # time constant of one cycle: no step starts, stops or changes all at once
            rate = min(1.0, CYCLE_S * c.gait_frequency_hz)
            level = 1.0 if asks_to_move(self.policy_command) else 0.0
            self._gait_level += min(rate, max(-rate, float(level - self._gait_level)))
            self._gait_command += (self.policy_command - self._gait_command) * rate
            lead = c.gait_lead_s * c.gait_frequency_hz  # in cycles
            phase = (self._phase_acted + lead) % 1.0
            self._actions.set_offsets(
                reference_gait_deg(c, phase, self._gait_command, self._gait_level)
            )
        if (
            c.command_change_steps
            and self.episode_step
            and (self.episode_step % c.command_change_steps == 0)
        ):
            self._draw_command()

    @property
    def _limits_growth(self) -> bool:
        """Whether the command's growth is limited (``command_accel_limit``)."""
        return any(self.config.command_accel_limit)

    @property
    def _tells_its_own_command(self) -> bool:
        """Whether the policy is told a command of its own (``policy_command``: with a loop or
        a limited growth) rather than the one given."""
        return bool(self.config.command_feedback_gain) or self._limits_growth

    def _set_perception(self, p: Perception, cycles: int = 1, episode_over: bool = False) -> None:
        super()._set_perception(p, cycles, episode_over)
        if episode_over:
            return
        if self._tells_its_own_command and self.policy_command is self.velocity_command:
            # a config replaced since the reset: the command given stays as given
            self.policy_command = self.velocity_command.copy()
        if self._limits_growth:
            self._grow_the_command(cycles * CYCLE_S)
        if self.config.command_feedback_gain:
            self._close_the_loop(cycles * CYCLE_S)
        elif self._limits_growth:
            self.policy_command[:] = self._working_command

    def _grow_the_command(self, dt: float) -> None:
        """The command the walk works for after ``dt`` s: the given one, each component's
        magnitude grown by at most ``command_accel_limit`` × ``dt`` (cut at once; across zero
        from zero)."""
        given, working = self.velocity_command, self._working_command
        limit = np.asarray(self.config.command_accel_limit, dtype=float)
        was = np.where(given * working > 0.0, np.abs(working), 0.0)
        allowed = np.where(limit > 0.0, was + limit * dt, np.inf)
        working[:] = np.sign(given) * np.minimum(np.abs(given), allowed)

    def _close_the_loop(self, dt: float) -> None:
        """``policy_command`` from the command the walk works for (``velocity_command``, its
        growth limited by ``command_accel_limit``) and the torso's motion over the last ``dt``
        s (``command_feedback_gain``)."""
        c, gt = self.config, self.ground_truth
        target = self._working_command if self._limits_growth else self.velocity_command
        if not np.array_equal(self.velocity_command, self._loop_command):  # a new command
            self._loop_command[:] = self.velocity_command
            self._loop_integral[:] = 0.0
            self._loop_heading = None
        if gt is None or gt.torso_vel is None or not asks_to_move(target):
            self.policy_command[:] = target
            return
        gain = c.command_feedback_gain
        cos_h, sin_h = heading_frame(gt.torso_quat)
        heading = math.atan2(sin_h, cos_h)
        forward, left = in_heading_frame((cos_h, sin_h), gt.torso_vel[0], gt.torso_vel[1])
        self._loop_integral[0] += gain * dt * (target[0] - forward)
        self._loop_integral[1] += gain * dt * (target[1] - left)
        wanted = heading if self._loop_heading is None else self._loop_heading
        wanted += math.radians(target[2]) * dt
        error = math.remainder(wanted - heading, math.tau)
        error = min(_LOOP_HEADING_ERROR, max(-_LOOP_HEADING_ERROR, error))
        self._loop_heading = heading + error  # no wind-up beyond the held error
        low, high = self._command_ranges
        out = self.policy_command
        out[:2] = target[:2] + self._loop_integral
        out[2] = target[2] + math.degrees(gain * error)
        np.clip(out, low, high, out=out)
        self._loop_integral[:] = out[:2] - target[:2]  # nor beyond the ranges

    @property
    def _command_ranges(self) -> tuple[np.ndarray, np.ndarray]:
        c = self.config
        ranges = (c.forward_speed_range, c.sideways_speed_range, c.turn_rate_range)
        return np.array([r[0] for r in ranges]), np.array([r[1] for r in ranges])

    def _reward_terms(self, action: np.ndarray) -> dict[str, float]:
        gt = self.ground_truth
        v = gt.torso_vel if gt.torso_vel is not None else np.zeros(3)
        w = gt.torso_ang_vel if gt.torso_ang_vel is not None else np.zeros(3)
        heading = heading_frame(gt.torso_quat)
        forward, left = in_heading_frame(heading, v[0], v[1])
        if self._start_heading is None:
            self._start_heading = heading
        progress = v[0] * self._start_heading[0] + v[1] * self._start_heading[1]
        velocity = np.array([forward, left, v[2]])
        upright = up_z(gt.torso_quat)
        touchdowns = []
        down: list[bool] = []
        forces = self.perception.force_sensors
        contact = gt.feet_contact  # robots without foot pressure perceptors (the league's)
        for foot in ("lf", "rf"):
            on_ground = bool(
                contact[foot]
                if contact is not None
                else foot in forces and forces[foot].force[2] > 1.0
            )
            down.append(on_ground)
            if on_ground:
                if self._air[foot] > 0.0:
                    touchdowns.append(self._air[foot])
                self._air[foot] = 0.0
            else:
                self._air[foot] += CYCLE_S
        terms = walk_reward_terms(
            self.config,
            velocity=velocity,
            turn_rate=float(w[2]),
            command=self._acted_command
            if self.config.track_told_command
            else self.velocity_command,
            up_z=upright,
            touchdown_air_times=touchdowns,
            action=action,
            last_action=self._prev_action,
            joint_speeds=self.joint_velocities,
            fallen=self.fallen,
            phase=self._phase_acted,
            feet_down=(down[0], down[1]),
            progress=float(progress),
        )
        self._prev_action = np.array(action, dtype=float)
        self._forward[0] += float(velocity[0])
        self._forward[1] += abs(float(velocity[0] - self.velocity_command[0]))
        self._forward[2] += 1
        return terms

    def _info(self) -> dict[str, Any]:
        info = super()._info()
        info["velocity_command"] = self.velocity_command.copy()
        total, error, n = self._forward
        if n:  # this episode's mean forward speed and forward tracking error so far
            info["forward_speed_mps"] = total / n
            info["forward_error_mps"] = error / n
        return info

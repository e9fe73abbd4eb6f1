"""Run: Walk's task at running speeds, over a faster reference gait and a taller stance."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from robocup_gym.envs.config import PAPER_STANDING_POSE_DEG
from robocup_gym.envs.tasks.walk import Walk, WalkConfig

__all__ = ["RUN_POSE_DEG", "RUN_POSE_OFFSETS_DEG", "SPRINT_OPTIONS", "Run", "RunConfig"]


def _run_pose() -> dict[str, float]:
    pose = dict(PAPER_STANDING_POSE_DEG)
    for side in "LR":
        for joint, offset in RUN_POSE_OFFSETS_DEG.items():
            pose[side + joint] += offset
    return pose


RUN_POSE_OFFSETS_DEG: dict[str, float] = {"HipPitch": -6.0, "KneePitch": 12.5, "AnklePitch": -2.6}
"""How Run's stance differs from the paper's crouched pose, deg, both legs: taller, less bent."""

RUN_POSE_DEG: dict[str, float] = _run_pose()
"""The stance Run starts from and steps around, deg by joint name."""


@dataclass
class RunConfig(WalkConfig):
    """:class:`WalkConfig` with a faster reference gait, a taller stance and running
    commands."""

    joint_start_deg: Any = field(default_factory=lambda: dict(RUN_POSE_DEG))
    """The stance (:data:`RUN_POSE_DEG`), deg by name."""
    gait_frequency_hz: float = 4.2
    """Gait cycles per second (Walk: 3)."""
    gait_lift_deg: float = 26.6
    """Peak leg lift of the swinging foot, deg (Walk: 16)."""
    gait_stride_deg_per_mps: float = 32.0
    """Stride amplitude per m/s of commanded forward speed, deg per m/s: the largest stride at
    0.75 m/s, about the open-loop gait's fastest."""
    gait_stride_max_deg: float = 23.9
    """Largest stride amplitude, deg (Walk: 20): open loop on ODE ~0.65 m/s over 10 s."""
    gait_side_max_deg: float = 8.0
    """Largest sideways swing, deg (Walk: 12, which falls at this pace)."""
    gait_sway_deg: float = -2.6
    """Hip and ankle roll swing, deg (Walk: 0)."""
    gait_lead_s: float = -0.02
    """How far ahead of the gait clock the pattern plays, s (Walk: 0.05)."""
    forward_speed_range: tuple[float, float] = (0.4, 1.6)
    """Commanded forward speed, m/s."""
    sideways_speed_range: tuple[float, float] = (-0.2, 0.2)
    """Commanded leftward speed, m/s."""
    turn_rate_range: tuple[float, float] = (-30.0, 30.0)
    """Commanded turn rate, deg/s."""
    standing_command_prob: float = 0.05
    """Probability that a drawn command is zero (stand still)."""
    tracking_sigma: float = 0.4
    """Width of the linear tracking kernel, (m/s)² (Walk: 0.1): at running commands beyond
    what the gait does open loop, a narrow kernel pays nearly nothing and gives no gradient
    toward speed."""
    tracking_turn_sigma: float | None = 0.1
    """Width of the turn tracking kernel, (rad/s)² (Walk: ``tracking_sigma``)."""
    w_tracking_turn: float = 2.0
    """Weight of the turn tracking term (Walk: 0.8). Policies trained with 0.8 run in circles
    (17°/s with σ = 0.4, 29°/s with σ = 0.1): curving lets them run faster in the heading frame
    than the turn term costs."""


SPRINT_OPTIONS: dict[str, Any] = {
    "w_progress": 3.0,
    "w_tracking_linear": 0.0,
    "w_tracking_turn": 0.0,
    "forward_speed_range": (1.5, 1.5),
    "sideways_speed_range": (0.0, 0.0),
    "turn_rate_range": (0.0, 0.0),
    "standing_command_prob": 0.0,
}
"""What ``RobocupGym/Run-v1`` sets over :class:`RunConfig`: forward as fast as it can, paid for
the distance covered along the heading it started with (``w_progress``, m/s × 3 per step) instead
of for tracking a command, which is always 1.5 m/s straight ahead (the reference gait's largest
stride)."""


class Run(Walk):
    """Run forward at a commanded speed (0.4–1.6 m/s), steering a little, without falling.

    :class:`Walk` with other defaults: the reward's terms, the command (forward, sideways,
    turn), its observation and the residual over the reference gait are Walk's. What differs:

    ===========================  ==============  ===============================================
    option                       default (Walk)  meaning
    ===========================  ==============  ===============================================
    ``joint_start_deg``          stance (paper)  knees 12.5° straighter, hips 6° and ankles
                                                 2.6° less bent (:data:`RUN_POSE_DEG`)
    ``gait_frequency_hz``        4.2 (3.0)       gait cycles per second
    ``gait_lift_deg``            26.6 (16)       leg lift, deg
    ``gait_stride_deg_per_mps``  32 (40)         stride per m/s commanded, deg
    ``gait_stride_max_deg``      23.9 (20)       largest stride, deg
    ``gait_side_max_deg``        8 (12)          largest sideways swing, deg
    ``gait_sway_deg``            −2.6 (0)        hip/ankle roll swing, deg
    ``gait_lead_s``              −0.02 (0.05)    pattern ahead of the clock, s
    ``forward_speed_range``      0.4–1.6         commanded forward speed, m/s (−0.3–0.8)
    ``sideways_speed_range``     ±0.2 (±0.3)     commanded leftward speed, m/s
    ``turn_rate_range``          ±30 (±45)       commanded turn rate, deg/s
    ``standing_command_prob``    0.05 (0.2)      share of commands to stand still
    ``tracking_sigma``           0.4 (0.1)       width of the linear tracking kernel
    ``tracking_turn_sigma``      0.1 (σ)         width of the turn tracking kernel
    ``w_tracking_turn``          2.0 (0.8)       weight of the turn tracking term
    ===========================  ==============  ===============================================

    The reference gait's amplitudes, stance and timing were searched open loop (zero actions,
    CMA-ES over the forward speed of 10 s runs, falls penalised) on the ODE engine, Nao type 0:
    alone it runs ~0.7 m/s and falls now and then; the policy over it learns the rest.

    ``RobocupGym/Run-v1`` runs straight ahead as fast as it can (:data:`SPRINT_OPTIONS`): the
    command is always 1.5 m/s forward, and instead of the tracking terms each step pays 3 × the
    torso's speed along the heading the episode started with (``w_progress``; the distance
    covered that way, as FC Portugal's running gym pays), so turning away or falling early costs
    distance. The shipped ``run`` policy, learnt on it, runs 1.77 m/s over its ± 30° residual
    window and 1.55 m/s over the ± 22° it is shipped with on type 0 (docs/results.md), where PPO on
    Run-v0's tracking reward stayed below the reference gait's 0.65 m/s.

    Version history:

    * v1: sprint straight ahead: ``w_progress`` 3 instead of the tracking terms, a fixed
      1.5 m/s forward command (:data:`SPRINT_OPTIONS`).
    * v0: first release.
    """

    config_class = RunConfig
    config: RunConfig

"""TargetKick: kick the ball to a commanded distance and direction, and stay on your feet."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from robocup_gym.envs.base_env import BaseEnv
from robocup_gym.envs.config import DEFAULT_OBSERVATIONS, EnvConfig, EnvConfigError
from robocup_gym.envs.tasks.commanded_kicks import commanded_kick
from robocup_gym.envs.tasks.reference_kick import ReferenceKickConfig, ReferenceKickTask, kick_table
from robocup_gym.sim.physics import ball_rest_point

__all__ = [
    "TARGET_KICK_OBSERVATIONS",
    "TargetKick",
    "TargetKickConfig",
    "commanded_kick",
    "kick_outcome",
]

TARGET_KICK_OBSERVATIONS = (*DEFAULT_OBSERVATIONS, "kick_target")
"""The paper's observations (the ball's place among them, robot frame) and the command."""

CONTACT_SPEED = 0.1
"""The ball counts as kicked once it moves faster than this, m/s."""


@dataclass
class TargetKickConfig(ReferenceKickConfig):
    """:class:`ReferenceKickConfig` (the reference kick, target angles around the crouched pose)
    plus TargetKick's command and reward options."""

    observations: tuple[str, ...] = TARGET_KICK_OBSERVATIONS
    randomise_kick_target: bool = True
    """A new command every episode (distance and direction drawn uniformly)."""
    kick_target_distance_range: tuple[float, float] = (2.0, 10.0)
    """Commanded kick distance, m."""
    kick_target_angle_range: tuple[float, float] = (-45.0, 45.0)
    """Commanded direction relative to the robot's heading, deg (CCW positive)."""
    ball_spawn_noise: float = 0.03
    """The ball starts 3 cm from its spot (``ball_start_pos``: 0.16 m ahead of the right foot),
    in a random direction."""
    max_episode_steps: int = 60
    """1.2 s to reach the ball and kick."""
    wait_steps: int = 50
    """1 s with the joints stopped after the episode, before the outcome is measured: the robot
    must still be up then."""
    w_accuracy: float = 1.0
    """Weight of 1 − |rest − target| / distance: 1 on target, 0 for a ball that did not move."""
    fall_penalty: float = 1.0
    """Subtracted when the robot is down after the wait (as much as the best kick earns: no
    kick is worth a fall)."""
    kick_per_command: bool = False
    """Play the kick made for the episode's command (:func:`commanded_kick`: its distance and
    direction), with the ball at that kick's spot (plus ``ball_spawn_noise``), instead of
    ``kick_keyframes``. A Nao's motion: without ``reference_kick`` (a league robot) it does
    nothing."""

    def validate(self) -> None:
        super().validate()
        shortest = self.kick_target_distance_range[0]
        if not shortest > 0.0:
            raise EnvConfigError(
                f"kick_target_distance_range must lie above 0 m, got {shortest!r} m as its low end"
            )
        for name in ("w_accuracy", "fall_penalty"):
            v = getattr(self, name)
            if not math.isfinite(v):
                raise EnvConfigError(f"{name} must be finite, got {v!r}")


def kick_outcome(
    spawn: np.ndarray,
    ball_pos: np.ndarray,
    ball_vel: np.ndarray,
    heading_deg: float,
    target: np.ndarray,
) -> dict[str, float]:
    """How a kick went against its command.

    Args:
        spawn: Where the ball started (x, y[, z]), m, world frame.
        ball_pos, ball_vel: The ball now, m and m/s, world frame (it may still roll).
        heading_deg: The robot's heading when the command was given, deg.
        target: The command: (distance m, direction deg relative to ``heading_deg``).

    Returns:
        ``rest_x``/``rest_y`` (where the ball comes to rest, m, :func:`ball_rest_point`),
        ``kick_distance_m`` (from the spawn to there), ``miss_m`` (from the commanded point),
        ``distance_error`` (|kick distance − commanded| / commanded), ``direction_error_deg``
        (the angle between the commanded and the actual direction; 180 for a ball that did not
        move).
    """
    rest = ball_rest_point(ball_pos, ball_vel)
    d, angle = float(target[0]), math.radians(heading_deg + float(target[1]))
    aim = np.array([spawn[0] + d * math.cos(angle), spawn[1] + d * math.sin(angle)])
    travel = rest - np.asarray(spawn[:2], dtype=float)
    distance = float(np.hypot(*travel))
    if distance > 1e-6:
        off = math.atan2(travel[1], travel[0]) - angle
        direction_error = abs(math.degrees((off + math.pi) % (2.0 * math.pi) - math.pi))
    else:
        direction_error = 180.0
    return {
        "rest_x": float(rest[0]),
        "rest_y": float(rest[1]),
        "kick_distance_m": distance,
        "miss_m": float(np.hypot(*(rest - aim))),
        "distance_error": abs(distance - d) / d,
        "direction_error_deg": direction_error,
    }


class TargetKick(ReferenceKickTask, BaseEnv):
    """Kick the ball to a commanded point: a distance (2–10 m) and a direction (±45° of the
    robot's heading), and still stand 1 s later.

    Every episode draws the command (observed as ``kick_target``: distance m, direction deg) and
    places the ball 3 cm from its spot in front of the right foot; the robot sees where the ball
    is (``ball_rel``, its own frame). The robot starts in the crouched standing pose and its
    actions are target angles added to a reference kick (:mod:`.reference_kick`: lean onto the
    left foot, swing the right through the ball, back to the stance), which alone moves the
    ball about 2.7 m straight ahead and stays up. With ``kick_per_command`` (``TargetKick-v1``)
    the kick is the one chosen for the episode's command instead (:func:`commanded_kick`: of a
    library of searched kicks, the one whose measured landings miss the command least), the
    ball at its spot: zero actions kick to the command.

    Paid once, after the episode and ``wait_steps`` more cycles with the joints stopped, from
    where the ball will come to rest (its position and velocity then,
    :func:`~robocup_gym.sim.physics.ball_rest_point`):

    .. code-block:: text

        reward = w_accuracy · (1 − |rest − aim| / distance)  −  fall_penalty (if down)

    where ``aim`` is the commanded point from the ball's spawn. ``info`` gives the outcome
    (:func:`kick_outcome`: ``kick_distance_m``, ``distance_error``, ``direction_error_deg``,
    ``miss_m``) on the last step and ``contact_step``, the first step the ball moved faster than
    0.1 m/s (``None`` before).

    ================================  ==========  ============================================
    option                            default     meaning
    ================================  ==========  ============================================
    ``kick_target_distance_range``    (2, 10)     commanded distance, m
    ``kick_target_angle_range``       (−45, 45)   commanded direction, deg from the heading
    ``ball_spawn_noise``              0.03        ball offset from its spot, m
    ``max_episode_steps``             60          steps to kick (1.2 s)
    ``wait_steps``                    50          stopped cycles before the outcome (1 s)
    ``w_accuracy``                    1.0         weight of the accuracy term
    ``fall_penalty``                  1.0         paid when down after the wait
    ``kick_per_command``              False       play the kick made for the command, the
                                                  ball at its spot (v1: True)
    ``reference_kick``                True        actions correct the reference kick
    ``action_mode``                   target      target angles, start pose ± 30°
                                      angle
    ``ball_start_pos``                (−0.84,     0.16 m ahead of the right foot
                                      −0.055)
    ================================  ==========  ============================================

    ``reset(options={"kick_target": (m, deg)})`` fixes the command (evaluation). Everything
    else is :class:`EnvConfig`.

    Version history:

    * v0: first release (robocup-gym 0.2.0).
    * v1: plays the kick made for each command (``kick_per_command``) with the ball at its spot,
      1 cm of ball spawn noise (v0: the reference kick whatever the command, 3 cm).
    """

    config_class = TargetKickConfig
    config: TargetKickConfig
    contact_step: int | None = None
    """The first step of the episode on which the ball moved faster than 0.1 m/s."""

    @property
    def _plays_commanded_kick(self) -> bool:
        return self.config.kick_per_command and self.config.reference_kick

    def _initial_state(self, options):
        start = super()._initial_state(options)
        self.contact_step = None
        if not self._plays_commanded_kick:
            return start
        keyframes, spot = commanded_kick(*start.kick_target, self.config.robot_type)
        self._kick_table = kick_table(keyframes)
        if "ball_pos" not in options:
            # the spot is measured from a robot at the default start; this one's start and the
            # drawn spawn noise carry over
            ahead = np.subtract(spot, EnvConfig.robot_start_pos)
            h = math.radians(start.pose.heading_deg)
            rotated = (
                ahead[0] * math.cos(h) - ahead[1] * math.sin(h),
                ahead[0] * math.sin(h) + ahead[1] * math.cos(h),
            )
            noise = start.ball_pos[:2] - self.config.ball_start[:2]
            start.ball_pos[:2] = np.add((start.pose.x, start.pose.y), rotated) + noise
        return start

    def _outcome(self) -> dict[str, float]:
        start = self.episode_start
        return kick_outcome(
            self.ball_spawn_pos,
            self.ball_pos,
            self.ball_vel,
            start.pose.heading_deg if start is not None else 0.0,
            self.kick_target,
        )

    def _reward_terms(self, action: np.ndarray) -> dict[str, float]:
        if not self.has_completed:
            return {}
        c = self.config
        outcome = self._outcome()
        terms = {"accuracy": c.w_accuracy * (1.0 - outcome["miss_m"] / float(self.kick_target[0]))}
        if self.fallen:  # after the wait cycles
            terms["fall"] = -c.fall_penalty
        return terms

    def _info(self) -> dict[str, Any]:
        info = super()._info()
        if (
            self.contact_step is None
            and self.episode_step
            and float(np.linalg.norm(self.ball_vel)) > CONTACT_SPEED
        ):
            self.contact_step = self.episode_step
        info["contact_step"] = self.contact_step
        if self.has_completed and self.ground_truth is not None:
            info.update(self._outcome())
        return info

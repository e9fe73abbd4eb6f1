"""Dribble: walk the ball to a target point, keeping it within reach."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from robocup_gym.envs.base_env import reset_numbers
from robocup_gym.envs.config import EnvConfigError
from robocup_gym.envs.observations import heading_frame, in_heading_frame, turn_to_deg
from robocup_gym.envs.tasks.walk import WALK_OBSERVATIONS, Walk, WalkConfig
from robocup_gym.sim.physics import BALL_RADIUS, CYCLE_S

__all__ = ["DRIBBLE_OBSERVATIONS", "Dribble", "DribbleConfig", "dribble_guide"]

DRIBBLE_OBSERVATIONS = (*WALK_OBSERVATIONS, "ball_rel", "ball_vel", "target_rel")
"""Walk's observations (the guide's command among them), the ball and the target point."""


@dataclass
class DribbleConfig(WalkConfig):
    """:class:`WalkConfig` plus Dribble's target, guide and reward options."""

    observations: tuple[str, ...] = DRIBBLE_OBSERVATIONS
    robot_start_pos: tuple[float, float] = (-3.0, 0.0)
    ball_start_pos: tuple[float, float, float] = (-2.75, 0.0, 0.041)
    """0.25 m ahead of the robot."""
    ball_spawn_noise: float = 0.05
    target_distance_range: tuple[float, float] = (4.0, 8.0)
    """Distance from the ball's start to the target, m."""
    target_angle_range: tuple[float, float] = (-30.0, 30.0)
    """Direction from the ball's start to the target, deg from the robot's heading."""
    goal_radius: float = 0.5
    """The episode ends, paid ``goal_bonus``, once the ball is this close to the target, m."""
    reach: float = 1.0
    """The ball is lost while farther than this from the torso (ground distance), m."""
    guide_speed: float = 0.5
    """Forward speed the guide commands when the robot faces its aim point, m/s."""
    guide_near_m: float = 0.0
    """Within this distance of the ball (torso to ball, on the ground, m) the guide commands
    ``guide_near_speed`` instead of ``guide_speed``; 0: one speed everywhere."""
    guide_near_speed: float = 0.5
    """The guide's speed within ``guide_near_m`` of the ball, m/s."""
    guide_behind: float = 0.2
    """The guide aims this far behind the ball's centre on the line from the target, m."""
    guide_turn_gain: float = 1.5
    """Turn rate the guide commands per degree of heading error, (deg/s) per deg."""
    command_change_steps: int = 0
    """The guide sets the command every step (no random commands)."""
    w_ball_progress: float = 1.0
    """Weight of the ball's speed toward the target, m/s, clipped to ±1 (a ball kicked away
    faster than the robot walks is not dribbled: at 2 × up to 1.5 m/s PPO learnt to lunge at
    the ball and fall)."""
    w_near_ball: float = 0.2
    """Paid every step the ball is within ``reach``."""
    goal_bonus: float = 10.0
    """Paid once when the ball reaches the target."""
    next_target_at_goal: bool = False
    """At the goal, draw the next target (as at the start, from the ball and the robot's
    heading then) and go on, instead of ending the episode. Walk's per-step terms pay for
    every step of an episode, so an episode that ends at the goal pays a slower dribble more;
    going on pays reaching the target sooner."""

    def validate(self) -> None:
        super().validate()
        lo, hi = self.target_distance_range
        if not (math.isfinite(hi) and 0.0 < lo <= hi):
            raise EnvConfigError(
                f"target_distance_range must be (low, high) m with 0 < low <= high, got "
                f"{self.target_distance_range!r}"
            )
        for name in (
            "goal_radius", "reach", "guide_speed", "guide_behind", "guide_turn_gain",
            "guide_near_m", "guide_near_speed",
        ):  # fmt: skip
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0.0):
                raise EnvConfigError(f"{name} must be a finite number >= 0, got {v!r}")
        for name in ("w_ball_progress", "w_near_ball", "goal_bonus"):
            if not math.isfinite(getattr(self, name)):
                raise EnvConfigError(f"{name} must be finite, got {getattr(self, name)!r}")


def dribble_guide(
    config: DribbleConfig,
    robot_xy: np.ndarray,
    heading: tuple[float, float],
    ball_xy: np.ndarray,
    target_xy: np.ndarray,
) -> np.ndarray:
    """The walking command (forward m/s, left m/s, turn deg/s) that steers a robot at
    ``robot_xy`` facing ``heading`` (cos, sin) to the ball and through it toward the target:
    its aim is a point ``guide_behind`` behind the ball on the line from the target, or, once
    the robot is behind the ball within 0.1 m of that line, a point 0.5 m beyond the ball on it.
    It commands forward ``guide_speed``·cos(bearing of the aim) (not backward), sideways
    ``guide_speed``·sin(bearing) within ±0.3 m/s, and a turn of ``guide_turn_gain`` × the
    heading error toward the ball-to-target direction within ±45°/s; within ``guide_near_m``
    of the ball ``guide_near_speed`` instead of ``guide_speed``."""
    c = config
    speed = c.guide_speed
    if float(np.hypot(*(ball_xy - robot_xy))) < c.guide_near_m:
        speed = c.guide_near_speed
    to_target = target_xy - ball_xy
    length = float(np.hypot(*to_target))
    u = to_target / length if length > 1e-9 else np.array([heading[0], heading[1]])
    rel = robot_xy - ball_xy
    along = float(np.dot(rel, u))
    lateral = abs(float(rel[0] * u[1] - rel[1] * u[0]))
    behind = along < 0.0 and lateral < 0.1
    aim = ball_xy + 0.5 * u if behind else ball_xy - (c.guide_behind + BALL_RADIUS) * u
    d = aim - robot_xy
    fwd, left = in_heading_frame(heading, d[0], d[1])
    bearing = math.atan2(left, fwd)
    error = turn_to_deg(heading, math.atan2(u[1], u[0]))
    return np.array(
        [
            speed * max(0.0, math.cos(bearing)),
            float(np.clip(speed * math.sin(bearing), -0.3, 0.3)),
            float(np.clip(c.guide_turn_gain * error, -45.0, 45.0)),
        ]
    )


class Dribble(Walk):
    """Walk the ball to a target point, keeping it within reach.

    Every episode draws a target ``target_distance_range`` (4–8 m) from the ball's start, within
    ``target_angle_range`` (±30°) of the robot's heading; the robot starts 0.25 m behind the
    ball (5 cm of noise). The walking command is not drawn: a guide (:func:`dribble_guide`) sets
    it every step, steering behind the ball on the line to the target, and the reference gait
    walks it (zero actions dribble as the guide does); the policy sees the command, the ball
    (``ball_rel``, ``ball_vel``) and the target (``target_rel``) and learns corrections. Every
    step pays Walk's terms (:class:`Walk`: tracking the guide's command, upright, gait, effort,
    alive, fall) and these:

    ====================  ==========  =====================================================
    term                  default w   value
    ====================  ==========  =====================================================
    ``ball_progress``     1.0         ball velocity toward the target, m/s, within ±1
    ``near_ball``         0.2         the ball within ``reach`` (1 m) of the torso
    ``goal``              10          once, the ball within ``goal_radius`` (0.5 m) of it
    ====================  ==========  =====================================================

    The episode ends at the goal (with ``next_target_at_goal``: the next target is drawn from
    there, and it goes on), at a fall, or after ``max_episode_steps`` (10 s). ``info`` gives
    ``losses`` (times the ball went beyond ``reach``), ``goals`` (targets reached),
    ``ball_to_target_m`` and, at the end, ``ball_speed_to_target_mps`` (the distance the ball
    gained on its targets over the episode's time). ``reset(options={"dribble_target": (x,
    y)})`` fixes the (first) target (world m).

    Version history:

    * v0: first release (robocup-gym 0.2.0).
    * v1: ``next_target_at_goal``: at the goal the next target is drawn and the episode goes
      on (v0 ended it: Walk's per-step terms then paid a slower dribble more).
    """

    config_class = DribbleConfig
    config: DribbleConfig
    task_reset_options = frozenset({"dribble_target"})
    losses = 0
    """Times this episode the ball went beyond ``reach`` of the torso."""
    goals = 0
    """Times this episode the ball reached a target."""
    _near = True
    _at_goal = False
    _gained = 0.0
    _start_gap = 0.0

    def _draw_command(self) -> None:
        self.velocity_command[:] = 0.0  # the guide sets it once the world is observed

    def _initial_state(self, options):
        start = super()._initial_state({k: v for k, v in options.items() if k != "dribble_target"})
        ball = start.ball_pos[:2]
        if "dribble_target" in options:
            target = reset_numbers(options, "dribble_target", (2,), "be (x, y) m", finite=True)
        else:
            target = self._draw_target(ball, math.radians(start.pose.heading_deg))
        self.target_pos = target
        self._start_gap = float(np.hypot(*(target - ball)))
        self._gained = 0.0
        self.losses = 0
        self.goals = 0
        self._near = True
        self._at_goal = False
        return start

    def _draw_target(self, ball: np.ndarray, heading_rad: float) -> np.ndarray:
        """A target ``target_distance_range`` from ``ball`` within ``target_angle_range`` of
        the heading ``heading_rad``."""
        c, rng = self.config, self.np_random
        distance = rng.uniform(*c.target_distance_range)
        angle = heading_rad + math.radians(rng.uniform(*c.target_angle_range))
        return ball + distance * np.array([math.cos(angle), math.sin(angle)])

    def _next_target(self, ball: np.ndarray, heading: tuple[float, float]) -> None:
        """The target after a goal, drawn like the first from the ball and the robot's heading
        now."""
        self._gained += self._start_gap - self._ball_to_target()
        self.target_pos = self._draw_target(ball, math.atan2(heading[1], heading[0]))
        self._start_gap = float(np.hypot(*(self.target_pos - ball)))

    def _set_perception(self, p, cycles: int = 1, episode_over: bool = False) -> None:
        super()._set_perception(p, cycles, episode_over)
        gt = self.ground_truth
        if gt is None or episode_over:
            return
        ball = gt.ball_pos[:2]
        heading = heading_frame(gt.torso_quat)
        # (a step's goal: the reset's perception counts none)
        self._at_goal = self.episode_step > 0 and self._ball_to_target() <= self.config.goal_radius
        if self._at_goal:
            self.goals += 1
            if self.config.next_target_at_goal:
                self._next_target(ball, heading)
        self.velocity_command[:] = dribble_guide(
            self.config, gt.torso_pos[:2], heading, ball, self.target_pos
        )
        near = float(np.hypot(*(ball - gt.torso_pos[:2]))) <= self.config.reach
        if self._near and not near:
            self.losses += 1
        self._near = near

    def _ball_to_target(self) -> float:
        return float(np.hypot(*(self.target_pos - self.ball_pos[:2])))

    def _is_terminated(self) -> bool:
        at_goal_ends = self._at_goal and not self.config.next_target_at_goal
        return super()._is_terminated() or at_goal_ends

    def _reward_terms(self, action: np.ndarray) -> dict[str, float]:
        terms = super()._reward_terms(action)
        c = self.config
        to_target = self.target_pos - self.ball_pos[:2]
        gap = float(np.hypot(*to_target))
        toward = float(np.dot(self.ball_vel[:2], to_target) / gap) if gap > 1e-9 else 0.0
        terms["ball_progress"] = c.w_ball_progress * float(np.clip(toward, -1.0, 1.0))
        terms["near_ball"] = c.w_near_ball if self._near else 0.0
        terms["goal"] = c.goal_bonus if self._at_goal else 0.0
        return terms

    def _info(self) -> dict[str, Any]:
        info = super()._info()
        if self.ground_truth is not None:
            gap = self._ball_to_target()
            info["losses"] = self.losses
            info["goals"] = self.goals
            info["ball_to_target_m"] = gap
            if self.has_completed and self.episode_step:
                info["ball_speed_to_target_mps"] = (self._gained + self._start_gap - gap) / (
                    self.episode_step * CYCLE_S
                )
        return info

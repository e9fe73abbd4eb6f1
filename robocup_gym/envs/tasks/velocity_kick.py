"""VelocityKick: kick the ball fast and straight along +x (the paper's ``KickVelocityReward``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from robocup_gym.envs.base_env import BaseEnv
from robocup_gym.envs.config import EnvConfig, EnvConfigError

__all__ = ["VelocityKick", "VelocityKickConfig"]


@dataclass
class VelocityKickConfig(EnvConfig):
    """:class:`EnvConfig` plus VelocityKick's reward options."""

    wait_steps: int = 20
    """Cycles the world runs on after the episode before the reward is measured (paper: 20)."""
    displacement_weight: float = 1.0
    """a: weight of the ball's x displacement (m)."""
    speed_weight: float = 1.0
    """b: weight of the ball's speed in the x–z plane (m/s)."""
    lateral_weight: float = 1.0
    """c: weight of the lateral penalty."""
    penalise_y_velocity: bool = False
    """Add |ball y velocity| (m/s) to the lateral penalty (paper: ``penalise_y_vel_too``)."""
    square_lateral_penalty: bool = False
    """Square the lateral penalty (paper: ``square_y``)."""
    fall_penalty: float = 0.0
    """d: subtracted when the robot is down at the episode's end, after the wait cycles (paper: 0,
    no penalty: PPO then often learns a kick that throws the robot at the ball)."""
    lateral_reference: str = "spawn"
    """``"spawn"``: |y| is measured from the ball's spawn y (the kick line through the ball);
    ``"field"``: from the field's x axis y = 0 (the paper's literal ``|ball y|``; identical when
    the ball starts on y = 0, as in the paper)."""

    def validate(self) -> None:
        super().validate()
        if self.lateral_reference not in ("spawn", "field"):
            raise EnvConfigError(
                f"lateral_reference must be 'spawn' or 'field', got {self.lateral_reference!r}"
            )
        for name in ("displacement_weight", "speed_weight", "lateral_weight", "fall_penalty"):
            v = getattr(self, name)
            if not math.isfinite(v):
                raise EnvConfigError(f"{name} must be finite, got {v!r}")


class VelocityKick(BaseEnv):
    """Kick the ball along +x: reward distance and speed, penalise going sideways.

    Paid once, after the episode ends (fall or ``max_episode_steps``) and the world has run
    ``wait_steps`` (20) more cycles with the joints stopped; 0 on every other step. With the ball
    state at that moment (world frame) and its spawn position ``s``:

    .. code-block:: text

        lateral = |y − y_ref|  (+ |v_y|  if penalise_y_velocity)
        reward  = a · (x − s_x)  +  b · √(v_x² + v_z²)  −  c · lateral  (or c · lateral²)
                  −  d  (if the robot is down after the wait cycles)

    ==========================  =======  ========  ===========================================
    option                      symbol   default   meaning
    ==========================  =======  ========  ===========================================
    ``displacement_weight``     a        1.0       per m the ball moved along +x
    ``speed_weight``            b        1.0       per m/s of ball speed in the x–z plane
    ``lateral_weight``          c        1.0       per m (and m/s) of lateral error
    ``penalise_y_velocity``     –        False     add |v_y| to the lateral error
    ``square_lateral_penalty``  –        False     square the lateral error
    ``lateral_reference``       y_ref    "spawn"   ``"spawn"``: s_y; ``"field"``: 0
    ``fall_penalty``            d        0.0       paid when down after the wait (paper: none)
    ``wait_steps``              –        20        cycles between episode end and reward
    ==========================  =======  ========  ===========================================

    Everything else is :class:`EnvConfig` (pass fields as keyword arguments).

    Version history:

    * v0: first release (robocup-gym 0.2.0).
    """

    config_class = VelocityKickConfig
    config: VelocityKickConfig

    def _reward_terms(self, action: np.ndarray) -> dict[str, float]:
        if not self.has_completed:
            return {}
        c = self.config
        p, v = self.ball_pos, self.ball_vel
        s = self.ball_spawn_pos
        dx = float(p[0] - s[0])
        speed = math.hypot(float(v[0]), float(v[2]))
        y_ref = float(s[1]) if c.lateral_reference == "spawn" else 0.0
        lateral = abs(float(p[1]) - y_ref)
        if c.penalise_y_velocity:
            lateral += abs(float(v[1]))
        if c.square_lateral_penalty:
            lateral = lateral * lateral
        terms = {
            "displacement": c.displacement_weight * dx,
            "speed": c.speed_weight * speed,
            "lateral": -(c.lateral_weight * lateral),
        }
        if self.fallen:  # after the wait cycles, when the ball state is measured
            terms["fall"] = -c.fall_penalty
        return terms

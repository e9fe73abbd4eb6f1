"""LongKick: kick the ball as far as possible along the robot's heading, and stay on your feet."""

from __future__ import annotations

from dataclasses import dataclass

from robocup_gym.envs.tasks.reference_kick import ReferenceKickConfig, ReferenceKickTask
from robocup_gym.envs.tasks.velocity_kick import VelocityKick, VelocityKickConfig

__all__ = ["LongKick", "LongKickConfig"]


@dataclass
class LongKickConfig(ReferenceKickConfig, VelocityKickConfig):
    """:class:`VelocityKickConfig` with a robot that must still stand 1 s after the kick, over
    the reference kick (:class:`ReferenceKickConfig`)."""

    max_episode_steps: int = 60
    """1.2 s to kick."""
    wait_steps: int = 50
    """1 s with the joints stopped before the reward: the ball rolls on, the robot must stay
    up."""
    fall_penalty: float = 3.0
    """Subtracted when the robot is down after the wait (a kick that throws the robot at the
    ball earns less than a shorter one that stands)."""


class LongKick(ReferenceKickTask, VelocityKick):
    """VelocityKick's reward (ball travel along +x, its speed, minus the lateral error), with a
    fall after the kick penalised. The robot starts in the crouched standing pose and its actions
    are target angles added to a reference kick (:mod:`.reference_kick`), which alone moves the
    ball about 2.7 m and stays up.

    Paid once, after the episode and ``wait_steps`` more cycles with the joints stopped:

    .. code-block:: text

        reward = (x − s_x) + √(v_x² + v_z²) − |y − s_y|  −  fall_penalty (if down)

    ====================  ========  ==============================================
    option                default   meaning
    ====================  ========  ==============================================
    ``max_episode_steps`` 60        steps to kick (1.2 s)
    ``wait_steps``        50        stopped cycles before the reward (1 s)
    ``fall_penalty``      3.0       paid when the robot is down after the wait
    ``reference_kick``    True      actions correct the reference kick
    ``action_mode``       target    target angles, start pose ± 30°
                          angle
    ``ball_start_pos``    (−0.84,   0.16 m ahead of the right foot
                          −0.055)
    ====================  ========  ==============================================

    The other options are :class:`VelocityKickConfig`'s (weights, lateral reference).

    Version history:

    * v0: first release (robocup-gym 0.2.0).
    """

    config_class = LongKickConfig
    config: LongKickConfig

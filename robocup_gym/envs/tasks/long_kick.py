"""LongKick: kick the ball as far as possible along the robot's heading, and stay on your feet."""

from __future__ import annotations

from dataclasses import dataclass

from robocup_gym.envs.tasks.reference_kick import Keyframes, ReferenceKickConfig, ReferenceKickTask
from robocup_gym.envs.tasks.velocity_kick import VelocityKick, VelocityKickConfig

__all__ = [
    "LONG_KICK_BALL_START_POS",
    "LONG_KICK_KEYFRAMES",
    "LONG_KICK_KEYFRAMES_BY_TYPE",
    "LONG_KICK_KEYFRAMES_TYPE_4",
    "LongKick",
    "LongKickConfig",
]

LONG_KICK_KEYFRAMES: Keyframes = (
    (0.0, {}),
    (
        0.538,
        {"lle2": 2.65, "lle3": 8.48, "lle5": 27.64, "lle6": -1.72, "rle2": 2.65, "rle6": -1.72},
    ),
    (
        0.7186,
        {
            "lae1": -138.85,
            "lle2": -5.13,
            "lle3": -7.18,
            "lle4": 14.0,
            "lle5": -11.07,
            "lle6": 6.78,
            "rae1": 127.81,
            "rle2": -3.47,
            "rle3": 40.17,
            "rle4": -73.76,
            "rle5": -91.35,
            "rle6": 6.78,
        },
    ),
    (
        0.7386,
        {
            "lae1": -0.25,
            "lle2": 21.78,
            "lle3": -48.71,
            "lle4": -7.67,
            "lle5": 23.77,
            "lle6": 25.92,
            "rae1": 9.05,
            "rle2": -35.14,
            "rle3": 87.24,
            "rle4": 37.88,
            "rle5": 47.84,
            "rle6": 25.92,
        },
    ),
    (
        0.9133,
        {
            "lle2": -54.14,
            "lle3": -17.09,
            "lle5": 11.03,
            "lle6": -1.71,
            "rle2": -54.14,
            "rle3": -59.28,
            "rle4": -10.74,
            "rle5": -30.34,
            "rle6": -1.71,
        },
    ),
    (0.9333, {}),
)
"""The long kick ``LongKick-v1`` plays under its actions, written as
:data:`~robocup_gym.envs.tasks.reference_kick.REFERENCE_KICK_KEYFRAMES` is: a slow lean onto the
left foot (0.54 s), the right leg drawn back with the arms thrown apart, a swing through the
ball in 20 ms (every joint then at its speed limit: the offsets are beyond what the joints
reach), the right leg pulled back and the hips rolled to catch the robot, and the stance again
at 0.93 s. Found by CMA-ES on the default engine, open loop, from the reference kick, together
with the ball's spot (:data:`LONG_KICK_BALL_START_POS`): the score was the ball's forward
travel to where it comes to rest, less 1.5 × its sideways error, 6 m off for a robot down 1 s
later, averaged over the Nao types 0–4 with 0.5° of start-angle noise and 1 cm of ball spawn
noise, and type 0 without noise. Alone (zero actions) it moves the ball ~9.7 m on type 0
(9.4–9.7 m on types 0–3) and the robot stands (``tests/envs/test_reference_kick.py``)."""

LONG_KICK_KEYFRAMES_TYPE_4: Keyframes = (
    (0.0, {}),
    (
        0.5529,
        {"lle2": 0.37, "lle3": 2.65, "lle5": 43.34, "lle6": -3.34, "rle2": 0.37, "rle6": -3.34},
    ),
    (
        0.7262,
        {
            "lae1": -166.49,
            "lle2": -8.94,
            "lle3": -11.75,
            "lle4": 16.48,
            "lle5": -13.4,
            "lle6": 9.6,
            "rae1": 89.2,
            "rle2": -6.55,
            "rle3": 43.87,
            "rle4": -74.32,
            "rle5": -99.11,
            "rle6": 9.6,
        },
    ),
    (
        0.7462,
        {
            "lae1": -13.81,
            "lle2": 22.31,
            "lle3": -34.0,
            "lle4": -25.58,
            "lle5": 22.63,
            "lle6": 26.98,
            "rae1": 11.36,
            "rle2": -33.0,
            "rle3": 87.15,
            "rle4": 28.9,
            "rle5": 45.27,
            "rle6": 26.98,
        },
    ),
    (
        0.9565,
        {
            "lle2": -51.96,
            "lle3": -27.3,
            "lle5": 11.27,
            "lle6": -7.81,
            "rle2": -51.96,
            "rle3": -50.42,
            "rle4": -1.83,
            "rle5": -14.55,
            "rle6": -7.81,
        },
    ),
    (0.9765, {}),
)
"""Nao type 4's own long kick (its toes change how the foot meets the ball): the same search
from :data:`LONG_KICK_KEYFRAMES`, type 4 alone (without noise and twice with the noise above),
the ball at :data:`LONG_KICK_BALL_START_POS`. Alone it moves the ball ~10 m on type 4, where
:data:`LONG_KICK_KEYFRAMES` gives ~7.9 m."""

LONG_KICK_KEYFRAMES_BY_TYPE: dict[int, Keyframes] = {4: LONG_KICK_KEYFRAMES_TYPE_4}
"""The Nao types with a long kick of their own (``kick_keyframes_by_type`` of ``LongKick-v1``);
the others play :data:`LONG_KICK_KEYFRAMES`."""

LONG_KICK_BALL_START_POS = (-0.8151, -0.0673)
"""Where ``LongKick-v1`` places the ball (x, y, m): 2.5 cm further ahead and 1.2 cm further
right than :data:`~robocup_gym.envs.tasks.reference_kick.KICK_BALL_START_POS`, the spot the
long kick was searched with."""


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
    * v1: plays the long kick (:data:`LONG_KICK_KEYFRAMES`, ``kick_keyframes``; type 4 its own,
      :data:`LONG_KICK_KEYFRAMES_BY_TYPE`) instead of the reference kick, with the ball at its
      spot (:data:`LONG_KICK_BALL_START_POS`): zero actions move the ball ~9.4–10 m instead of
      ~2.7 m.
    """

    config_class = LongKickConfig
    config: LongKickConfig

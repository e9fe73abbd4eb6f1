"""SimpleKick: kick the ball as far as possible (the RobocupGym paper's ``EnvSimpleKick``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from robocup_gym.envs.base_env import BaseEnv
from robocup_gym.envs.config import EnvConfig

__all__ = ["SimpleKick", "SimpleKickConfig"]


@dataclass
class SimpleKickConfig(EnvConfig):
    """:class:`EnvConfig` with SimpleKick's defaults (wait 200 cycles = 4 s so the ball stops)."""

    wait_steps: int = 200
    """Cycles the world runs on after the episode before the reward is measured (paper: 200)."""


class SimpleKick(BaseEnv):
    """Kick the ball as far as possible, in any direction.

    The robot stands at ``robot_start_pos`` facing +x with the ball 0.2 m ahead of its right foot.
    The episode lasts ``max_episode_steps`` (40) cycles or until the robot falls; then the world
    runs ``wait_steps`` (200) more cycles with the joints stopped and the reward is paid once:

    ============  ====================================================================
    step          reward
    ============  ====================================================================
    not final     0
    final         ``‖ball_pos − ball_spawn_pos‖`` in m, measured after ``wait_steps``
    ============  ====================================================================

    There are no reward coefficients. Everything else is :class:`SimpleKickConfig` /
    :class:`EnvConfig` (pass fields as keyword arguments).

    Version history:

    * v0: first release (robocup-gym 0.2.0).
    """

    config_class = SimpleKickConfig

    def _reward_terms(self, action: np.ndarray) -> dict[str, float]:
        if not self.has_completed:
            return {}
        d = self.ball_pos - self.ball_spawn_pos
        return {"distance": math.sqrt(float(d @ d))}

"""A new task is one small class: subclass a RoboCup Gym environment and name its reward terms.

python examples/custom_task.py
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robocup_gym.envs import BaseEnv, EnvConfig


@dataclass
class KickToTargetConfig(EnvConfig):
    """Task options are fields of a config subclass (documented, typed, overridable)."""

    target: tuple[float, float] = (1.0, 0.5)
    """Where the ball should stop, world frame, m."""
    wait_steps: int = 100
    observations: tuple[str, ...] = ("joint_pos", "joint_vel", "ball_rel", "gyro", "time")


class KickToTarget(BaseEnv):
    """Reward: minus the distance between where the ball stops and ``target``, once at the end."""

    config_class = KickToTargetConfig

    def _reward_terms(self, action: np.ndarray) -> dict[str, float]:
        if not self.has_completed:
            return {}
        miss = float(np.linalg.norm(self.ball_pos[:2] - np.array(self.config.target)))
        return {"miss": -miss}


if __name__ == "__main__":
    env = KickToTarget(target=(0.0, 0.0), max_episode_steps=30)
    obs, info = env.reset(seed=0)
    total = 0.0
    done = False
    while not done:
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        total += reward
        done = terminated or truncated
    print(f"return {total:.3f}; ball at {info['ball_pos'].round(3)}, fallen: {info['fallen']}")

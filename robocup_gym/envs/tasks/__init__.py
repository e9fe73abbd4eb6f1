"""Ready-made tasks. A new task is one small file: subclass BaseEnv (or a task) and override
``_get_reward``; see ``docs/environments.md``."""

from robocup_gym.envs.tasks.simple_kick import SimpleKick, SimpleKickConfig
from robocup_gym.envs.tasks.velocity_kick import VelocityKick, VelocityKickConfig

__all__ = ["SimpleKick", "SimpleKickConfig", "VelocityKick", "VelocityKickConfig"]

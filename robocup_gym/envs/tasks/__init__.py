"""Ready-made tasks. A new task is one small file: subclass BaseEnv (or a task) and override
``_reward_terms``; see ``docs/environments.md``."""

from robocup_gym.envs.tasks.getup import GetUp, GetUpConfig
from robocup_gym.envs.tasks.simple_kick import SimpleKick, SimpleKickConfig
from robocup_gym.envs.tasks.velocity_kick import VelocityKick, VelocityKickConfig
from robocup_gym.envs.tasks.walk import Walk, WalkConfig

__all__ = [
    "GetUp",
    "GetUpConfig",
    "SimpleKick",
    "SimpleKickConfig",
    "VelocityKick",
    "VelocityKickConfig",
    "Walk",
    "WalkConfig",
]

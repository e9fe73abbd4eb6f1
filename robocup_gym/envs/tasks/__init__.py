"""Ready-made tasks. A new task is one small file: subclass BaseEnv (or a task) and override
``_reward_terms``; see ``docs/environments.md``."""

from robocup_gym.envs.tasks.dribble import Dribble, DribbleConfig
from robocup_gym.envs.tasks.getup import GetUp, GetUpConfig
from robocup_gym.envs.tasks.long_kick import LongKick, LongKickConfig
from robocup_gym.envs.tasks.run import Run, RunConfig
from robocup_gym.envs.tasks.simple_kick import SimpleKick, SimpleKickConfig
from robocup_gym.envs.tasks.target_kick import TargetKick, TargetKickConfig
from robocup_gym.envs.tasks.velocity_kick import VelocityKick, VelocityKickConfig
from robocup_gym.envs.tasks.walk import Walk, WalkConfig

__all__ = [
    "Dribble",
    "DribbleConfig",
    "GetUp",
    "GetUpConfig",
    "LongKick",
    "LongKickConfig",
    "Run",
    "RunConfig",
    "SimpleKick",
    "SimpleKickConfig",
    "TargetKick",
    "TargetKickConfig",
    "VelocityKick",
    "VelocityKickConfig",
    "Walk",
    "WalkConfig",
]

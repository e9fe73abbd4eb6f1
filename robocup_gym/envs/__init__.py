"""Gymnasium environments for the simulated RoboCup 3D Nao.

Importing this package registers the tasks with Gymnasium::

    import gymnasium
    import robocup_gym.envs  # noqa: F401  (registers RobocupGym/*)

    env = gymnasium.make("RobocupGym/VelocityKick-v0", wait_steps=20, robot_type=0)

or use the classes directly (``VelocityKick()``, ``SimpleKick(max_episode_steps=60)``). The
options are documented in :class:`EnvConfig` and ``docs/environments.md``.
"""

import gymnasium as _gym

from robocup_gym.envs.base_env import BaseEnv, EpisodeStart
from robocup_gym.envs.config import (
    DEFAULT_OBSERVATIONS,
    PAPER_STANDING_POSE_DEG,
    ActionMode,
    EnvConfig,
    EnvConfigError,
    Normalisation,
)
from robocup_gym.envs.observations import COMPONENTS, component_names
from robocup_gym.envs.tasks import (
    Dribble,
    DribbleConfig,
    GetUp,
    GetUpConfig,
    LongKick,
    LongKickConfig,
    Run,
    RunConfig,
    SimpleKick,
    SimpleKickConfig,
    TargetKick,
    TargetKickConfig,
    VelocityKick,
    VelocityKickConfig,
    Walk,
    WalkConfig,
)
from robocup_gym.envs.tasks.long_kick import (
    LONG_KICK_BALL_START_POS,
    LONG_KICK_KEYFRAMES,
    LONG_KICK_KEYFRAMES_BY_TYPE,
)
from robocup_gym.envs.tasks.run import SPRINT_OPTIONS

__all__ = [
    "COMPONENTS",
    "DEFAULT_OBSERVATIONS",
    "PAPER_STANDING_POSE_DEG",
    "REGISTERED_IDS",
    "ActionMode",
    "BaseEnv",
    "Dribble",
    "DribbleConfig",
    "EnvConfig",
    "EnvConfigError",
    "EpisodeStart",
    "GetUp",
    "GetUpConfig",
    "LongKick",
    "LongKickConfig",
    "Normalisation",
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
    "component_names",
    "register_envs",
]

_ENTRY_POINTS = {
    "RobocupGym/SimpleKick-v0": "robocup_gym.envs.tasks.simple_kick:SimpleKick",
    "RobocupGym/VelocityKick-v0": "robocup_gym.envs.tasks.velocity_kick:VelocityKick",
    "RobocupGym/Walk-v0": "robocup_gym.envs.tasks.walk:Walk",
    "RobocupGym/Run-v0": "robocup_gym.envs.tasks.run:Run",
    "RobocupGym/Run-v1": "robocup_gym.envs.tasks.run:Run",
    "RobocupGym/GetUp-v0": "robocup_gym.envs.tasks.getup:GetUp",
    "RobocupGym/GetUp-v1": "robocup_gym.envs.tasks.getup:GetUp",
    "RobocupGym/TargetKick-v0": "robocup_gym.envs.tasks.target_kick:TargetKick",
    "RobocupGym/TargetKick-v1": "robocup_gym.envs.tasks.target_kick:TargetKick",
    "RobocupGym/LongKick-v0": "robocup_gym.envs.tasks.long_kick:LongKick",
    "RobocupGym/LongKick-v1": "robocup_gym.envs.tasks.long_kick:LongKick",
    "RobocupGym/Dribble-v0": "robocup_gym.envs.tasks.dribble:Dribble",
    "RobocupGym/Dribble-v1": "robocup_gym.envs.tasks.dribble:Dribble",
}
REGISTERED_IDS: tuple[str, ...] = tuple(_ENTRY_POINTS)
"""Every Gymnasium id this package registers."""
_ID_OPTIONS: dict[str, dict] = {
    "RobocupGym/GetUp-v1": {"self_collisions": True},
    "RobocupGym/Run-v1": SPRINT_OPTIONS,
    "RobocupGym/TargetKick-v1": {"kick_per_command": True, "ball_spawn_noise": 0.01},
    "RobocupGym/Dribble-v1": {"next_target_at_goal": True},
    "RobocupGym/LongKick-v1": {
        "kick_keyframes": LONG_KICK_KEYFRAMES,
        "kick_keyframes_by_type": LONG_KICK_KEYFRAMES_BY_TYPE,
        "ball_start_pos": LONG_KICK_BALL_START_POS,
    },
}
"""The options a version sets over its class's defaults (its docstring's version history)."""


def register_envs() -> None:
    """Register the RobocupGym ids with Gymnasium (idempotent; done on import)."""
    for env_id, entry_point in _ENTRY_POINTS.items():
        if env_id not in _gym.registry:
            # No max_episode_steps: the environments truncate themselves, after which they run
            # their wait steps and pay the final reward (a TimeLimit wrapper would skip that).
            _gym.register(id=env_id, entry_point=entry_point, kwargs=_ID_OPTIONS.get(env_id, {}))


register_envs()

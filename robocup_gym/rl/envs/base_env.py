"""Compatibility alias: the paper's ``robocup_gym.rl.envs.base_env.BaseEnv``.

It is :class:`robocup_gym.envs.compat.PaperBaseEnv`, i.e. :class:`robocup_gym.envs.BaseEnv` with
the paper's constructor and attributes (``python_agent_conn.player``, ``env_config``, …).
"""

from robocup_gym.envs.compat import PaperBaseEnv as BaseEnv

__all__ = ["BaseEnv"]

"""Compatibility alias: the paper's ``EnvSimpleKick`` (= :class:`robocup_gym.envs.SimpleKick`)."""

from robocup_gym.envs.tasks.env_simple_kick import EnvSimpleKick

__all__ = ["EnvSimpleKick"]

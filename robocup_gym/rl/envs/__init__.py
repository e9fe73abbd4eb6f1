"""Compatibility alias of :mod:`robocup_gym.envs` (the paper's ``robocup_gym.rl.envs``)."""

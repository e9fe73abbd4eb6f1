"""Compatibility aliases of the paper's tasks (see :mod:`robocup_gym.envs.compat`)."""

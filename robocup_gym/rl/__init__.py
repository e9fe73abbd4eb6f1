"""Compatibility package: the RobocupGym paper's module paths (``robocup_gym.rl.envs…``).

Thin aliases over :mod:`robocup_gym.envs` so the paper's listings run unchanged; see
:mod:`robocup_gym.envs.compat`. New code should import from :mod:`robocup_gym.envs`.
"""

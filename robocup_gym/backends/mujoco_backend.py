"""The MuJoCo engine's backend: :class:`robocup_gym.backends.in_process.MujocoBackend`."""

from robocup_gym.backends.in_process import MujocoBackend

__all__ = ["MujocoBackend"]

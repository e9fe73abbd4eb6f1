"""The ODE engine's in-process backend: :class:`robocup_gym.backends.in_process.OdeBackend`."""

from robocup_gym.backends.in_process import OdeBackend

__all__ = ["OdeBackend"]

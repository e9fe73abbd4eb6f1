"""Compatibility alias: the paper's ``KickVelocityReward``.

It is :class:`robocup_gym.envs.VelocityKick` with the paper's constructor.

The paper's arguments map onto :class:`~robocup_gym.envs.VelocityKickConfig`:
``coefficients=[a, b, c]`` → ``displacement_weight, speed_weight, lateral_weight``;
``square_y`` → ``square_lateral_penalty``; ``penalise_y_vel_too`` → ``penalise_y_velocity``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from robocup_gym.envs.compat import PaperEnvMixin
from robocup_gym.envs.config import EnvConfig, EnvConfigError
from robocup_gym.envs.tasks.velocity_kick import VelocityKick

__all__ = ["KickVelocityReward"]


class KickVelocityReward(PaperEnvMixin, VelocityKick):
    """The paper's velocity kick (reward a·dx + b·speed_xz − c·|y|, after ``wait_steps`` = 20)."""

    def __init__(
        self,
        env_config: EnvConfig | None = None,
        vectorise_index: int = 0,
        wait_steps: int = 20,
        coefficients: Sequence[float] | None = None,
        square_y: bool | None = None,
        penalise_y_vel_too: bool | None = None,
        **kwargs: Any,
    ) -> None:
        if coefficients is not None:
            if len(coefficients) != 3:
                raise EnvConfigError(f"coefficients must be [a, b, c], got {coefficients!r}")
            a, b, c = (float(v) for v in coefficients)
            kwargs.update(displacement_weight=a, speed_weight=b, lateral_weight=c)
        if square_y is not None:
            kwargs["square_lateral_penalty"] = bool(square_y)
        if penalise_y_vel_too is not None:
            kwargs["penalise_y_velocity"] = bool(penalise_y_vel_too)
        super().__init__(env_config, vectorise_index, wait_steps, **kwargs)

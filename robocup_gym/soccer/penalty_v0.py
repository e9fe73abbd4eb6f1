"""Penalty: one striker (``left_1``) against one goalkeeper (``right_1``).

The ball lies 4 m in front of the right team's goal, the striker 0.2 m behind it facing the
goal, the goalkeeper on its goal line facing the ball; play is on. The episode ends when a goal
is scored (the striker's team +``reward_goal``, the keeper's as much less), when the ball leaves
the field (a set piece is called) or after ``max_cycles`` (500 = 10 s). ``start_noise`` (m,
default 0) moves the ball and both players by up to that much in y at every reset.

``env(**options)`` is the AEC form, ``parallel_env(**options)`` the Parallel one; options are
those of :class:`robocup_gym.soccer.env.SoccerConfig` plus ``start_noise``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, ClassVar

import numpy as np

from robocup_gym.soccer.env import SoccerConfig, SoccerParallelEnv, scenario_functions
from robocup_gym.soccer.game import CycleReport, Start
from robocup_gym.types import is_number

__all__ = ["BALL_SPOT", "SPREAD_M", "PenaltyEnv", "env", "parallel_env", "raw_env"]

BALL_SPOT = (11.0, 0.0)
"""Where the ball lies, m (4 m in front of the right goal)."""
SPREAD_M = 0.3
"""The ``start_noise`` of penalties in matches and in team training, m."""


class PenaltyEnv(SoccerParallelEnv):
    metadata: ClassVar[dict] = {**SoccerParallelEnv.metadata, "name": "robocup_penalty_v0"}
    default_config = replace(
        SoccerConfig(), left_types=(0,), right_types=(0,), max_cycles=500, walk_faces_x=False
    )

    def __init__(self, render_mode: str | None = None, start_noise: float = 0.0, **options: Any):
        for side in ("left_types", "right_types"):
            if side in options and len(options[side]) != 1:
                raise ValueError(f"{side}: a penalty has one player a side, got {options[side]!r}")
        if not (is_number(start_noise) and np.isfinite(start_noise) and start_noise >= 0):
            raise ValueError(f"start_noise must be a finite distance >= 0, got {start_noise!r}")
        self.start_noise = float(start_noise)
        super().__init__(render_mode, **options)

    def _start(self, rng: np.random.Generator) -> Start:
        dy = rng.uniform(-self.start_noise, self.start_noise) if self.start_noise else 0.0
        bx, by = BALL_SPOT[0], BALL_SPOT[1] + dy
        return Start(
            players={"left_1": (bx - 0.2, by + 0.055, 0.0), "right_1": (14.6, dy / 2, 180.0)},
            ball=(bx, by),
        )

    def goalkeepers(self) -> set[str]:
        return {"right_1"}

    def _ended(self, report: CycleReport) -> str | None:
        if report.goal is not None:
            return f"goal for the {report.goal} team"
        if report.play_mode != "PlayOn":
            return f"the ball is out ({report.play_mode})"
        return None


parallel_env, raw_env, env = scenario_functions(PenaltyEnv, "penalty")

"""Keepaway: two attackers (``left_1``, ``left_2``) keep the ball from one defender
(``right_1``) inside a square of ``area`` metres (8) around the centre spot.

The attackers start 2 m apart on the left of the square with the ball at ``left_1``'s feet, the
defender on the right facing them; play is on (the automatic referee still calls a ball that
leaves the field). Every cycle the ball is kept pays the attackers ``reward_hold`` (0.01) and
takes as much from the defender. The episode ends when the defender touches the ball, when the
ball leaves the square or the play mode changes, or after ``max_cycles`` (1,500 = 30 s).

``env(**options)`` is the AEC form, ``parallel_env(**options)`` the Parallel one; options are
those of :class:`robocup_gym.soccer.env.SoccerConfig` plus ``area`` and ``reward_hold``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, ClassVar

import numpy as np

from robocup_gym.soccer.env import SoccerConfig, SoccerParallelEnv, scenario_functions
from robocup_gym.soccer.game import CycleReport, Start

__all__ = ["KeepawayEnv", "env", "parallel_env", "raw_env"]


class KeepawayEnv(SoccerParallelEnv):
    metadata: ClassVar[dict] = {**SoccerParallelEnv.metadata, "name": "robocup_keepaway_v0"}
    default_config = replace(
        SoccerConfig(), left_types=(0, 0), right_types=(0,), max_cycles=1500, walk_faces_x=False
    )

    def __init__(
        self,
        render_mode: str | None = None,
        area: float = 8.0,
        reward_hold: float = 0.01,
        **options: Any,
    ):
        if not np.isfinite(float(area)) or not 2.0 <= float(area) <= 20.0:
            raise ValueError(f"area must be a side length of 2-20 m, got {area!r}")
        if not np.isfinite(float(reward_hold)):
            raise ValueError(f"reward_hold must be finite, got {reward_hold!r}")
        self.area = float(area)
        self.reward_hold = float(reward_hold)
        super().__init__(render_mode, **options)
        if not self.config.left_types or not self.config.right_types:
            raise ValueError("keepaway needs attackers (left_types) and defenders (right_types)")

    def goalkeepers(self) -> set[str]:
        return set()  # nobody guards a goal

    def _start(self, rng: np.random.Generator) -> Start:
        h = self.area / 2
        c = self.config
        players = {}
        n_att = len(c.left_types)
        for k in range(n_att):
            y = (k - (n_att - 1) / 2) * 2.0
            players[f"left_{k + 1}"] = (-h + 1.0, max(-h + 0.5, min(h - 0.5, y)), 0.0)
        for k in range(len(c.right_types)):
            y = (k - (len(c.right_types) - 1) / 2) * 2.0
            players[f"right_{k + 1}"] = (h - 1.0, max(-h + 0.5, min(h - 0.5, y)), 180.0)
        x1, y1, _ = players["left_1"]
        return Start(players=players, ball=(x1 + 0.2, y1 - 0.055))

    def _ended(self, report: CycleReport) -> str | None:
        touch = self.game.last_touch
        if touch is not None and touch.side == "right":
            return "the defender won the ball"
        x, y = (float(v) for v in self.game.ball_position()[:2])
        if max(abs(x), abs(y)) > self.area / 2:
            return "the ball left the square"
        if report.play_mode != "PlayOn":
            return f"play stopped ({report.play_mode})"
        return None

    def _scenario_reward(self, report: CycleReport) -> dict[str, float]:
        return {"hold": self.reward_hold}


parallel_env, raw_env, env = scenario_functions(KeepawayEnv, "keepaway")

"""Penalty, version 1: :mod:`robocup_gym.soccer.penalty_v0`'s scenario (one striker, ``left_1``,
against one goalkeeper, ``right_1``; the ball 4 m in front of the right goal) whose walk skill
sees each player as if it faced +x (``walk_faces_x``), as it was trained: the goalkeeper, facing
−x, walks where it is told.

``env(**options)`` is the AEC form, ``parallel_env(**options)`` the Parallel one; options are
those of :class:`robocup_gym.soccer.env.SoccerConfig` plus ``start_noise``.

Version history:

* v1: with skill actions the walk sees each player as if it faced +x.
* v0: the walk saw the torso's orientation in the world frame: a player facing −x walked askew,
  hardly turned clockwise and fell walking sideways.
"""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

from robocup_gym.soccer import penalty_v0
from robocup_gym.soccer.env import SoccerParallelEnv, scenario_functions
from robocup_gym.soccer.penalty_v0 import BALL_SPOT, SPREAD_M

__all__ = ["BALL_SPOT", "SPREAD_M", "PenaltyEnv", "env", "parallel_env", "raw_env"]


class PenaltyEnv(penalty_v0.PenaltyEnv):
    metadata: ClassVar[dict] = {**SoccerParallelEnv.metadata, "name": "robocup_penalty_v1"}
    default_config = replace(penalty_v0.PenaltyEnv.default_config, walk_faces_x=True)


parallel_env, raw_env, env = scenario_functions(PenaltyEnv, "penalty")

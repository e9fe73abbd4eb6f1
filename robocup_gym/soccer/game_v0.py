"""The game, version 0: :mod:`robocup_gym.soccer.game_v1` with the referee of that version, which
ended a kick-off, kick-in, corner, goal or free kick only with the drop ball after 15 s, not at
the first touch of the ball (``first_touch_plays_on=False``), and whose walk skill saw the
torso's orientation in the world frame (``walk_faces_x=False``). Use ``game_v1``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

from robocup_gym.soccer import game_v1
from robocup_gym.soccer.env import SoccerParallelEnv, scenario_functions

__all__ = ["GameEnv", "env", "parallel_env", "raw_env"]


class GameEnv(game_v1.GameEnv):
    metadata: ClassVar[dict] = {**SoccerParallelEnv.metadata, "name": "robocup_game_v0"}
    default_config = replace(
        game_v1.GameEnv.default_config, first_touch_plays_on=False, walk_faces_x=False
    )


parallel_env, raw_env, env = scenario_functions(GameEnv, "game")

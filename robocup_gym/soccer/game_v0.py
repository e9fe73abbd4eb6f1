"""The game, version 0: :mod:`robocup_gym.soccer.game_v1` with the referee of that version, which
ended a kick-off, kick-in, corner, goal or free kick only with the drop ball after 15 s, not at
the first touch of the ball (``first_touch_plays_on=False``). Use ``game_v1``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, ClassVar

from robocup_gym.soccer import game_v1
from robocup_gym.soccer.env import SoccerParallelEnv, aec_from_parallel, scenario_env

__all__ = ["GameEnv", "env", "parallel_env", "raw_env"]


class GameEnv(game_v1.GameEnv):
    metadata: ClassVar[dict] = {**SoccerParallelEnv.metadata, "name": "robocup_game_v0"}
    default_config = replace(game_v1.GameEnv.default_config, first_touch_plays_on=False)


def parallel_env(**options: Any):
    """The scenario's Parallel environment; ``robot="T1"`` or ``"K1"`` plays it on the league's
    simulator (:mod:`robocup_gym.soccer.league`)."""
    return scenario_env(GameEnv, "game", options)


def raw_env(**options: Any):
    return aec_from_parallel(parallel_env(**options))


env = raw_env

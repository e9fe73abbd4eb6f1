"""The game: N against N (1–11 a side, mixed robot types) on the full field with the automatic
referee (kick-off, goals, ball out with kick-in, corner and goal kick, half time).

Both teams stand in their kick-off formation (:mod:`robocup_gym.soccer.formation`; the right
team's player 2 outside the centre circle) and the left team kicks off. The episode ends at game
over (600 s of game time) or, truncated, after ``max_cycles`` (3,000 = 60 s by default; 30,000
for a whole game). Goals pay ``reward_goal`` (team-shared, zero-sum); ``ball_progress`` and
``possession`` are the optional shaping terms of :mod:`robocup_gym.soccer.env`. 11 against 11
with types mixed as the league allows is the real game. With ``random_start=True`` every player
and the ball start at random places on the field, in play (a training aid: goals come early).

``env(**options)`` is the AEC form, ``parallel_env(**options)`` the Parallel one; options are
those of :class:`robocup_gym.soccer.env.SoccerConfig`.

Version history:

* v1: a kick-off, kick-in, corner, goal or free kick ends at the first touch of the ball (after
  a set piece's 1 s pause), as on rcssserver3d; with skill actions the walk sees each player as
  if it faced +x (a player facing −x walked askew, hardly turned clockwise and fell walking
  sideways).
* v0: the referee ended them only with the drop ball after 15 s.
"""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

import numpy as np

from robocup_gym.soccer.env import (
    SoccerConfig,
    SoccerParallelEnv,
    random_start,
    scenario_functions,
)
from robocup_gym.soccer.formation import kickoff_positions
from robocup_gym.soccer.game import Start

__all__ = ["GameEnv", "env", "parallel_env", "raw_env"]


class GameEnv(SoccerParallelEnv):
    metadata: ClassVar[dict] = {**SoccerParallelEnv.metadata, "name": "robocup_game_v1"}
    default_config = replace(SoccerConfig(), left_types=(0, 1), right_types=(0, 1), max_cycles=3000)

    random_starts: ClassVar[bool] = True

    def _start(self, rng: np.random.Generator) -> Start:
        c = self.config
        if c.random_start:
            return random_start(self.possible_agents, rng)
        players = {}
        for side, types in (("left", c.left_types), ("right", c.right_types)):
            for k, pos in enumerate(kickoff_positions(side, len(types), side == "left")):
                players[f"{side}_{k + 1}"] = pos
        return Start(players=players, ball=(0.0, 0.0), play_mode="KickOff_Left")


parallel_env, raw_env, env = scenario_functions(GameEnv, "game")

"""Keepaway, version 1: :mod:`robocup_gym.soccer.keepaway_v0`'s scenario (two attackers keep
the ball from one defender inside a square around the centre spot) whose walk skill sees each
player as if it faced +x (``walk_faces_x``), as it was trained: the defender, facing −x, walks
where it is told.

``env(**options)`` is the AEC form, ``parallel_env(**options)`` the Parallel one; options are
those of :class:`robocup_gym.soccer.env.SoccerConfig` plus ``area`` and ``reward_hold``.

Version history:

* v1: with skill actions the walk sees each player as if it faced +x.
* v0: the walk saw the torso's orientation in the world frame: a player facing −x walked askew,
  hardly turned clockwise and fell walking sideways.
"""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

from robocup_gym.soccer import keepaway_v0
from robocup_gym.soccer.env import SoccerParallelEnv, scenario_functions

__all__ = ["KeepawayEnv", "env", "parallel_env", "raw_env"]


class KeepawayEnv(keepaway_v0.KeepawayEnv):
    metadata: ClassVar[dict] = {**SoccerParallelEnv.metadata, "name": "robocup_keepaway_v1"}
    default_config = replace(keepaway_v0.KeepawayEnv.default_config, walk_faces_x=True)


parallel_env, raw_env, env = scenario_functions(KeepawayEnv, "keepaway")

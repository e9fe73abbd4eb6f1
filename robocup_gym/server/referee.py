"""The rules of the game live in :mod:`robocup_gym.sim.referee` and the teams in
:mod:`robocup_gym.sim.teams`; this module keeps their old import path."""

from robocup_gym.sim.referee import BEAM_MODES, Referee, other
from robocup_gym.sim.teams import InitError, Player, TeamRegistry

__all__ = ["BEAM_MODES", "InitError", "Player", "Referee", "TeamRegistry", "other"]

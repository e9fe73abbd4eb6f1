"""The rules of the game live in :mod:`robocup_gym.sim.referee`; this module keeps their old
import path."""

from robocup_gym.sim.referee import (
    BEAM_MODES,
    InitError,
    Player,
    Referee,
    TeamRegistry,
    other,
)

__all__ = ["BEAM_MODES", "InitError", "Player", "Referee", "TeamRegistry", "other"]

"""Names and numbers the protocol exposes (wire reference §7.3, §9, §10)."""

from __future__ import annotations

from robocup_gym.types import PLAY_MODES  # defined with the game state

__all__ = [
    "DEFAULT_AGENT_PORT",
    "DEFAULT_ENVIRONMENT",
    "DEFAULT_MONITOR_PORT",
    "PLAY_MODES",
    "TEAM_SIDES",
    "play_mode_id",
]

DEFAULT_AGENT_PORT = 3100
"""TCP port agents connect to."""
DEFAULT_MONITOR_PORT = 3200
"""TCP port of monitors and trainers."""

TEAM_SIDES = ("Left", "Right")
"""Team atoms of trainer commands (``None`` is also accepted by ``kickOff``)."""

DEFAULT_ENVIRONMENT: tuple[tuple[str, float], ...] = (
    ("FieldLength", 30),
    ("FieldWidth", 20),
    ("FieldHeight", 40),
    ("GoalWidth", 2.1),
    ("GoalDepth", 0.6),
    ("GoalHeight", 0.8),
    ("BorderSize", 0),
    ("FreeKickDistance", 2),
    ("WaitBeforeKickOff", 30),
    ("AgentRadius", 0.4),
    ("BallRadius", 0.042),
    ("BallMass", 0.026),
    ("RuleGoalPauseTime", 3),
    ("RuleKickInPauseTime", 1),
    ("RuleHalfTime", 300),
    ("PassModeMinOppBallDist", 1),
    ("PassModeDuration", 4),
)
"""The static environment predicates of a full monitor frame, in the server's order (§7.3)."""

_PLAY_MODE_IDS = {name: i for i, name in enumerate(PLAY_MODES)}


def play_mode_id(name: str) -> int:
    """Numeric id of a play-mode name (``"PlayOn"`` → 3).

    Raises:
        KeyError: for an unknown name, listing the valid ones.
    """
    try:
        return _PLAY_MODE_IDS[name]
    except KeyError:
        raise KeyError(f"unknown play mode {name!r}; valid: {', '.join(PLAY_MODES)}") from None

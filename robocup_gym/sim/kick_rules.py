"""rcssserver3d's rules on the kick that restarts play and on scoring (reference §9.3, §9.6):
which goals count, and the taker's second touch.

* **The kick-off team may not score at once.** With more than 2 players in the game, after a
  kick-off the kicking team's goal counts only once the other team has touched the ball, or the
  kicking team has touched it outside the centre circle (2 m); a goal before that gives the
  defenders a goal kick.
* **No goal straight from an indirect kick, no own goal straight from any set piece.** With more
  than 2 players, a goal whose last touch was the taker's kick (its touch less than 0.1 s after
  the taking touch) after a kick-off, kick-in or indirect free kick, or into the taker's own goal
  after any set piece, does not count: the defenders get a goal kick, or, for an own goal, the
  other team a corner kick. Corner kicks, goal kicks and direct free kicks may score directly.
* **The taker may not touch the ball twice in a row.** When the last touch is the taker's again
  later than 0.1 s after its kick (a longer touch counts as a second one) with nobody else in
  between, the other team gets an indirect free kick where the ball is.
* **After pass mode** a team cannot score for 10 s unless two different team-mates touched the
  ball after it left the 1 m circle around where pass mode held it; a goal in that time gives the
  defenders a goal kick.

:class:`KickRules` keeps this state; :class:`~robocup_gym.sim.referee.Referee` drives it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "FREE_KICK_DISTANCE",
    "KICK_DURATION_S",
    "PASS_MODE_MIN_OPP_DIST",
    "PASS_MODE_SCORE_WAIT_S",
    "KickRules",
    "TakenKick",
]

KICK_DURATION_S = 0.1
"""A touch within this time of the taking touch is still the same kick."""
PASS_MODE_SCORE_WAIT_S = 10.0
"""``PassModeScoreWaitTime``: how long after pass mode a team needs two touches to score."""
PASS_MODE_MIN_OPP_DIST = 1.0
"""``PassModeMinOppBallDist``, m: opponents kept this far from the ball in pass mode, and the
circle the ball must leave after it."""
FREE_KICK_DISTANCE = 2.0
"""``FreeKickDistance``, m: opponents kept this far at set pieces; outside it (the centre
circle) the kick-off team may score."""


def _other(side: str) -> str:
    return "right" if side == "left" else "left"


@dataclass
class TakenKick:
    """The touch that restarted play."""

    taker: Any
    """The player (``side``, ``unum``)."""
    time: float
    """Game time of the taking touch, s."""
    indirect: bool
    watched: bool = True
    """Whether the taker's second touch is still watched (until someone else plays the ball)."""


@dataclass
class KickRules:
    """The state of the kick and scoring rules (see the module docstring)."""

    kick: TakenKick | None = None
    kick_off_taker: Any = None
    """The kick-off's taker while its team may not score (``None``: it may)."""
    pass_time: dict[str, float] = field(default_factory=lambda: {"left": -1e3, "right": -1e3})
    """Each team's last game time in pass mode."""
    pass_cleared: dict[str, bool] = field(default_factory=lambda: {"left": False, "right": False})
    pass_first: dict[str, int] = field(default_factory=lambda: {"left": -1, "right": -1})
    """The number of the first team-mate to touch the ball since pass mode (-1: none)."""
    pass_ball: dict[str, np.ndarray] = field(default_factory=dict)
    pass_left_circle: dict[str, bool] = field(
        default_factory=lambda: {"left": False, "right": False}
    )
    pass_multiple: dict[str, bool] = field(default_factory=lambda: {"left": False, "right": False})
    """Whether a second team-mate has touched the ball since pass mode."""

    @staticmethod
    def _same(a: Any, b: Any) -> bool:
        return a is not None and b is not None and (a.side, a.unum) == (b.side, b.unum)

    # ------------------------------------------------------------------ restarts
    def restart(self) -> None:
        """A cycle of a kick-off or of a set piece after its pause (``ResetKickChecks``): no
        kick watched, the pass-mode windows closed."""
        if self.kick is not None:
            self.kick.watched = False
            self.kick.indirect = False
        self.pass_time = {"left": -1e3, "right": -1e3}

    def kick_off(self) -> None:
        """A cycle of a kick-off: its team may score (until the kick is taken)."""
        self.restart()
        self.kick_off_taker = None

    def taken(self, taker: Any, time: float, indirect: bool, *, kick_off: bool = False) -> None:
        """The touch that restarted play."""
        self.kick = TakenKick(taker, float(time), bool(indirect))
        if kick_off:
            self.kick_off_taker = taker

    def ball_touched_by(self, sides: set[str], ball_xy: np.ndarray) -> None:
        """Every cycle: the teams touching the ball now; once the other team, or the kick-off
        team outside the centre circle, has, the kick-off team may score."""
        if self.kick_off_taker is None:
            return
        team = self.kick_off_taker.side
        outside = float(np.hypot(*ball_xy[:2])) > FREE_KICK_DISTANCE
        if _other(team) in sides or (team in sides and outside):
            self.kick_off_taker = None

    # ------------------------------------------------------------------ play on
    def straight_from_kick(self, last: Any, last_time: float) -> bool:
        """Whether the last touch (``last`` at game time ``last_time``) is the restarting kick
        itself (``WasLastKickFromFreeKick``)."""
        k = self.kick
        return (
            k is not None
            and self._same(last, k.taker)
            and last_time - k.time < KICK_DURATION_S - 1e-9
        )

    def second_touch(self, last: Any, last_time: float) -> bool:
        """In play: whether the taker has just touched the ball a second time in a row; the
        watch ends at the first touch that is not the kick."""
        k = self.kick
        if k is None or not k.watched or self.straight_from_kick(last, last_time):
            return False
        k.watched = False
        k.indirect = False
        return self._same(last, k.taker)

    def goal(
        self, scored_on: str, last: Any, last_time: float, game_time: float, many: bool
    ) -> tuple[str, str | None]:
        """The verdict on a ball in ``scored_on``'s goal: ``("goal", None)``, or the award
        instead, ``("goal_kick", team)`` or ``("corner_kick", team)``. ``many``: more than 2
        players in the game."""
        if self.kick_off_taker is not None and scored_on != self.kick_off_taker.side:
            return self._punish(self.kick_off_taker, scored_on)
        k = self.kick
        if (
            many
            and self.straight_from_kick(last, last_time)
            and (k.indirect or k.taker.side == scored_on)
        ):
            return self._punish(k.taker, scored_on)
        scorer = _other(scored_on)
        if self._waiting(scorer, game_time):
            return "goal_kick", scored_on
        return "goal", None

    def _punish(self, taker: Any, scored_on: str) -> tuple[str, str]:
        if self.kick is not None:
            self.kick.indirect = False
        if taker.side == scored_on:  # an own goal: a corner kick for the other team
            return "corner_kick", _other(taker.side)
        return "goal_kick", scored_on

    # ------------------------------------------------------------------ pass mode
    def score_wait(self, side: str, game_time: float) -> float | None:
        """How long ``side`` is still barred from scoring after its pass mode (s; its last
        cycle in pass mode less than :data:`PASS_MODE_SCORE_WAIT_S` ago and not cleared), else
        ``None``. In single precision, as rcssserver3d computes the monitors' figure."""
        if not self._waiting(side, game_time):
            return None
        since = np.float32(game_time) - np.float32(self.pass_time[side])
        return float(np.float32(PASS_MODE_SCORE_WAIT_S) - since)

    def _waiting(self, side: str, game_time: float) -> bool:
        """Whether ``side`` is barred from scoring after its pass mode: its last cycle in pass
        mode less than :data:`PASS_MODE_SCORE_WAIT_S` ago and not cleared since."""
        return (
            game_time - self.pass_time[side] < PASS_MODE_SCORE_WAIT_S
            and not self.pass_cleared[side]
        )

    def in_pass_mode(self, side: str, game_time: float, ball_xy: np.ndarray) -> None:
        """A cycle of ``side``'s pass mode: its scoring window starts again."""
        self.pass_time[side] = float(game_time)
        self.pass_first[side] = -1
        self.pass_multiple[side] = False
        self.pass_left_circle[side] = False
        self.pass_cleared[side] = False
        self.pass_time[_other(side)] = -1e3
        self.pass_ball[side] = np.asarray(ball_xy[:2], dtype=float).copy()

    def after_pass_mode(self, touchers: list[Any], game_time: float, ball_xy: np.ndarray) -> None:
        """In play: the team in its window after pass mode clears it when the ball has left the
        1 m circle and a second team-mate touches it."""
        team = None
        for side in ("left", "right"):
            if self._waiting(side, game_time):
                team = side
                break
        if team is None:
            return
        if not self.pass_left_circle[team]:
            start = self.pass_ball.get(team, np.zeros(2))
            if float(np.hypot(*(ball_xy[:2] - start))) >= PASS_MODE_MIN_OPP_DIST:
                self.pass_left_circle[team] = True
        for p in touchers:
            if p.side != team:
                continue
            first = self.pass_first[team]
            if first > 0 and (first != p.unum or self.pass_multiple[team]):
                self.pass_multiple[team] = True
                if self.pass_left_circle[team]:
                    self.pass_cleared[team] = True
                break
            self.pass_first[team] = p.unum

"""Where players stand at a kick-off: one formation of 11 for the left team (own half, facing
+x); the right team's is its mirror image. A team of N uses the first N places (goalkeeper
first)."""

from __future__ import annotations

__all__ = ["KICKOFF_FORMATION", "RECEIVING_KICKER_PLACE", "kickoff_positions"]

KICKOFF_FORMATION: tuple[tuple[float, float], ...] = (
    (-14.0, 0.0),
    (-1.0, 0.0),
    (-9.0, -3.0),
    (-9.0, 3.0),
    (-5.0, -6.0),
    (-5.0, 6.0),
    (-5.0, 0.0),
    (-2.5, -3.5),
    (-2.5, 3.5),
    (-11.0, 0.0),
    (-7.0, -8.0),
)
"""(x, y) of the left team's places, m: goalkeeper, kicker at the centre circle, then the rest."""
RECEIVING_KICKER_PLACE = (-2.5, 0.0)
"""Player 2's place when the other team kicks off: outside the centre circle (2 m), which the
referee keeps clear of the defenders."""


def kickoff_positions(side: str, n: int, kicking: bool = True) -> list[tuple[float, float, float]]:
    """``(x, y, heading_deg)`` of players 1…n of ``side`` (left faces +x, right faces −x), for
    the team that kicks off (``kicking``) or the other."""
    if not 0 <= n <= len(KICKOFF_FORMATION):
        raise ValueError(f"a team has 0-{len(KICKOFF_FORMATION)} players, got {n}")
    places = list(KICKOFF_FORMATION[:n])
    if not kicking and n >= 2:
        places[1] = RECEIVING_KICKER_PLACE
    if side == "left":
        return [(x, y, 0.0) for x, y in places]
    return [(-x, -y, 180.0) for x, y in places]

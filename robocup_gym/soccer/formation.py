"""Where players stand at a kick-off: one formation of 11 for the left team (own half, facing
+x); the right team's is its mirror image. A team of N uses the first N places (goalkeeper
first)."""

from __future__ import annotations

__all__ = ["KICKOFF_FORMATION", "kickoff_positions"]

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


def kickoff_positions(side: str, n: int) -> list[tuple[float, float, float]]:
    """``(x, y, heading_deg)`` of players 1…n of ``side`` (left faces +x, right faces −x)."""
    if not 0 <= n <= len(KICKOFF_FORMATION):
        raise ValueError(f"a team has 0-{len(KICKOFF_FORMATION)} players, got {n}")
    if side == "left":
        return [(x, y, 0.0) for x, y in KICKOFF_FORMATION[:n]]
    return [(-x, -y, 180.0) for x, y in KICKOFF_FORMATION[:n]]

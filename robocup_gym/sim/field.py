"""The soccer field of rcssserver3d: dimensions, landmarks, lines seen by vision (reference §6)."""

from __future__ import annotations

import math

import numpy as np

FIELD_LENGTH = 30.0
"""m, x from −15 to +15."""
FIELD_WIDTH = 20.0
"""m, y from −10 to +10."""
GOAL_WIDTH = 2.1
GOAL_DEPTH = 0.6
GOAL_HEIGHT = 0.8
PENALTY_LENGTH = 1.8
PENALTY_HALF_WIDTH = 3.0
"""Half of the drawn/used penalty-area width (PenaltyWidth + GoalWidth)/2, m."""
CENTRE_CIRCLE_RADIUS = 2.0
FIELD_HALF_LENGTH = FIELD_LENGTH / 2
"""m: the goal lines are at x = ±15."""
FIELD_HALF_WIDTH = FIELD_WIDTH / 2
"""m: the side lines are at y = ±10."""
GOAL_HALF_WIDTH = GOAL_WIDTH / 2
PENALTY_X = FIELD_HALF_LENGTH - PENALTY_LENGTH
"""|x| beyond which a point is inside a penalty area (with |y| < :data:`PENALTY_HALF_WIDTH`), m."""


def _goal_boxes(
    side: int,
) -> list[tuple[str, tuple[float, float, float], tuple[float, float, float]]]:
    s = "L" if side < 0 else "R"
    x0 = side * 15.3
    return [
        (f"goal{s}_post1", (x0, 1.07, 0.4), (0.6, 0.04, 0.8)),
        (f"goal{s}_post2", (x0, -1.07, 0.4), (0.6, 0.04, 0.8)),
        (f"goal{s}_back", (side * 15.58, 0.0, 0.4), (0.04, 2.1, 0.8)),
        (f"goal{s}_bar", (x0, 0.0, 0.82), (0.6, 2.18, 0.04)),
    ]


WALLS: tuple[tuple[str, tuple[float, float, float], tuple[float, float, float]], ...] = (
    ("wall_left", (-24.99, 0.0, 0.0), (1.0, 51.0, 1.0)),
    ("wall_right", (24.99, 0.0, 0.0), (1.0, 51.0, 1.0)),
    ("wall_back", (0.0, 25.0, 0.0), (50.98, 1.0, 1.0)),
    ("wall_front", (0.0, -25.0, 0.0), (50.98, 1.0, 1.0)),
)
"""The four static walls around the field (reference §6.2): name, centre (m), full size (m)."""
GOAL_BOXES = tuple(_goal_boxes(-1) + _goal_boxes(1))
"""The goals' solid parts (reference §6.3), left goal first: side walls, back wall, top bar; name,
centre (m), full size (m). The goal sensor box makes no contacts and is not listed."""

#: Landmarks seen by vision, in the server's model order (world frame, not mirrored), m.
LANDMARKS: dict[str, tuple[float, float, float]] = {
    "G1L": (-15.0, 1.05, 0.8),
    "G2L": (-15.0, -1.05, 0.8),
    "G2R": (15.0, -1.05, 0.8),
    "G1R": (15.0, 1.05, 0.8),
    "F1L": (-15.0, 10.0, 0.0),
    "F2L": (-15.0, -10.0, 0.0),
    "F1R": (15.0, 10.0, 0.0),
    "F2R": (15.0, -10.0, 0.0),
}


def _field_lines() -> list[tuple[tuple[float, float], tuple[float, float]]]:
    lines = [
        ((0.0, -10.0), (0.0, 10.0)),
        ((15.0, -10.0), (15.0, 10.0)),
        ((-15.0, -10.0), (-15.0, 10.0)),
        ((15.0, 10.0), (-15.0, 10.0)),
        ((15.0, -10.0), (-15.0, -10.0)),
        ((13.2, 3.0), (13.2, -3.0)),
        ((13.2, 3.0), (15.0, 3.0)),
        ((13.2, -3.0), (15.0, -3.0)),
        ((-13.2, 3.0), (-13.2, -3.0)),
        ((-13.2, 3.0), (-15.0, 3.0)),
        ((-13.2, -3.0), (-15.0, -3.0)),
    ]
    pts = [
        (
            CENTRE_CIRCLE_RADIUS * math.cos(math.radians(a)),
            CENTRE_CIRCLE_RADIUS * math.sin(math.radians(a)),
        )
        for a in range(0, 360, 36)
    ]
    lines += [(pts[i], pts[(i + 1) % 10]) for i in range(10)]
    return lines


#: The 21 field lines of reference §6.4 as ((x1, y1), (x2, y2)), all at z = 0.
FIELD_LINES = _field_lines()
#: The same as an array of shape (21, 2, 3) (end points with z = 0).
FIELD_LINE_POINTS = np.array([[[a[0], a[1], 0.0], [b[0], b[1], 0.0]] for a, b in FIELD_LINES])

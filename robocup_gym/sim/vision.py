"""Restricted vision (``See``): geometry, field of view, line clipping and noise (spec §4.7).

All functions are pure: they take world positions and the head pose and return polar coordinates
``(distance m, horizontal deg, vertical deg)`` relative to the head, horizontal positive to the
robot's left, vertical positive up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robocup_gym.sim.field import FIELD_LINE_POINTS, LANDMARKS
from robocup_gym.types import SeenPlayer, Vision

DISTANCE_NOISE_PERCENT = 0.0965
"""σ of the distance noise in % of the distance."""
HORIZONTAL_NOISE_DEG = 0.1480
"""σ of the horizontal-angle noise (the code's assignment; the manual swaps the two)."""
VERTICAL_NOISE_DEG = 0.1225
CALIBRATION_ERROR_M = 0.005
"""Half-width of the per-robot uniform calibration offset, per axis, m."""
MIN_DISTANCE_M = 0.1
PLAYER_PARTS = ("head", "rlowerarm", "llowerarm", "rfoot", "lfoot")

_LANDMARK_NAMES = tuple(LANDMARKS)
_LANDMARK_POS = np.array(list(LANDMARKS.values()))


@dataclass(frozen=True)
class VisionConfig:
    """How the ``See`` perceptor behaves.

    Attributes:
        noise: Gaussian distance/angle noise and the per-robot calibration offset (rcssserver3d
            default on). ``False`` gives exact polar coordinates.
        view_cone_deg: Full horizontal and vertical opening (120 on the real server; 360 for
            "full vision").
        interval: Vision every ``interval`` cycles (3 on the real server).
        ground_truth: Add the ``mypos``/``myorien``/``ballpos`` extensions (off in competitions).
        lines: Report field lines.
    """

    noise: bool = True
    view_cone_deg: float = 120.0
    interval: int = 3
    ground_truth: bool = False
    lines: bool = True


def to_head_frame(points: np.ndarray, head_pos: np.ndarray, head_rot: np.ndarray) -> np.ndarray:
    """World points (n, 3) → head frame (x right, y forward, z up), m."""
    return (points - head_pos) @ head_rot


def polar(rel: np.ndarray) -> np.ndarray:
    """Head-frame points (n, 3) → polar (n, 3): distance m, horizontal deg, vertical deg."""
    x, y, z = rel[:, 0], rel[:, 1], rel[:, 2]
    d = np.sqrt(x * x + y * y + z * z)
    theta = np.degrees(np.arctan2(y, x)) - 90.0
    theta = (theta + 180.0) % 360.0 - 180.0
    phi = np.degrees(np.arctan2(z, np.sqrt(x * x + y * y)))
    return np.stack([d, theta, phi], axis=1)


def _visible(pol: np.ndarray, half_cone: float) -> np.ndarray:
    return (
        (pol[:, 0] > MIN_DISTANCE_M)
        & (np.abs(pol[:, 1]) <= half_cone)
        & (np.abs(pol[:, 2]) <= half_cone)
    )


def _noisy(pol: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    out = pol.copy()
    n = len(pol)
    out[:, 0] += rng.normal(0.0, DISTANCE_NOISE_PERCENT, n) * out[:, 0] / 100.0
    out[:, 1] += rng.normal(0.0, HORIZONTAL_NOISE_DEG, n)
    out[:, 2] += rng.normal(0.0, VERTICAL_NOISE_DEG, n)
    return out


def clip_segment(a: np.ndarray, b: np.ndarray, half_cone_deg: float) -> tuple | None:
    """Clip a head-frame segment to the view pyramid (near plane 0.1 m along +y, sides at
    ±half_cone). Returns the clipped end points or ``None`` if nothing is inside (Liang–Barsky)."""
    t = np.tan(np.radians(min(half_cone_deg, 89.0)))
    d = b - a
    t0, t1 = 0.0, 1.0
    # each plane: n · p >= c  → written as f(p) = n·p - c >= 0
    planes = (
        (np.array([0.0, 1.0, 0.0]), MIN_DISTANCE_M),
        (np.array([-1.0, t, 0.0]), 0.0),
        (np.array([1.0, t, 0.0]), 0.0),
        (np.array([0.0, t, -1.0]), 0.0),
        (np.array([0.0, t, 1.0]), 0.0),
    )
    for n, c in planes:
        fa = float(n @ a) - c
        fd = float(n @ d)
        if abs(fd) < 1e-12:
            if fa < 0:
                return None
            continue
        tt = -fa / fd
        if fd > 0:
            t0 = max(t0, tt)
        else:
            t1 = min(t1, tt)
        if t0 > t1:
            return None
    return a + t0 * d, a + t1 * d


def see(
    *,
    head_pos: np.ndarray,
    head_rot: np.ndarray,
    ball_pos: np.ndarray,
    players: list[tuple[str, int, np.ndarray]],
    calibration: np.ndarray,
    rng: np.random.Generator,
    config: VisionConfig,
    mirror: bool = False,
) -> Vision:
    """Build one ``See`` percept.

    Args:
        head_pos: Head centre, world, m.
        head_rot: Head rotation matrix (columns = head x/y/z axes in world).
        ball_pos: Ball centre, world, m.
        players: ``(team name, unum, parts (5, 3) world positions in PLAYER_PARTS order)`` for every
            robot that has a team (the observer included).
        calibration: This robot's fixed calibration offset (3,), m (zeros when noise is off).
        rng: Noise source.
        config: Vision settings.
        mirror: True for a right-team observer (ground-truth extensions are team-mirrored).
    """
    half = float(int(config.view_cone_deg) // 2)
    cal = calibration if config.noise else np.zeros(3)
    objs = np.vstack([_LANDMARK_POS, ball_pos[None, :]])
    rel = to_head_frame(objs, head_pos, head_rot) + cal
    pol = polar(rel)
    vis = _visible(pol, half)
    if config.noise:
        pol = _noisy(pol, rng)
    names = (*_LANDMARK_NAMES, "B")
    objects = {names[i]: pol[i] for i in np.flatnonzero(vis)}

    seen_players: list[SeenPlayer] = []
    for team, unum, parts in players:
        prel = to_head_frame(parts, head_pos, head_rot) + cal
        ppol = polar(prel)
        pvis = _visible(ppol, half)
        if not pvis.any():
            continue
        if config.noise:
            ppol = _noisy(ppol, rng)
        seen_players.append(
            SeenPlayer(team, unum, {PLAYER_PARTS[i]: ppol[i] for i in np.flatnonzero(pvis)})
        )

    lines = np.zeros((0, 2, 3))
    if config.lines:
        ends = to_head_frame(FIELD_LINE_POINTS.reshape(-1, 3), head_pos, head_rot) + cal
        ends = ends.reshape(-1, 2, 3)
        out = []
        for a, b in ends:
            seg = clip_segment(a, b, half)
            if seg is None:
                continue
            lp = polar(np.stack(seg))
            if not _visible(lp, half + 1e-6).all():
                continue
            out.append(lp)
        if out:
            lines = np.stack(out)
            if config.noise:
                lines = _noisy(lines.reshape(-1, 3), rng).reshape(-1, 2, 3)

    vision = Vision(objects=objects, players=seen_players, lines=lines)
    if config.ground_truth:
        s = -1.0 if mirror else 1.0
        vision.my_pos = head_pos * np.array([s, s, 1.0])
        fwd = head_rot[:, 1]
        heading = float(np.degrees(np.arctan2(fwd[1], fwd[0])))
        if mirror:
            heading = (heading + 360.0) % 360.0 - 180.0
        vision.my_orientation_deg = heading
        vision.ball_pos = ball_pos * np.array([s, s, 1.0])
    return vision

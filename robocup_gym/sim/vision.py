"""Restricted vision (``See``): geometry, field of view, line clipping and noise (reference §4.7).

All functions are pure: they take world positions and the head pose and return polar coordinates
``(distance m, horizontal deg, vertical deg)`` relative to the head, horizontal positive to the
robot's left, vertical positive up.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache

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
_OBJECT_NAMES = (*_LANDMARK_NAMES, "B")
_OBJECTS = np.vstack([_LANDMARK_POS, np.zeros((1, 3))])
"""Landmarks and a slot for the ball."""
_LINE_ENDS = np.ascontiguousarray(FIELD_LINE_POINTS.reshape(-1, 3))
_ZERO3 = np.zeros(3)
_NOISE_SIGMA = np.array([[DISTANCE_NOISE_PERCENT], [HORIZONTAL_NOISE_DEG], [VERTICAL_NOISE_DEG]])


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


def _clip_segments(ends: np.ndarray, half_cone_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`clip_segment` for many head-frame segments ``ends`` (n, 2, 3) at once, with the
    same arithmetic per segment.

    Returns ``(inside (n,) bool, clipped ends (n, 2, 3))``; rows where ``inside`` is False are
    meaningless. ``t0`` only grows and ``t1`` only shrinks from plane to plane, so "empty after
    some plane" is "empty after all planes" and the planes can be done together.
    """
    t = float(np.tan(np.radians(min(half_cone_deg, 89.0))))
    ad = ends.copy()
    ad[:, 1] -= ad[:, 0]  # rows: start a, direction d = b - a
    # f(p) = n·p - c of the five planes of clip_segment for a (fa) and d (fd) at once; the terms
    # with coefficient 0 or ±1 are exact, so each is the two-term expression clip_segment computes
    coef_y, coef_x, coef_z, const = _planes(t)
    f = ad[:, :, 1:2] * coef_y + ad[:, :, 0:1] * coef_x + ad[:, :, 2:3] * coef_z - const
    fa = f[:, 0]
    fd = f[:, 1]
    up = fd >= 1e-12  # (fd > 0 and not parallel)
    down = fd <= -1e-12  # (fd <= 0 and not parallel)
    par = ~(up | down)
    tt = -fa / np.where(par, 1.0, fd)
    t01 = np.empty((len(ad), 2))
    # + 0.0: never -0.0 (as max() starting from 0.0)
    t01[:, 0] = np.maximum(np.where(up, tt, 0.0).max(axis=1), 0.0) + 0.0
    t01[:, 1] = np.minimum(np.where(down, tt, 1.0).min(axis=1), 1.0)
    inside = ~((par & (fa < 0)).any(axis=1) | (t01[:, 0] > t01[:, 1]))
    return inside, ad[:, 0:1] + t01[:, :, None] * ad[:, 1:2]


@cache
def _planes(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Coefficients of y, x and z and the constant (for a point and for a direction) of the
    planes ``n · p >= c`` of :func:`clip_segment`."""
    coef_y = np.array([1.0, t, t, t, t])
    coef_x = np.array([0.0, -1.0, 1.0, 0.0, 0.0])
    coef_z = np.array([0.0, 0.0, 0.0, -1.0, 1.0])
    const = np.array([[MIN_DISTANCE_M, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 0.0]])
    return coef_y, coef_x, coef_z, const


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
    observer = Observer(head_pos, head_rot, calibration, mirror)
    return see_many([observer], ball_pos=ball_pos, players=players, rng=rng, config=config)[0]


@dataclass(frozen=True)
class Observer:
    """One robot that sees: its head's centre (world, m) and rotation matrix (columns = head
    x/y/z axes in world), its calibration offset (m) and whether it plays on the right."""

    head_pos: np.ndarray
    head_rot: np.ndarray
    calibration: np.ndarray
    mirror: bool = False


def see_many(
    observers: Sequence[Observer],
    *,
    ball_pos: np.ndarray,
    players: list[tuple[str, int, np.ndarray]],
    rng: np.random.Generator,
    config: VisionConfig,
) -> list[Vision]:
    """The ``See`` percepts of several robots of one world in one cycle: the same percepts,
    noise included, as :func:`see` for each observer in turn (the noise is drawn from ``rng``
    in the same order), with the geometry of all of them computed at once."""
    half = float(int(config.view_cone_deg) // 2)
    noise = config.noise
    n_obs = len(observers)
    if not n_obs:
        return []
    n_obj = len(_OBJECTS)
    n_parts = len(PLAYER_PARTS)
    n_players = len(players)
    # every point in one array: landmarks and ball, each player's parts, line end points
    pieces = [_OBJECTS[:-1], ball_pos.reshape(1, 3)]
    pieces += [parts for _, _, parts in players]
    if config.lines:
        pieces.append(_LINE_ENDS)
    points = np.concatenate(pieces)
    n_all = len(points)
    rel = np.empty((n_obs, n_all, 3))
    for k, o in enumerate(observers):
        rel[k] = to_head_frame(points, o.head_pos, o.head_rot)
        rel[k] += o.calibration if noise else _ZERO3
    n_pts = n_obj + n_parts * n_players
    n_line_ends = n_all - n_pts
    inside = None
    if config.lines:
        inside, clipped = _clip_segments(rel[:, n_pts:].reshape(-1, 2, 3), half)
        rel[:, n_pts:] = clipped.reshape(n_obs, n_line_ends, 3)
        inside = inside.reshape(n_obs, -1)
    # one polar conversion and one visibility test for everything (element-wise operations)
    pol_all = polar(rel.reshape(-1, 3)).reshape(n_obs, n_all, 3)
    vis_all = _visible(pol_all.reshape(-1, 3), half).reshape(n_obs, n_all)
    # which players are seen (any part), and which lines (both ends inside the cone, slightly
    # widened: clipped ends lie on its border)
    pvis_all = vis_all[:, n_obj:n_pts].reshape(n_obs, n_players, n_parts)
    seen_any = pvis_all.any(axis=2)
    keep = None
    if config.lines:
        lvis = _visible(pol_all[:, n_pts:].reshape(-1, 3), half + 1e-6)
        keep = inside & lvis.reshape(n_obs, -1, 2).all(axis=2)
    # the noise of everything seen, per observer in turn, drawn at once: per observer one draw
    # per group (the objects, each seen player, the lines), the same numbers group by group
    n_seen = seen_any.sum(axis=1)
    n_lines = np.zeros(n_obs, dtype=np.intp) if keep is None else keep.sum(axis=1)
    sizes = 3 * (n_obj + n_parts * n_seen + 2 * n_lines)
    starts = np.cumsum(sizes) - sizes  # each observer's first number
    z = rng.standard_normal(int(sizes.sum())) if noise else None
    # the objects (all of them are in the draw, seen or not)
    obj = pol_all[:, :n_obj]
    if z is not None:
        obj = _add_noise(obj, z[starts[:, None] + _OBJECT_DRAW].reshape(n_obs, 3, n_obj))
    # the seen players' parts, in observer order, one group of n_parts per player
    sk, sj = np.nonzero(seen_any)
    parts = pol_all[:, n_obj:n_pts].reshape(n_obs, n_players, n_parts, 3)[sk, sj]
    first_seen = np.cumsum(n_seen) - n_seen
    if z is not None and len(sk):
        rank = np.arange(len(sk)) - np.repeat(first_seen, n_seen)
        base = starts[sk] + 3 * n_obj + 3 * n_parts * rank
        draw = z[base[:, None] + np.arange(3 * n_parts)].reshape(len(sk), 3, n_parts)
        parts = _add_noise(parts, draw)
    # the lines' end points, one group per observer (its 2 n_lines rows)
    lines = np.zeros((0, 2, 3))
    first_line = np.cumsum(n_lines) - n_lines
    if keep is not None:
        lk, ll = np.nonzero(keep)
        lines = pol_all[:, n_pts:].reshape(n_obs, -1, 2, 3)[lk, ll]
        if z is not None and len(lk):
            rank = np.arange(len(lk)) - np.repeat(first_line, n_lines)
            base = starts[lk] + 3 * n_obj + 3 * n_parts * n_seen[lk]
            rows = 2 * n_lines[lk]  # the group's rows: number c of row r is base + c rows + r
            r = 2 * rank[:, None] + np.arange(2)  # (lines, 2)
            idx = base[:, None, None] + np.arange(3)[None, :, None] * rows[:, None, None]
            draw = z[idx + r[:, None, :]]  # (lines, 3 components, 2 ends)
            lines = _add_noise(lines, draw)
    return [
        _assemble(
            o,
            obj[k],
            vis_all[k, :n_obj],
            parts[first_seen[k] : first_seen[k] + n_seen[k]],
            sj[first_seen[k] : first_seen[k] + n_seen[k]],
            pvis_all[k],
            lines[first_line[k] : first_line[k] + n_lines[k]],
            ball_pos,
            players,
            config,
        )
        for k, o in enumerate(observers)
    ]


_OBJECT_DRAW = np.arange(3 * len(_OBJECTS))


def _add_noise(pol: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``pol`` (..., n, 3) with SimSpark's noise from the standard normal numbers ``z``
    (..., 3, n): per point, distance + σ_d z₀ × distance / 100, horizontal + σ_h z₁, vertical
    + σ_v z₂, each ``0.0 + sigma * z`` as numpy computes ``normal(0.0, sigma)``."""
    zz = z * _NOISE_SIGMA
    zz += 0.0
    out = pol.copy()
    out[..., 0] += zz[..., 0, :] * out[..., 0] / 100.0
    out[..., 1] += zz[..., 1, :]
    out[..., 2] += zz[..., 2, :]
    return out


def _assemble(
    o: Observer,
    objects_pol: np.ndarray,
    objects_seen: np.ndarray,
    parts_pol: np.ndarray,
    seen: np.ndarray,
    pvis_all: np.ndarray,
    lines: np.ndarray,
    ball_pos: np.ndarray,
    players: list[tuple[str, int, np.ndarray]],
    config: VisionConfig,
) -> Vision:
    """One observer's percept from its share of :func:`see_many`'s arrays (noise applied)."""
    names = _OBJECT_NAMES
    objects = {names[i]: objects_pol[i] for i in np.flatnonzero(objects_seen)}
    seen_players: list[SeenPlayer] = []
    for j, pol, shown in zip(seen.tolist(), parts_pol, pvis_all[seen].tolist(), strict=True):
        team, unum, _ = players[j]
        visible = {name: pol[i] for i, name in enumerate(PLAYER_PARTS) if shown[i]}
        seen_players.append(SeenPlayer(team, unum, visible))
    vision = Vision(objects=objects, players=seen_players, lines=lines)
    if config.ground_truth:
        head_pos, head_rot, mirror = o.head_pos, o.head_rot, o.mirror
        s = -1.0 if mirror else 1.0
        vision.my_pos = head_pos * np.array([s, s, 1.0])
        fwd = head_rot[:, 1]
        heading = float(np.degrees(np.arctan2(fwd[1], fwd[0])))
        if mirror:
            heading = (heading + 360.0) % 360.0 - 180.0
        vision.my_orientation_deg = heading
        vision.ball_pos = ball_pos * np.array([s, s, 1.0])
    return vision

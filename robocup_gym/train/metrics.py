"""Per-episode kick metrics from the environments' ``info`` and their summaries.

The kick tasks report, in the ``info`` of an episode's last step, how far the ball went (x
displacement along the field, total distance) and whether the robot fell. This module reads them
under the names the tasks use (with a few aliases so that stock environments simply report
nothing), and summarises a list of episodes into the numbers the CLI prints and saves.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

BALL_DX_KEYS = ("ball_dx", "ball_displacement_x", "ball_x_displacement")
"""Ball displacement along the field's x axis (towards the opponent goal), m. The tasks report it
as the first element of ``info["ball_displacement"]`` (x, y, z)."""
BALL_DISPLACEMENT_KEY = "ball_displacement"
BALL_DIST_KEYS = ("ball_distance", "ball_total_distance")
"""Straight-line distance from the ball's start to where it came to rest, m."""
FALL_KEYS = ("fallen", "has_fallen", "fell", "robot_fallen")
"""Whether the robot fell during the episode."""

TASK_MEASURES: dict[str, str] = {
    "forward_speed_mps": "forward speed (m/s)",
    "forward_error_mps": "forward tracking error (m/s)",
    "distance_error": "kick distance error (fraction)",
    "direction_error_deg": "kick direction error (deg)",
    "ball_speed_to_target_mps": "ball speed toward the target (m/s)",
    "losses": "ball losses per episode",
}
"""The tasks' own measures in the ``info`` of an episode's last step (Walk's speed and tracking
error, TargetKick's errors, Dribble's progress and losses), with their labels: a summary has
each one's mean as ``<key>_mean``."""

_SKIP = {
    "episode",
    "terminal_observation",
    "TimeLimit.truncated",
    "final_observation",
    "final_info",
    "_final_observation",
    "_final_info",
}


def _first(info: Mapping[str, Any], keys: Sequence[str]) -> float | None:
    for k in keys:
        if k in info:
            v = info[k]
            if isinstance(v, np.ndarray):
                if v.size != 1:
                    continue
                v = v.item()
            try:
                return float(v)
            except (TypeError, ValueError):
                continue
    return None


def scalar_infos(info: Mapping[str, Any]) -> dict[str, float]:
    """All scalar numeric entries of one ``info`` dict (bools as 0/1)."""
    out: dict[str, float] = {}
    for k, v in info.items():
        if k in _SKIP or k.startswith("_"):
            continue
        if isinstance(v, np.ndarray):
            if v.size != 1:
                continue
            v = v.item()
        if isinstance(v, bool | int | float | np.number | np.bool_):
            f = float(v)
            if math.isfinite(f):
                out[k] = f
    return out


def episode_record(info: Mapping[str, Any], ep_return: float, ep_length: int) -> dict[str, float]:
    """One episode's metrics from the ``info`` of its last step."""
    rec = {"return": float(ep_return), "length": float(ep_length)}
    dx = _first(info, BALL_DX_KEYS)
    disp = info.get(BALL_DISPLACEMENT_KEY)
    if dx is None and disp is not None and np.ndim(disp) == 1 and len(disp) >= 1:
        dx = float(disp[0])
    dist = _first(info, BALL_DIST_KEYS)
    fell = _first(info, FALL_KEYS)
    if dx is not None:
        rec["ball_dx"] = dx
    if dist is not None:
        rec["ball_distance"] = dist
    if fell is not None:
        rec["fell"] = 1.0 if fell else 0.0
    diverged = _first(info, ("diverged",))
    if diverged is not None:
        rec["diverged"] = 1.0 if diverged else 0.0
    success = _first(info, ("success",))  # GetUp
    if success is not None:
        rec["success"] = 1.0 if success else 0.0
    assist = _first(info, ("assist_share",))  # a training run's TorsoAssist
    if assist is not None:
        rec["assist_share"] = float(assist)
    for key in TASK_MEASURES:
        v = _first(info, (key,))
        if v is not None:
            rec[key] = float(v)
    return rec


def mean_ci95(values: Sequence[float]) -> list[float] | None:
    """The 95 % interval of the mean of ``values`` (normal approximation: mean ± 1.96 standard
    errors), rounded to 3 decimals; ``None`` for fewer than two values."""
    v = np.asarray(values, dtype=float)
    if len(v) < 2:
        return None
    half = 1.96 * float(v.std(ddof=1)) / math.sqrt(len(v))
    return [round(float(v.mean()) - half, 3), round(float(v.mean()) + half, 3)]


def summarize(records: Iterable[Mapping[str, float]]) -> dict[str, float | int | None]:
    """Mean/std summary of episode records (keys absent from all episodes are ``None``)."""
    records = list(records)

    def stats(key: str) -> tuple[float | None, float | None]:
        vals = [r[key] for r in records if key in r]
        if not vals:
            return None, None
        return float(np.mean(vals)), float(np.std(vals))

    dx_mean, dx_std = stats("ball_dx")
    dist_mean, dist_std = stats("ball_distance")
    ret_mean, ret_std = stats("return")
    len_mean, _ = stats("length")
    fall, _ = stats("fell")
    diverged, _ = stats("diverged")
    dx_vals = [r["ball_dx"] for r in records if "ball_dx" in r]
    return {
        "episodes": len(records),
        "ball_dx_mean": dx_mean,
        "ball_dx_std": dx_std,
        "ball_dx_max": float(np.max(dx_vals)) if dx_vals else None,
        "ball_distance_mean": dist_mean,
        "ball_distance_std": dist_std,
        "fall_rate": fall,
        "diverged_rate": diverged,
        "return_mean": ret_mean,
        "return_std": ret_std,
        "length_mean": len_mean,
        "success_rate": stats("success")[0],
        **{f"{key}_mean": stats(key)[0] for key in TASK_MEASURES},
        "assist_share_mean": stats("assist_share")[0],
    }

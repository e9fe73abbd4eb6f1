"""Shared data for the protocol tests (the real-server captures in tests/data/rcssserver3d)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robocup_gym.types import Perception

DATA = Path(__file__).resolve().parents[1] / "data" / "rcssserver3d"


def _lines(name: str) -> list[str]:
    text = (DATA / name).read_text(encoding="latin-1")
    return [line for line in text.split("\n") if line]


PERCEPTS: list[str] = _lines("perceptor_messages.txt")
"""20 raw percepts of the SPL fork (3 decimals, extra GS fields k/ti)."""
MONITOR: list[str] = _lines("monitor_messages.txt")
"""6 raw monitor frames: header-only full, full after scene, full after init, 3 deltas."""
UPSTREAM: str = _lines("upstream_percept_example.txt")[0]
"""The upstream rcssserver3d 0.7.3 percept of wire reference §5.13 (2 decimals)."""


def assert_same_perception(a: Perception, b: Perception) -> None:
    """Field-by-field equality (NaN equal to NaN, -0.0 equal to 0.0)."""
    assert a.time == b.time
    assert a.game == b.game
    np.testing.assert_array_equal(a.gyro, b.gyro)
    np.testing.assert_array_equal(a.accel, b.accel)
    assert a.joint_names == b.joint_names
    np.testing.assert_array_equal(a.joint_angles_deg, b.joint_angles_deg)
    assert a.force_sensors.keys() == b.force_sensors.keys()
    for k in a.force_sensors:
        np.testing.assert_array_equal(a.force_sensors[k].point, b.force_sensors[k].point)
        np.testing.assert_array_equal(a.force_sensors[k].force, b.force_sensors[k].force)
    assert a.heard == b.heard
    assert (a.vision is None) == (b.vision is None)
    if a.vision is not None and b.vision is not None:
        va, vb = a.vision, b.vision
        assert list(va.objects) == list(vb.objects)
        for k in va.objects:
            np.testing.assert_array_equal(va.objects[k], vb.objects[k])
        assert [(p.team, p.unum, list(p.parts)) for p in va.players] == [
            (p.team, p.unum, list(p.parts)) for p in vb.players
        ]
        for pa, pb in zip(va.players, vb.players, strict=True):
            for k in pa.parts:
                np.testing.assert_array_equal(pa.parts[k], pb.parts[k])
        np.testing.assert_array_equal(va.lines, vb.lines)
        assert va.lines.shape == vb.lines.shape
        for name in ("my_pos", "ball_pos"):
            x, y = getattr(va, name), getattr(vb, name)
            assert (x is None) == (y is None)
            if x is not None:
                np.testing.assert_array_equal(x, y)
        assert va.my_orientation_deg == vb.my_orientation_deg

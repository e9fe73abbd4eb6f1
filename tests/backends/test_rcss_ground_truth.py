"""Ground truth from the monitor stream: the backend's fast delta scanner against the general
scene-graph parser, on the real server's recorded frames and on a live stream."""

from __future__ import annotations

import numpy as np
import pytest

from robocup_gym.backends.rcssserver3d_monitor import MonitorTracker, _VelocityTrack
from robocup_gym.protocol.monitor import MonitorState
from robocup_gym.server.client import AgentClient, MonitorClient
from robocup_gym.sim.rotations import matrix_to_quat

from .conftest import HOST
from .mock_rcss import fixture_lines


def _reference(state: MonitorState, side: str, unum: int):
    """Ball position and torso transform by the general parser (whole scene graph)."""
    scene = state.scene
    ball = scene.ball_position()
    top = scene.agents().get((side, unum))
    torso = None
    if top is not None:
        world = scene.world_transforms()
        for path, node, _ in scene.walk():
            if path[0] == top and node.is_mesh and "naobody" in (node.model or ""):
                torso = world[path[:-2]]
                break
    return ball, torso


def _compare(frames: list[str], side: str, unum: int) -> int:
    tracker = MonitorTracker()
    tracker.set_agent(side, unum)
    ref = MonitorState()
    compared = 0
    for f in frames:
        tracker.feed(f)
        ref.update(f)
        assert not tracker.need_full
        ball, torso = _reference(ref, side, unum)
        s = tracker.newest()
        np.testing.assert_allclose(s.ball_pos, ball, atol=1e-12)
        assert s.game_time == ref.info.time
        if torso is None:
            assert s.torso is None
        else:
            np.testing.assert_allclose(s.torso, torso, atol=1e-12)
            compared += 1
    return compared


def test_scanner_matches_the_parser_on_recorded_real_frames():
    frames = fixture_lines("monitor_messages.txt")
    assert _compare(frames, "left", 1) == 4  # the full scene after init and three deltas


def test_scanner_matches_the_parser_on_a_live_stream(make_server):
    server = make_server(monitor_interval=1)
    frames: list[str] = []
    with MonitorClient(HOST, server.monitor_port) as mon, AgentClient(HOST, server.agent_port) as a:
        a.handshake("Alpha", 0, 0)
        a.send("(syn)")
        a.recv()
        rng = np.random.default_rng(0)
        for k in range(60):
            joints = "".join(f"(he{j} {rng.uniform(-3, 3):.3f})" for j in (1, 2))
            a.send(joints + f"(rle3 {3 * np.sin(k / 5):.3f})(syn)")
            a.recv()
        a.send("(syn)")
        a.recv()
        while True:
            try:
                frames.append(mon.recv(timeout=0.5))
            except TimeoutError:
                break
    assert any("(RDS 0 1)" in f for f in frames) and any("(RSG 0 1)" in f for f in frames)
    assert _compare(frames, "left", 1) > 50


def test_a_delta_that_does_not_fit_asks_for_a_full_frame():
    frames = fixture_lines("monitor_messages.txt")
    tracker = MonitorTracker()
    tracker.set_agent("left", 1)
    for f in frames[:3]:
        tracker.feed(f)
    assert tracker.has_agent and not tracker.need_full
    broken = frames[3].replace("(nd(nd StaticMesh))", "", 1)  # one node fewer
    tracker.feed(broken)
    assert tracker.need_full and tracker.errors == 1
    n = len(tracker.snapshots)
    tracker.feed(frames[4])  # further deltas are ignored until a full frame arrives
    assert len(tracker.snapshots) == n
    tracker.feed(frames[2])
    assert not tracker.need_full and len(tracker.snapshots) == n + 1


def test_velocity_from_sparse_updates():
    v = _VelocityTrack()
    # a body at 0.1 m/s whose pose is only resent after it moved > 5 mm (every 3rd frame)
    for k in range(12):
        t = 0.02 * k
        sent = 0.1 * 0.02 * (k - k % 3)
        vel = v.update(t, np.array([sent, 0.0, 0.0]))
        if k >= 3 and k % 3 == 0:
            assert vel[0] == pytest.approx(0.1)  # exact between two updates
        if k > 3:
            assert 0.0 < vel[0] <= 0.1 + 1e-9
    # the clock set back (a reset): no bogus velocity
    assert np.all(v.update(0.0, np.array([5.0, 0.0, 0.0])) == 0.0)


def test_quaternion_from_rotation_matrix():
    rng = np.random.default_rng(1)
    for _ in range(50):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        w, x, y, z = q
        r = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )
        got = matrix_to_quat(np.round(r, 6))
        assert abs(np.dot(got, q)) == pytest.approx(1.0, abs=1e-6)

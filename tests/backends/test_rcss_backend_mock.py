"""The backend's client against a scripted server that replays the real rcssserver3d's own
messages (percepts in the SPL fork's 3-decimal format, the real monitor stream)."""

from __future__ import annotations

import math
import re
import time

import numpy as np
import pytest

from robocup_gym.backends.rcssserver3d_backend import Rcssserver3dBackend
from robocup_gym.robot.nao import nao_model
from robocup_gym.types import AgentCommand

from .mock_rcss import MockRcss


@pytest.fixture
def mock():
    m = MockRcss()
    yield m
    m.stop()
    assert not m.errors, m.errors


def _connect(mock: MockRcss, backends) -> Rcssserver3dBackend:
    return backends.add(
        Rcssserver3dBackend(
            host="127.0.0.1", agent_port=mock.agent_port, monitor_port=mock.monitor_port, timeout=5
        )
    )


def test_handshake_keeps_sending_syn_and_reads_real_messages(mock, backends):
    t = time.monotonic()
    b = _connect(mock, backends)
    assert time.monotonic() - t < 1.5, "the first percept should not wait for the 2 s stall"
    assert mock.received[0] == "(scene rsg/agent/nao/nao_hetero.rsg 0)"
    assert mock.syn_before_first_percept >= 1
    assert any(m.startswith("(init (unum 0) (teamname RobocupGym))") for m in mock.received)
    assert (b.side, b.unum) == ("left", 1)

    p = b.last_perception
    assert p.joint_names == nao_model(0).perceptor_names and len(p.joint_angles_deg) == 22
    assert p.game.play_mode == "BeforeKickOff"
    gt = p.ground_truth
    assert gt is not None
    # the recorded scene: ball on the centre spot, the robot near (-0.95, -0.02) facing ~+x
    np.testing.assert_allclose(gt.ball_pos, (0.0, 0.0, 0.0417605), atol=1e-6)
    assert gt.torso_pos[0] == pytest.approx(-0.95, abs=0.02)
    assert 0.37 < gt.torso_pos[2] < 0.41
    assert np.linalg.norm(gt.torso_quat) == pytest.approx(1.0)
    w, x, y, z = gt.torso_quat
    forward = np.array([2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)])
    assert math.degrees(math.atan2(forward[1], forward[0])) == pytest.approx(6, abs=3)


def test_steps_send_one_full_command_with_syn_per_percept(mock, backends):
    b = _connect(mock, backends)
    n_before = len(mock.received)
    times = []
    for _ in range(5):
        p = b.step(AgentCommand({"he1": 0.5, "rle3": -1.25}))
        times.append(p.time)
        assert p.ground_truth is not None
    msgs = mock.received[n_before:]
    assert len(msgs) == 5
    for m in msgs:
        assert m.endswith("(syn)") and m.count("(syn)") == 1
        assert "(he1 0.5000)" in m and "(rle3 -1.2500)" in m
    # the recorded percepts are consecutive cycles, 20 ms apart
    assert np.allclose(np.diff(times), 0.02)
    # full array commands: all 22 effectors in canonical order
    b.step(AgentCommand(np.linspace(-1, 1, 22)))
    names = re.findall(r"\(([a-z]+\d) ", mock.received[-1])
    assert tuple(names) == nao_model(0).effector_names

"""Against a real rcssserver3d: runs where one is installed (``RCSSSERVER3D`` or on ``PATH``),
reported as skipped with the reason everywhere else."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robocup_gym.backends import RobotPose
from robocup_gym.backends.process import RcssServerNotFoundError, find_binary
from robocup_gym.backends.rcssserver3d_backend import Rcssserver3dBackend
from robocup_gym.envs.config import PAPER_STANDING_POSE_DEG, resolve_angles
from robocup_gym.robot.nao import nao_model
from robocup_gym.types import AgentCommand

from .conftest import pid_alive, wait_until


@pytest.fixture
def real_binary() -> str:
    try:
        binary = find_binary()
    except RcssServerNotFoundError as exc:
        pytest.skip(f"no real rcssserver3d here: {str(exc).split('. ')[0]}")
    with open(binary, "rb") as f:
        if f.read(2) == b"#!":  # a script (e.g. the fake of the other tests), not the server
            pytest.skip(f"{binary} is a script, not a real rcssserver3d")
    return binary


def test_real_server_launch_reset_step_close(real_binary):
    b = Rcssserver3dBackend(binary=real_binary, startup_timeout=60, timeout=20)
    try:
        model = nao_model(0)
        # all joints at 0: the real robot stands with its torso centre at 0.383 m (fixture)
        p = b.reset_episode(RobotPose(-1.0, 0.0), ball_pos=(-0.8, -0.055, 0.042))
        assert b.last_reset.converged, b.last_reset
        gt = p.ground_truth
        assert gt is not None
        np.testing.assert_allclose(gt.torso_pos, (-1.0, 0.0, 0.383), atol=0.02)
        np.testing.assert_allclose(gt.ball_pos, (-0.8, -0.055, 0.042), atol=0.01)
        assert p.game.play_mode == "PlayOn"
        # the paper's crouch, twice (the second from the first: few joint cycles)
        start = resolve_angles(model, PAPER_STANDING_POSE_DEG, "pose")
        for _ in range(2):
            p = b.reset_episode(
                RobotPose(-1.0, 0.0, joint_angles_deg=start), ball_pos=(-0.8, -0.055, 0.042)
            )
            assert b.last_reset.converged, b.last_reset
            np.testing.assert_allclose(p.joint_angles_deg, start, atol=1.5)
        times, laj1 = [p.time], [p.joint("laj1")]
        for k in range(20):
            p = b.step(AgentCommand({"lae1": 2.0 if k < 5 else 0.0}))
            times.append(p.time)
            laj1.append(p.joint("laj1"))
            assert p.ground_truth is not None
        assert np.allclose(np.diff(times), 0.02, atol=1e-6)
        assert laj1[-1] - laj1[0] == pytest.approx(math.degrees(0.2), abs=2.0)
        assert p.ground_truth.torso_pos[2] > 0.3  # still standing
        pid = b.server.pid
    finally:
        b.close()
    wait_until(lambda: not pid_alive(pid), timeout=15, what="rcssserver3d exit")

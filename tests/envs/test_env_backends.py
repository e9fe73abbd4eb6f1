"""The backend seam: registry by name, and the MuJoCo backend's reset/step/advance contract."""

from __future__ import annotations

import numpy as np
import pytest

from robocup_gym.backends import _REGISTRY as REGISTRY
from robocup_gym.backends import (
    Backend,
    BackendDivergedError,
    BackendNotAvailableError,
    RobotPose,
    available_backends,
    make_backend,
    register_backend,
)
from robocup_gym.backends.in_process import MujocoBackend
from robocup_gym.envs import BaseEnv
from robocup_gym.types import AgentCommand, Perception


def test_registry_builds_by_name_and_accepts_new_entries():
    assert "mujoco" in available_backends()
    b = make_backend("mujoco", robot_type=2)
    assert isinstance(b, MujocoBackend) and b.robot_type == 2
    assert b.robot_model.robot_type.index == 2

    register_backend("test-fake", lambda **kw: MujocoBackend(**kw))
    try:
        assert isinstance(make_backend("test-fake", robot_type=0), MujocoBackend)
    finally:
        REGISTRY.pop("test-fake")
    with pytest.raises(BackendNotAvailableError, match="test-fake"):
        make_backend("test-fake")


def test_an_option_a_backend_does_not_take_is_named_with_the_ones_it_takes():
    with pytest.raises(TypeError, match=r"unknown option\(s\) 'vison' for the 'ode' backend; "):
        make_backend("ode", robot_type=0, vison=True)
    with pytest.raises(TypeError, match=r"'ode' backend; options: robot_type, seed, vision"):
        BaseEnv(backend="ode", backend_options={"vison": True})


@pytest.mark.parametrize("port", ["3100", 0, 70000, 3100.0])
def test_a_server_port_that_is_not_one_is_named(port):
    from robocup_gym.backends.rcssserver3d_backend import Rcssserver3dBackend

    with pytest.raises(ValueError, match=f"agent_port must be a port number 1-65535, got {port!r}"):
        Rcssserver3dBackend(host="127.0.0.1", agent_port=port, monitor_port=3200)


def test_planned_backend_error_names_it(monkeypatch, tmp_path):
    monkeypatch.delenv("RCSSSERVER3D", raising=False)  # (a machine with a real server)
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(BackendNotAvailableError) as e:
        make_backend("rcssserver3d")
    assert "rcssserver3d" in str(e.value) and "mujoco" in str(e.value)


def test_mujoco_backend_reset_places_everything_instantly():
    b = MujocoBackend(robot_type=0)
    t_before = b.world.time
    angles = np.zeros(len(b.robot_model.joints))
    angles[b.robot_model.effector_names.index("lae1")] = -40.0
    p = b.reset_episode(
        RobotPose(x=2.0, y=-1.0, heading_deg=90.0, joint_angles_deg=angles),
        ball_pos=(2.3, -1.0, 0.041),
        ball_vel=(0.5, 0.0, 0.0),
    )
    assert isinstance(p, Perception)
    assert b.world.time == t_before  # no simulated warm-up cycles
    gt = p.ground_truth
    np.testing.assert_allclose(gt.torso_pos[:2], (2.0, -1.0), atol=1e-9)
    np.testing.assert_allclose(gt.ball_pos, (2.3, -1.0, 0.041), atol=1e-9)
    np.testing.assert_allclose(gt.ball_vel, (0.5, 0.0, 0.0), atol=1e-9)
    assert p.joint("laj1") == pytest.approx(-40.0)
    assert p.game.play_mode == "PlayOn" and p.game.game_time == 0.0


def test_mujoco_backend_step_and_advance_count_cycles():
    b = MujocoBackend()
    b.reset_episode(RobotPose(-1.0, 0.0), ball_pos=(-0.8, -0.055, 0.041))
    t0 = b.world.time
    p = b.step(AgentCommand({"lae1": 2.0}))
    assert p.time == pytest.approx(t0 + 0.02)
    p = b.advance(10, AgentCommand(np.zeros(len(b.robot_model.joints))))
    assert p.time == pytest.approx(t0 + 0.22)
    with pytest.raises(ValueError):
        b.advance(0)


def test_divergence_is_reported_and_reset_recovers():
    b = MujocoBackend()
    b.reset_episode(RobotPose(-1.0, 0.0), ball_pos=(-0.8, -0.055, 0.041))
    b.world.data.qvel[0] = np.nan  # blow the physics up
    with pytest.raises(BackendDivergedError):
        b.step(AgentCommand())
    p = b.reset_episode(RobotPose(-1.0, 0.0), ball_pos=(-0.8, -0.055, 0.041))
    assert np.isfinite(b.world.data.qvel).all()
    assert np.isfinite(b.step(AgentCommand()).joint_angles_deg).all()
    assert p.ground_truth.torso_pos[0] == pytest.approx(-1.0)


class _FlakyBackend(MujocoBackend):
    """Diverges on the n-th step (to test the environment's handling)."""

    fail_at = 3

    def __init__(self, **kw):
        super().__init__(**kw)
        self.steps = 0

    def step(self, command):
        self.steps += 1
        if self.steps == self.fail_at:
            raise BackendDivergedError("simulated blow-up")
        return super().step(command)


def test_env_uses_an_injected_backend_and_survives_divergence():
    backend = _FlakyBackend()
    assert isinstance(backend, Backend)
    env = BaseEnv(backend=backend, max_episode_steps=10)
    env.reset(seed=0)
    a = np.zeros(env.action_space.shape, dtype=np.float32)
    env.step(a)
    env.step(a)
    with pytest.warns(RuntimeWarning, match="diverged"):
        obs, reward, terminated, truncated, info = env.step(a)
    assert info["diverged"] is True and reward == 0.0
    assert truncated and not terminated
    assert env.observation_space.contains(obs)
    assert env.diverged_episodes == 1
    env.reset()
    _, _, _, _, info = env.step(a)
    assert info["diverged"] is False


def test_injected_backend_must_match_robot_type():
    with pytest.raises(ValueError, match="robot_type"):
        BaseEnv(backend=MujocoBackend(robot_type=1), robot_type=0)


def test_rgb_array_rendering_in_a_subprocess():
    """render_mode="rgb_array" draws the scene (needs EGL; skipped where there is no GL)."""
    import os
    import subprocess
    import sys

    code = (
        "import numpy as np\n"
        "from robocup_gym.envs import VelocityKick\n"
        "env = VelocityKick(render_mode='rgb_array', render_size=(64, 48))\n"
        "env.reset(seed=0)\n"
        "img = env.render()\n"
        "assert img.shape == (48, 64, 3) and img.dtype == np.uint8, (img.shape, img.dtype)\n"
        "assert img.std() > 1.0  # not a blank image\n"
        "env.close()\n"
        "print('RENDER-OK')\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "MUJOCO_GL": "egl"},
    )
    if proc.returncode != 0 and ("OpenGL" in proc.stderr or "EGL" in proc.stderr):
        pytest.skip("no OpenGL/EGL on this machine")
    assert "RENDER-OK" in proc.stdout, proc.stderr[-2000:]

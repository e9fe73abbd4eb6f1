"""The training assist (:mod:`robocup_gym.envs.assist`): an upward push on the torso that fades
out, only where it is asked for."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import robocup_gym.envs  # noqa: F401 (registers the tasks)
from robocup_gym.backends.base import Backend, BackendNotAvailableError
from robocup_gym.envs.assist import TorsoAssist, assist_share
from robocup_gym.sim.engines.ode import available

ENGINES = [
    "mujoco",
    pytest.param("ode", marks=pytest.mark.skipif(not available(), reason="no libode")),
]


def test_the_push_falls_linearly_to_zero():
    assert assist_share(0.8, 100, 0) == pytest.approx(0.8)
    assert assist_share(0.8, 100, 25) == pytest.approx(0.6)
    assert assist_share(0.8, 100, 100) == 0.0
    assert assist_share(0.8, 100, 1000) == 0.0
    assert assist_share(0.8, 0, 0) == 0.0


def _torso_heights(env, steps: int) -> list[float]:
    """Torso heights over ``steps`` steps of a zero action (velocity mode: every joint held)."""
    env.reset(seed=0, options={"start_side": "back"})
    zero = np.zeros(env.action_space.shape)
    out = []
    for _ in range(steps):
        env.step(zero)
        out.append(float(env.unwrapped.ground_truth.torso_pos[2]))
    return out


@pytest.mark.parametrize("engine", ENGINES)
def test_a_strong_push_lifts_a_lying_robot_and_a_faded_one_does_not(engine):
    plain = gym.make("RobocupGym/GetUp-v0", backend=engine, action_mode="velocity")
    pushed = TorsoAssist(
        gym.make("RobocupGym/GetUp-v0", backend=engine, action_mode="velocity"), 1.5, 10_000
    )
    faded = TorsoAssist(
        gym.make("RobocupGym/GetUp-v0", backend=engine, action_mode="velocity"),
        1.5,
        10,
        start_step=10,
    )
    try:
        lying = _torso_heights(plain, 30)
        assert max(lying) - min(lying) < 0.01  # holds still, lying
        assert max(_torso_heights(pushed, 30)) > lying[0] + 0.3
        assert _torso_heights(faded, 30) == pytest.approx(lying, abs=1e-9)
    finally:
        for e in (plain, pushed, faded):
            e.close()


def test_the_push_is_reported_and_its_schedule_continues_across_episodes():
    env = TorsoAssist(gym.make("RobocupGym/GetUp-v0", backend="mujoco"), 0.5, 8, start_step=2)
    try:
        weight = env.unwrapped.robot_model.total_mass * 9.81
        assert env.weight_n == pytest.approx(weight)
        env.reset(seed=1)
        forces = []
        for k in range(10):
            if k == 3:
                env.reset(seed=2)  # a new episode does not restart the schedule
            forces.append(env.step(env.action_space.sample())[4]["assist_force_n"])
        expected = [0.5 * max(0.0, 1 - (2 + k) / 8) * weight for k in range(10)]
        assert forces == pytest.approx(expected)
        assert forces[-1] == 0.0 and forces[0] > forces[1] > 0.0
    finally:
        env.close()


def test_bad_settings_and_backends_that_cannot_push_are_refused():
    env = gym.make("RobocupGym/GetUp-v0", backend="mujoco")
    try:
        for share in (-0.1, 2.5, float("nan")):
            with pytest.raises(ValueError, match="assist share"):
                TorsoAssist(env, share, 10)
        with pytest.raises(ValueError, match="decay_steps"):
            TorsoAssist(env, 0.5, -1)
    finally:
        env.close()

    class Remote(Backend):  # a backend without an in-process world (a real server)
        name = "remote"
        robot_model = None

        def _place(self, start):
            raise NotImplementedError

        def step(self, command):
            raise NotImplementedError

    with pytest.raises(BackendNotAvailableError, match="'remote' backend cannot push"):
        Remote().set_torso_force((0.0, 0.0, 10.0))


@pytest.mark.parametrize("engine", ENGINES)
def test_a_tilt_limited_push_leaves_a_lying_robot_alone(engine):
    """``max_tilt_deg``: no push while the torso lies flat (the robot must sit up first)."""
    plain = gym.make("RobocupGym/GetUp-v0", backend=engine, action_mode="velocity")
    gated = TorsoAssist(
        gym.make("RobocupGym/GetUp-v0", backend=engine, action_mode="velocity"),
        1.5,
        10_000,
        0,
        60.0,
    )
    try:
        assert _torso_heights(gated, 20) == pytest.approx(_torso_heights(plain, 20), abs=1e-9)
        gated.reset(seed=0, options={"start_side": "back"})
        assert gated.step(np.zeros(gated.action_space.shape))[4]["assist_force_n"] == 0.0
        with pytest.raises(ValueError, match="max_tilt_deg"):
            TorsoAssist(plain, 0.5, 10, 0, 0.0)
    finally:
        plain.close()
        gated.close()


def test_the_success_schedule_lowers_the_push_with_each_success():
    """``schedule="success"``: −2 % of the start push per successful episode, +0.5 % per
    failed one, never above the start; reported in ``info["assist_share"]``."""
    from robocup_gym.envs.assist import FAILURE_STEP_UP, SUCCESS_STEP_DOWN

    env = TorsoAssist(
        gym.make(
            "RobocupGym/GetUp-v0", backend="mujoco", max_episode_steps=3, action_mode="velocity"
        ),
        0.5,
        0,
        schedule="success",
    )
    try:
        base = env.unwrapped
        env.reset(seed=0)
        zero = np.zeros(env.action_space.shape)
        info = {}
        for _ in range(3):  # a failed episode at the start push: stays there
            info = env.step(zero)[4]
        assert info["success"] is False and info["assist_share"] == pytest.approx(0.5)
        env.reset(seed=1)
        base.success = True  # as if up for a second: this step ends the episode as a success
        _, _, terminated, _, info = env.step(zero)
        assert terminated and info["success"] is True
        assert info["assist_share"] == pytest.approx(0.5 * (1 - SUCCESS_STEP_DOWN))
        env.reset(seed=2)
        for _ in range(3):
            info = env.step(zero)[4]
        assert info["assist_share"] == pytest.approx(
            0.5 * (1 - SUCCESS_STEP_DOWN + FAILURE_STEP_UP)
        )
        assert info["assist_force_n"] == pytest.approx(0.5 * (1 - SUCCESS_STEP_DOWN) * env.weight_n)
        with pytest.raises(ValueError, match="assist schedule"):
            TorsoAssist(env.env, 0.5, 10, schedule="cosine")
    finally:
        env.close()

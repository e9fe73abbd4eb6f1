"""The environments on either physics engine: SimSpark's step on ODE by default, MuJoCo on
request, chosen by one argument; never a silent switch."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import robocup_gym.envs  # noqa: F401 (registers the tasks)
from robocup_gym.backends import DEFAULT_ENGINE, BackendNotAvailableError
from robocup_gym.sim.engines.ode import available
from robocup_gym.sim.engines.ode import lib as ode_lib

needs_ode = pytest.mark.skipif(not available(), reason="no libode here (apt-get install libode8)")


@needs_ode
def test_the_default_engine_is_simsparks_physics_on_ode():
    assert DEFAULT_ENGINE == "ode"
    env = gym.make("RobocupGym/VelocityKick-v0")
    assert env.unwrapped.backend.name == "ode"
    env.close()


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"engine": "mujoco"}, "mujoco"),
        ({"backend": "mujoco"}, "mujoco"),
        pytest.param({"engine": "ode"}, "ode", marks=needs_ode),
        pytest.param({"backend": "ode", "engine": "ode"}, "ode", marks=needs_ode),
    ],
)
def test_one_argument_chooses_the_engine(kwargs, name):
    env = gym.make("RobocupGym/SimpleKick-v0", **kwargs)
    assert env.unwrapped.backend.name == name
    env.close()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"engine": "bullet"}, r"unknown engine 'bullet'; engines: 'ode', 'mujoco'"),
        ({"engine": "rcssserver3d"}, r"unknown engine 'rcssserver3d'"),
        ({"backend": "mujoco", "engine": "ode"}, r"backend='mujoco' and engine='ode' disagree"),
    ],
)
def test_a_bad_engine_choice_is_a_clear_error(kwargs, match):
    with pytest.raises(BackendNotAvailableError, match=match):
        gym.make("RobocupGym/VelocityKick-v0", **kwargs)


def test_without_libode_the_default_says_how_to_install_it_and_never_switches(
    monkeypatch, tmp_path
):
    monkeypatch.setenv("ROBOCUP_GYM_LIBODE", str(tmp_path / "libode.so"))
    ode_lib.load.cache_clear()
    try:
        with pytest.raises(BackendNotAvailableError) as err:
            gym.make("RobocupGym/VelocityKick-v0")
        text = str(err.value)
        assert "apt-get install libode8" in text and "engine='mujoco'" in text
        env = gym.make("RobocupGym/VelocityKick-v0", engine="mujoco")  # the other engine works
        env.close()
    finally:
        ode_lib.load.cache_clear()


@pytest.mark.parametrize("engine", ["mujoco", pytest.param("ode", marks=needs_ode)])
@pytest.mark.parametrize("task", ["RobocupGym/VelocityKick-v0", "RobocupGym/SimpleKick-v0"])
def test_check_env_passes_on_every_engine(engine, task):
    env = gym.make(task, engine=engine)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


@needs_ode
def test_the_engines_start_an_episode_alike():
    """Same start state, same first observation (to the precision of the contact solvers:
    the feet's forces), and vision works on both."""
    obs = {}
    for engine in ("mujoco", "ode"):
        env = gym.make(
            "RobocupGym/VelocityKick-v0",
            engine=engine,
            observations=("joint_pos", "ball_rel", "foot_force", "accel", "ball_vision"),
        )
        obs[engine], _ = env.reset(seed=4)
        env.close()
    np.testing.assert_allclose(obs["mujoco"], obs["ode"], atol=0.05)

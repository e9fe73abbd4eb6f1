"""The policies shipped in ``robocup_gym/data/policies``: they load, describe themselves, and do
what their names say in-process on the default engine."""

from __future__ import annotations

import pytest

pytest.importorskip("onnxruntime")

from robocup_gym.sim.engines.ode import available
from robocup_gym.train.pretrained import (
    describe,
    pretrained_names,
    pretrained_policy,
)
from robocup_gym.train.tasks import make_env

GETUPS = {"get-up-front": "front", "get-up-back": "back"}


def test_the_get_ups_are_shipped_and_describe_themselves():
    assert set(GETUPS) <= set(pretrained_names())
    for name, side in GETUPS.items():
        meta = describe(name)
        assert meta["env_id"] == "RobocupGym/GetUp-v0" and meta["backend"] == "ode"
        assert meta["env_kwargs"]["start_side"] == side
        assert meta["env_config"]["mirror_actions"] is True
        assert meta["verification"]["max_abs_diff"] <= 1e-5
        assert len(meta["action_labels"]) == 10 and meta["training"]["n_envs"] == 16


@pytest.mark.skipif(not available(), reason="no libode")
@pytest.mark.parametrize("name", sorted(GETUPS))
def test_each_get_up_lifts_the_robot_within_80_cycles(name):
    """From its side's lying pose (the plain drop, the one it was trained on), on ODE."""
    policy = pretrained_policy(name)
    meta = policy.metadata
    env = make_env(meta["env_id"], backend="ode", env_kwargs=meta["env_kwargs"])
    try:
        obs, _ = env.reset(seed=0)
        start_z = env.unwrapped.torso_pos[2]
        done, info = False, {}
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs))
            done = terminated or truncated
        assert info["start_side"] == GETUPS[name]
        assert info["success"] and info["steps_to_up"] <= 80
        assert env.unwrapped.torso_pos[2] > max(0.28, start_z + 0.1)  # up, and held up
    finally:
        env.close()

"""Names that moved between modules stay importable from where users found them."""

import importlib

import pytest

MOVED = [
    ("robocup_gym.train.export", "OnnxPolicy", "robocup_gym.train.onnx_policy"),
    ("robocup_gym.train.export", "read_metadata", "robocup_gym.train.onnx_policy"),
    ("robocup_gym.train.evaluate", "run_episodes", "robocup_gym.train.episodes"),
    ("robocup_gym.train.run", "algo_class", "robocup_gym.train.algos"),
    ("robocup_gym.train.tasks", "validate_algo_kwargs", "robocup_gym.train.algos"),
    ("robocup_gym.sim.pose", "resting_torso_height", "robocup_gym.sim.kinematics"),
    ("robocup_gym.backends.ode_backend", "OdeBackend", "robocup_gym.backends.in_process"),
    ("robocup_gym.backends.mujoco_backend", "MujocoBackend", "robocup_gym.backends.in_process"),
]


@pytest.mark.parametrize(("old", "name", "new"), MOVED)
def test_a_moved_name_is_the_same_object_at_its_old_path(old, name, new):
    assert getattr(importlib.import_module(old), name) is getattr(
        importlib.import_module(new), name
    )

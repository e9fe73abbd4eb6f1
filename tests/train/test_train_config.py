"""TrainConfig: paper defaults, YAML files, overrides; task names."""

from __future__ import annotations

from math import inf

import pytest

from robocup_gym.train.config import TrainConfig, algo_defaults, load_yaml
from robocup_gym.train.tasks import kebab, registered_tasks, resolve_task, task_name


def test_ppo_defaults_are_the_papers():
    hp = TrainConfig().resolved_algo_kwargs()
    assert hp["gamma"] == 0.99
    assert hp["gae_lambda"] == 0.95
    assert hp["n_steps"] == 64
    assert hp["n_epochs"] == 10
    assert hp["clip_range"] == 0.2
    assert hp["learning_rate"] == 1e-4
    assert hp["ent_coef"] == 0.0
    assert TrainConfig().normalize_obs is False  # observation clipping happens in the env
    # not a hyperparameter of the paper: updates overlap the next rollout, switchable
    assert hp["overlap_updates"] is True
    off = TrainConfig(algo_kwargs={"overlap_updates": False}).resolved_algo_kwargs()
    assert off["overlap_updates"] is False and off["n_steps"] == 64


def test_a_task_can_need_other_hyperparameters_than_the_papers():
    """Walk's reference policy was trained with small plain Gaussian noise: ``train walk`` gets
    those settings over the paper's, the run's own ``algo_kwargs`` over them, and the config
    file records the merge; other tasks and algorithms keep the paper's."""
    walk = TrainConfig(task="walk").resolved_algo_kwargs()
    assert walk["use_sde"] is False and walk["learning_rate"] == 3e-4
    assert walk["batch_size"] == 256 and walk["n_steps"] == 64  # the rest is the paper's
    assert walk["policy_kwargs"]["log_std_init"] == -2.0
    assert walk["policy_kwargs"]["net_arch"] == [256, 256]
    by_id = TrainConfig(task="RobocupGym/Walk-v0").resolved_algo_kwargs()
    assert by_id == walk
    mine = TrainConfig(
        task="walk", algo_kwargs={"use_sde": True, "policy_kwargs": {"log_std_init": -1.0}}
    ).resolved_algo_kwargs()
    assert mine["use_sde"] is True and mine["policy_kwargs"]["log_std_init"] == -1.0
    assert mine["batch_size"] == 256 and mine["policy_kwargs"]["net_arch"] == [256, 256]
    assert TrainConfig(task="velocity-kick").resolved_algo_kwargs()["use_sde"] is True
    for kick in ("target-kick", "long-kick"):  # a residual over the reference kick
        hp = TrainConfig(task=kick).resolved_algo_kwargs()
        assert hp["use_sde"] is False and hp["policy_kwargs"]["log_std_init"] == -2.0
        assert (hp["n_steps"], hp["learning_rate"], hp["batch_size"]) == (256, 1e-4, 256)
    assert TrainConfig(task="walk", algo="sac").resolved_algo_kwargs() == {}
    assert TrainConfig(task="no-such-task").resolved_algo_kwargs()["use_sde"] is True


def test_sac_defaults_are_sb3s():
    assert algo_defaults("sac") == {}
    assert TrainConfig(algo="sac").resolved_algo_kwargs() == {}


def test_yaml_round_trip_and_merge(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text(
        "algo: ppo\nn_envs: 4\nalgo_kwargs: {learning_rate: 3.0e-4, "
        "policy_kwargs: {net_arch: [8]}}\nenv_kwargs: {wait_steps: 5}\n"
    )
    cfg = TrainConfig.load(path)
    hp = cfg.resolved_algo_kwargs()
    assert hp["learning_rate"] == 3e-4 and hp["n_steps"] == 64
    assert hp["policy_kwargs"]["net_arch"] == [8]
    assert cfg.env_kwargs == {"wait_steps": 5}
    cfg.save(tmp_path / "saved.yaml")
    again = TrainConfig.load(tmp_path / "saved.yaml")
    assert again.resolved_algo_kwargs() == hp
    assert cfg.merged(n_envs=None, seed=7).n_envs == 4


def test_numbers_in_exponent_notation_are_numbers(tmp_path):
    # PyYAML reads `3e-4` (no dot) as a string; SB3 then refuses it as a learning rate
    path = tmp_path / "c.yaml"
    path.write_text("algo_kwargs: {learning_rate: 3e-4, n_steps: 2e2}\n")
    hp = TrainConfig.load(path).resolved_algo_kwargs()
    assert hp["learning_rate"] == 3e-4 and isinstance(hp["learning_rate"], float)
    assert hp["n_steps"] == 200.0
    assert load_yaml("[1E+3, -.5, 7, 0x10, 1e-4x, .inf]") == [1000.0, -0.5, 7, 16, "1e-4x", inf]


def test_a_run_records_every_option_of_its_environment(tmp_path):
    """A run keeps its environment when a task's defaults change later: the trainer records
    every option (TrainConfig.env_config); resume, eval and export build from it."""
    import yaml

    from robocup_gym.envs.tasks.walk import WalkConfig
    from robocup_gym.train.trainer import prepare_run

    _, path = prepare_run(
        TrainConfig(task="walk", env_kwargs={"max_episode_steps": 50}), out=tmp_path
    )
    saved = TrainConfig.load(path / "config.yaml")
    assert saved.env_kwargs == {"max_episode_steps": 50}
    recorded = saved.env_config
    assert recorded["max_episode_steps"] == 50
    assert recorded["gait_frequency_hz"] == WalkConfig().gait_frequency_hz
    assert recorded["action_mode"] == "target_angle" and "backend_options" not in recorded
    assert set(recorded) == {f for f in WalkConfig.__dataclass_fields__} - {"backend_options"}
    # as if the run had started when Walk's default gait was 2 Hz
    data = yaml.safe_load((path / "config.yaml").read_text())
    data["env_config"]["gait_frequency_hz"] = 2.0
    (path / "config.yaml").write_text(yaml.safe_dump(data))
    from robocup_gym.train.tasks import make_env

    old = TrainConfig.load(path / "config.yaml")
    options = old.env_options(max_episode_steps=60)
    assert options["gait_frequency_hz"] == 2.0 and options["max_episode_steps"] == 60
    env = make_env(old.env_id, backend="mujoco", env_kwargs=old.env_options())
    assert env.unwrapped.config.gait_frequency_hz == 2.0
    assert env.unwrapped.config.max_episode_steps == 50
    env.close()
    # gymnasium.make would keep max_episode_steps for its TimeLimit; make_env gives it the task
    assert env.spec.max_episode_steps == 50
    legacy = TrainConfig(task="walk", env_kwargs={"max_episode_steps": 50})  # no env_config
    assert legacy.env_options() == {"max_episode_steps": 50}


@pytest.mark.parametrize(
    ("task", "option", "version_value", "own_value"),
    [
        ("run", "w_progress", 3.0, 0.0),  # Run-v1's sprint (0: Run's default)
        ("get-up", "self_collisions", True, False),  # GetUp-v1
        ("dribble", "next_target_at_goal", True, False),  # Dribble-v1
    ],
)
def test_a_run_records_and_runs_its_versions_options_under_its_own(
    tmp_path, task, option, version_value, own_value
):
    """A version's options (over its class's defaults) are what a run records and runs; an
    option the run sets (here to the class's default, ``own_value``) goes over them, in the
    record and in the environment."""
    import yaml

    from robocup_gym.train.tasks import make_env
    from robocup_gym.train.trainer import prepare_run

    for own, want in (({}, version_value), ({option: own_value}, own_value)):
        cfg, path = prepare_run(TrainConfig(task=task, env_kwargs=own), out=tmp_path)
        assert cfg.env_config[option] == want
        env = make_env(cfg.env_id, backend="ode", env_kwargs=cfg.env_options())
        try:
            assert getattr(env.unwrapped.config, option) == want
        finally:
            env.close()
        assert TrainConfig.load(path / "config.yaml").env_config[option] == want
    # a record that kept the class's default for the version's option (an earlier robocup-gym
    # wrote that) is read with the version's, which the run's environment had
    data = yaml.safe_load((path / "config.yaml").read_text())
    data["env_kwargs"] = {}
    data["env_config"][option] = own_value  # here the class's default
    (path / "config.yaml").write_text(yaml.safe_dump(data))
    assert TrainConfig.load(path / "config.yaml").env_config[option] == version_value


def test_hp_flags_read_exponent_notation():
    from robocup_gym.cli.common import _parse_assignments

    got = _parse_assignments(["learning_rate=3e-4", "policy_kwargs={log_std_init: -1e0}"], "--hp")
    assert got == {"learning_rate": 3e-4, "policy_kwargs": {"log_std_init": -1.0}}
    assert isinstance(got["learning_rate"], float)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"algo": "dqn"}, "unknown algorithm"),
        ({"n_envs": 0}, "n_envs"),
        (
            {"backend": "gazebo"},
            "unknown backend 'gazebo'; choose one of mujoco, rcssserver3d, ode",
        ),
        ({"assist_force": 0.8}, "assist_steps >= 1"),
        ({"assist_force": float("nan"), "assist_steps": 10}, "share of the robot's weight"),
        ({"assist_force": 3.0, "assist_steps": 10}, "share of the robot's weight"),
        ({"assist_steps": -5}, "assist_steps must be >= 0"),
        (
            {"assist_force": 0.5, "assist_steps": 10, "assist_max_tilt_deg": 0.0},
            "assist_max_tilt_deg must be within 0 and 180",
        ),
        (
            {"assist_force": 0.5, "assist_steps": 10, "backend": "rcssserver3d"},
            r"'rcssserver3d' backend\s+cannot",
        ),
        ({"robot_types": [0, 5]}, r"robot_types are Nao types 0-4, got \[0, 5\]"),
        ({"robot_types": [0, True]}, "robot_types are Nao types 0-4"),
        ({"robot_types": [3, 4]}, "type 4 .toes. has two joints more"),
        ({"task": "game-2v2", "robot_types": [0, 1]}, "single-robot task"),
        ({"robot_types": [0], "env_kwargs": {"robot": "T1"}}, "this run's robot is 'T1'"),
        # values of the wrong kind (a config file's text, a flag's "false") are named
        ({"timesteps": "1e6"}, "timesteps must be an integer, got '1e6'"),
        ({"n_envs": 2.5}, "n_envs must be an integer, got 2.5"),
        ({"seed": "x"}, "seed must be an integer, got 'x'"),
        ({"normalize_obs": "false"}, "normalize_obs must be true or false, got 'false'"),
        ({"checkpoint_every_s": "soon"}, "checkpoint_every_s must be a number, got 'soon'"),
        ({"env_kwargs": 3}, "env_kwargs must be a mapping of names to values, got 3"),
        ({"algo_kwargs": [1]}, r"algo_kwargs must be a mapping of names to values, got \[1\]"),
        ({"backend": 3}, "backend must be a name or None, got 3"),
    ],
)
def test_invalid_config(kwargs, match):
    with pytest.raises(ValueError, match=match):
        TrainConfig(**kwargs)


def test_every_registered_backend_is_a_valid_choice():
    """The training config accepts exactly the backends the registry can build."""
    from robocup_gym.backends import available_backends

    for name in available_backends():
        assert TrainConfig(backend=name).backend == name


def test_a_whole_number_written_as_a_float_is_an_integer(tmp_path):
    (tmp_path / "c.yaml").write_text("timesteps: 2.0e+6\nn_envs: 4.0\n")
    config = TrainConfig.load(tmp_path / "c.yaml")
    assert config.timesteps == 2_000_000 and type(config.timesteps) is int
    assert config.n_envs == 4 and type(config.n_envs) is int


def test_unknown_config_key(tmp_path):
    (tmp_path / "c.yaml").write_text("n_env: 3\n")
    with pytest.raises(ValueError, match="unknown config key"):
        TrainConfig.load(tmp_path / "c.yaml")


def test_task_names():
    tasks = registered_tasks()
    assert tasks["velocity-kick"] == "RobocupGym/VelocityKick-v0"
    assert tasks["simple-kick"] == "RobocupGym/SimpleKick-v0"
    assert resolve_task("VelocityKick") == "RobocupGym/VelocityKick-v0"
    assert resolve_task("RobocupGym/SimpleKick-v0") == "RobocupGym/SimpleKick-v0"
    assert resolve_task("Pendulum-v1") == "Pendulum-v1"
    assert kebab("VelocityKick") == "velocity-kick"
    assert task_name("RobocupGym/VelocityKick-v0") == "velocity-kick"
    with pytest.raises(
        ValueError,
        match="known tasks: dribble, get-up, long-kick, run, simple-kick, target-kick, "
        "velocity-kick, walk",
    ):
        resolve_task("penalty-kick")

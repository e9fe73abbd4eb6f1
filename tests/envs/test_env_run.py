"""Run: Walk's task at running speeds, over a faster reference gait and a taller stance."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import robocup_gym.envs  # noqa: F401 (registers the tasks)
from robocup_gym.envs import EnvConfigError, Run, RunConfig, Walk, WalkConfig
from robocup_gym.envs.config import PAPER_STANDING_POSE_DEG
from robocup_gym.envs.tasks.run import RUN_POSE_DEG, RUN_POSE_OFFSETS_DEG
from robocup_gym.sim.engines.ode import available

needs_ode = pytest.mark.skipif(not available(), reason="no libode")


def test_run_is_a_task_of_the_cli_with_walks_training_settings():
    from robocup_gym.train.config import TASK_ALGO_DEFAULTS
    from robocup_gym.train.tasks import resolve_task

    assert resolve_task("run") == "RobocupGym/Run-v1"
    for version in ("v0", "v1"):
        assert (
            TASK_ALGO_DEFAULTS[(f"RobocupGym/Run-{version}", "ppo")]
            == TASK_ALGO_DEFAULTS[("RobocupGym/Walk-v0", "ppo")]
        )


@needs_ode
def test_run_v1_pays_the_distance_run_along_its_start_heading():
    """Run-v1 (:data:`SPRINT_OPTIONS`): always told 1.5 m/s straight ahead, paid 3 × the speed
    along the start heading and nothing for tracking; v0 keeps Walk's tracking terms."""
    import gymnasium as gym

    from robocup_gym.envs.tasks.run import SPRINT_OPTIONS

    env = gym.make("RobocupGym/Run-v1")
    u = env.unwrapped
    for key, value in SPRINT_OPTIONS.items():
        assert getattr(u.config, key) == value, key
    try:
        for seed in range(2):
            env.reset(seed=seed)
            np.testing.assert_array_equal(u.velocity_command, [1.5, 0.0, 0.0])
            start = u.torso_pos.copy()
            progress = 0.0
            for _ in range(100):
                terms = env.step(np.zeros(env.action_space.shape))[4]["reward_terms"]
                assert terms["tracking_linear"] == 0.0 and terms["tracking_turn"] == 0.0
                progress += terms["progress"]
            # 3 × the speed each 20 ms step: 150 × the distance run along the start heading
            run = (u.torso_pos - start)[0]  # the robot starts facing +x
            assert run > 0.5 and progress / 150.0 == pytest.approx(run, rel=0.05)
    finally:
        env.close()
    v0 = gym.make("RobocupGym/Run-v0").unwrapped.config
    assert v0.w_progress == 0.0 and v0.w_tracking_linear > 0.0


def test_every_default_that_differs_from_walks_is_in_the_docstring_table():
    """Run says only what differs from Walk, and its table names each of those options."""
    walk, run = WalkConfig(), RunConfig()
    differ = [
        f.name
        for f in dataclasses.fields(RunConfig)
        if getattr(walk, f.name) != getattr(run, f.name)
    ]
    assert "gait_frequency_hz" in differ and "joint_start_deg" in differ
    for name in differ:
        assert f"``{name}``" in (Run.__doc__ or ""), name
    assert run.gait_frequency_hz > walk.gait_frequency_hz
    assert run.forward_speed_range[1] >= 1.5  # commands at the running target


def test_the_run_stance_is_the_paper_pose_with_its_leg_offsets():
    for side in "LR":
        for joint, offset in RUN_POSE_OFFSETS_DEG.items():
            name = side + joint
            assert RUN_POSE_DEG[name] == pytest.approx(PAPER_STANDING_POSE_DEG[name] + offset)
    untouched = set(PAPER_STANDING_POSE_DEG) - {s + j for s in "LR" for j in RUN_POSE_OFFSETS_DEG}
    assert all(RUN_POSE_DEG[n] == PAPER_STANDING_POSE_DEG[n] for n in untouched)
    env = Run(command_change_steps=0)
    env.reset(seed=0, options={"velocity_command": (0.0, 0.0, 0.0)})
    names = env.robot_model.perceptor_names
    knee = env.joint_angles_deg[names.index("llj4")]  # LKneePitch
    assert knee == pytest.approx(RUN_POSE_DEG["LKneePitch"], abs=0.01)  # starts in its stance
    env.close()


def test_run_options_are_validated_as_walks():
    with pytest.raises(EnvConfigError, match="gait_frequency_hz"):
        RunConfig(gait_frequency_hz=0.0).validate()
    with pytest.raises(EnvConfigError, match="forward_speed_range"):
        RunConfig(forward_speed_range=(1.5, 0.5)).validate()
    for bad in (0.0, -0.1, float("nan")):
        with pytest.raises(EnvConfigError, match="tracking_turn_sigma"):
            RunConfig(tracking_turn_sigma=bad).validate()


@needs_ode
def test_zero_actions_run_faster_than_walks_reference_gait():
    """The residual policy's starting point: told 1.5 m/s, Run's reference gait alone (zero
    actions) covers ~0.75 m/s over 3 s on ODE, Walk's (capped at its largest stride) ~0.5."""

    def speed(cls) -> float:
        env = cls(command_change_steps=0)
        try:
            env.reset(seed=0, options={"velocity_command": (1.5, 0.0, 0.0)})
            start = env.torso_pos.copy()
            for _ in range(150):
                assert not env.step(np.zeros(env.action_space.shape))[2]
            return float(env.torso_pos[0] - start[0]) / 3.0
        finally:
            env.close()

    run, walk = speed(Run), speed(Walk)
    assert run > 0.65 and walk < 0.6 and run > walk + 0.15


@needs_ode
def test_the_walk_benchmark_runs_run_at_its_own_forward_command(run_benchmark):
    """``benchmarks/walk.py zero --task run``: Run's gait alone, forward at Run's default
    command (1.5 m/s): it moves forward, short of the command (and falls now and then: the
    policy over it learns balance). Run-v1 only runs straight ahead: forward alone is measured."""
    res, lines = run_benchmark("walk.py", "zero", "--task", "run", "--episodes", 1, timeout=300)
    assert res["forward_command_mps"] == 1.5
    assert any("command (1.5, 0.0, 0.0)" in line for line in lines)
    assert "sideways" not in res and "turn" not in res
    assert 0.3 < res["forward_speed_mps"] < 1.5 and res["meets_target"] is False


def test_the_walk_benchmark_rejects_a_forward_command_that_is_no_speed():
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[2] / "benchmarks" / "walk.py"
    proc = subprocess.run(
        [sys.executable, str(script), "zero", "--forward", "nan", "--episodes", "1"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode != 0 and "--forward must be a speed above 0 m/s" in proc.stderr

"""The skills beyond the paper's: TargetKick (a commanded distance and direction), LongKick
(VelocityKick that must stand) and Dribble (walk the ball to a point), and their benchmarks."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import robocup_gym.envs  # noqa: F401 (registers the tasks)
from robocup_gym.envs import Dribble, EnvConfigError, LongKick, TargetKick, VelocityKick
from robocup_gym.envs.tasks.dribble import dribble_guide
from robocup_gym.envs.tasks.target_kick import kick_outcome
from robocup_gym.sim.engines.ode import available
from robocup_gym.sim.physics import BALL_ROLLING_TIME_S, ball_rest_point

pytestmark = pytest.mark.skipif(not available(), reason="no libode")


def test_the_cli_knows_the_skills():
    from robocup_gym.train.tasks import registered_tasks

    tasks = registered_tasks()
    assert tasks["target-kick"] == "RobocupGym/TargetKick-v1"
    assert tasks["long-kick"] == "RobocupGym/LongKick-v1"
    assert tasks["dribble"] == "RobocupGym/Dribble-v1"


@pytest.mark.parametrize("speed", [1.5, 4.0])
def test_a_rolling_ball_stops_where_the_drag_says(speed):
    """ball_rest_point, from the ball's state 1 s into its roll, is within 2 % of where the
    default engine's ball stops (the rolling time constant follows from the drags, not a fit)."""
    assert pytest.approx(0.95, abs=0.01) == BALL_ROLLING_TIME_S
    env = VelocityKick(
        ball_start_pos=(0.0, 0.0), ball_start_vel=(speed, 0.0, 0.0), max_episode_steps=400
    )
    try:
        env.reset(seed=0)
        zero = np.zeros(env.action_space.shape)
        predicted = None
        for step in range(1, 400):
            env.step(zero)
            if step == 50:
                predicted = ball_rest_point(env.ball_pos, env.ball_vel)
            if step > 50 and np.linalg.norm(env.ball_vel) < 1e-3:
                break
        travel = float(env.ball_pos[0])
        assert travel > 0.5 * speed
        assert predicted[0] == pytest.approx(travel, rel=0.02)
        assert abs(predicted[1]) < 1e-3
    finally:
        env.close()


def test_kick_outcome_measures_against_the_command():
    spawn = np.array([1.0, 2.0, 0.041])
    # commanded 4 m at +30° of a robot facing +y (heading 90°): the point (1 − 2, 2 + 2√3)
    aim = spawn[:2] + 4.0 * np.array([math.cos(math.radians(120)), math.sin(math.radians(120))])
    at_rest = kick_outcome(spawn, np.array([*aim, 0.041]), np.zeros(3), 90.0, np.array([4.0, 30]))
    assert at_rest["miss_m"] == pytest.approx(0.0, abs=1e-9)
    assert at_rest["distance_error"] == pytest.approx(0.0, abs=1e-9)
    assert at_rest["direction_error_deg"] == pytest.approx(0.0, abs=1e-6)
    # half as far, 90° off to the right, still rolling: the rest point counts
    rolling = kick_outcome(
        spawn,
        np.array([spawn[0] + 1.0, spawn[1], 0.041]),
        np.array([1.0 / BALL_ROLLING_TIME_S, 0.0, 0.0]),
        90.0,
        np.array([4.0, 0.0]),
    )
    assert rolling["kick_distance_m"] == pytest.approx(2.0)
    assert rolling["distance_error"] == pytest.approx(0.5)
    assert rolling["direction_error_deg"] == pytest.approx(90.0)
    assert rolling["miss_m"] == pytest.approx(math.hypot(2.0, 4.0))
    unmoved = kick_outcome(spawn, spawn, np.zeros(3), 0.0, np.array([3.0, 0.0]))
    assert unmoved["direction_error_deg"] == 180.0 and unmoved["distance_error"] == 1.0


def test_target_kick_pays_for_accuracy_and_sees_its_command():
    """A ball rolled exactly to the command earns about the whole accuracy term, one that does
    not move earns nothing; the command is in the observation and the contact step is
    reported."""
    env = TargetKick(max_episode_steps=5, wait_steps=5)
    try:
        labels = env.observation_labels
        k = labels.index("kick_target/distance")
        obs, info = env.reset(seed=3, options={"kick_target": (6.0, 20.0)})
        assert info["contact_step"] is None
        assert env.kick_target.tolist() == [6.0, 20.0]
        # min-max normalised: 6 m of [0, 20] → −0.4; 20° of [−90, 90] → 0.222
        assert obs[k] == pytest.approx(-0.4) and obs[k + 1] == pytest.approx(20 / 90)
        zero = np.zeros(env.action_space.shape)
        for _ in range(5):
            _, reward, terminated, truncated, info = env.step(zero)
        assert truncated and not terminated
        assert info["reward_terms"] == {"accuracy": pytest.approx(0.0, abs=1e-6)}
        assert info["contact_step"] is None and info["kick_distance_m"] < 1e-3

        # a ball sent 6 m at +20°: launched sliding, without spin, it rolls at 5/7 of its
        # launch speed at once (a solid sphere on μ = ∞), then slows with the rolling time
        angle = math.radians(20.0)
        speed = 6.0 / BALL_ROLLING_TIME_S / (5.0 / 7.0)
        env.reset(
            seed=3,
            options={
                "kick_target": (6.0, 20.0),
                "ball_vel": (speed * math.cos(angle), speed * math.sin(angle), 0.0),
            },
        )
        for _ in range(5):
            _, reward, terminated, truncated, info = env.step(zero)
        assert info["contact_step"] == 1
        assert reward == pytest.approx(1.0, abs=0.03)
        assert info["direction_error_deg"] < 1.0 and info["distance_error"] < 0.03
    finally:
        env.close()


def test_target_kick_draws_its_commands_and_penalises_a_fall():
    env = TargetKick()
    try:
        commands = []
        for seed in range(20):
            env.reset(seed=seed)
            commands.append(env.kick_target.copy())
        commands = np.array(commands)
        assert (commands[:, 0] >= 2.0).all() and (commands[:, 0] <= 10.0).all()
        assert (np.abs(commands[:, 1]) <= 45.0).all() and commands[:, 1].std() > 10.0
        # the robot pushed over: the fall is paid after the wait
        env.reset(seed=0, options={"joint_angles_deg": {"lle3": 60.0, "rle3": 60.0}})
        while True:
            _, _reward, terminated, truncated, info = env.step(env.action_space.sample())
            if terminated or truncated:
                break
        assert info["fallen"] and info["reward_terms"]["fall"] == -1.0
    finally:
        env.close()
    with pytest.raises(EnvConfigError, match="kick_target_distance_range"):
        TargetKick(kick_target_distance_range=(0.0, 5.0))


def test_long_kick_is_velocity_kick_that_must_stand():
    env = LongKick()
    try:
        c = env.config
        assert (c.max_episode_steps, c.wait_steps, c.fall_penalty) == (60, 50, 3.0)
        assert (c.displacement_weight, c.speed_weight, c.lateral_weight) == (1.0, 1.0, 1.0)
        assert VelocityKick().config.fall_penalty == 0.0  # the paper's kick is unchanged
        env.reset(seed=0, options={"joint_angles_deg": {"lle3": 60.0, "rle3": 60.0}})
        while True:
            _, _reward, terminated, truncated, info = env.step(env.action_space.sample())
            if terminated or truncated:
                break
        assert info["reward_terms"]["fall"] == -3.0
    finally:
        env.close()


def test_the_dribble_guide_walks_behind_the_ball_then_through_it():
    from robocup_gym.envs import DribbleConfig

    c = DribbleConfig()
    ball, target = np.array([0.0, 0.0]), np.array([5.0, 0.0])
    # behind the ball, facing the target: straight on, through the ball
    cmd = dribble_guide(c, np.array([-0.3, 0.0]), (1.0, 0.0), ball, target)
    assert cmd == pytest.approx([0.5, 0.0, 0.0])
    # beside the ball: go round behind it (back-left aim → no forward, sideways to the right)
    cmd = dribble_guide(c, np.array([0.0, 0.5]), (1.0, 0.0), ball, target)
    assert cmd[0] == 0.0 and cmd[1] == pytest.approx(-0.3)
    # facing away from the target: turn (left, the short way for a heading of −100°)
    cmd = dribble_guide(
        c,
        np.array([-0.3, 0.0]),
        (math.cos(math.radians(-100)), math.sin(math.radians(-100))),
        ball,
        target,
    )
    assert cmd[2] == 45.0


def test_the_dribble_guide_slows_near_the_ball_when_told():
    from robocup_gym.envs import DribbleConfig

    c = DribbleConfig(guide_speed=1.0, guide_near_m=0.4, guide_near_speed=0.5)
    ball, target = np.array([0.0, 0.0]), np.array([5.0, 0.0])
    near = dribble_guide(c, np.array([-0.3, 0.0]), (1.0, 0.0), ball, target)
    far = dribble_guide(c, np.array([-0.8, 0.0]), (1.0, 0.0), ball, target)
    assert near == pytest.approx([0.5, 0.0, 0.0])
    assert far == pytest.approx([1.0, 0.0, 0.0])
    # off by default: one speed everywhere
    assert DribbleConfig().guide_near_m == 0.0
    with pytest.raises(EnvConfigError, match="guide_near_speed"):
        DribbleConfig(guide_near_speed=float("nan")).validate()


def test_dribble_zero_actions_push_the_ball_toward_the_target():
    """The guide and the reference gait alone move the ball toward a target ahead; the episode
    reports the progress, and the task's terms are in the reward."""
    env = Dribble(max_episode_steps=200)
    try:
        env.reset(seed=1, options={"dribble_target": (2.0, 0.0)})
        assert env.target_pos.tolist() == [2.0, 0.0]
        k = env.observation_labels.index("target_rel/x")
        zero = np.zeros(env.action_space.shape)
        while True:
            obs, _reward, terminated, truncated, info = env.step(zero)
            if terminated or truncated:
                break
        assert not info["fallen"]
        assert info["ball_speed_to_target_mps"] > 0.2
        assert info["ball_to_target_m"] < 4.75 - 0.2 * 4.0
        assert {"ball_progress", "near_ball", "goal", "tracking_linear"} <= set(
            info["reward_terms"]
        )
        assert -1.0 < obs[k] < 1.0  # the target is within the observation's range
    finally:
        env.close()
    with pytest.raises(ValueError, match="dribble_target"):
        Dribble().reset(options={"dribble_target": (1.0, float("nan"))})
    with pytest.raises(ValueError, match=r"dribble_target must be \(x, y\) m, got 'goal'"):
        Dribble().reset(options={"dribble_target": "goal"})
    with pytest.raises(EnvConfigError, match="target_distance_range"):
        Dribble(target_distance_range=(5.0, 2.0))


def test_dribble_v1_draws_the_next_target_at_the_goal_and_goes_on():
    """Dribble-v1 pays the goal, draws the next target within the task's ranges of the ball and
    the robot's heading, and goes on; v0 ends the episode there."""
    made = gym.make("RobocupGym/Dribble-v1")
    assert made.unwrapped.config.next_target_at_goal
    made.close()
    v1 = Dribble(max_episode_steps=100, next_target_at_goal=True)
    v0 = Dribble(max_episode_steps=100)
    zero = np.zeros(v1.action_space.shape)
    try:
        for env in (v0, v1):
            env.reset(seed=3)
            start = env.episode_start.ball_pos[:2]
            first = start + np.array([0.3, 0.0])
            env.reset(seed=3, options={"dribble_target": first})
            _, _, terminated, _, info = env.step(zero)
            assert info["reward_terms"]["goal"] == 10.0 and info["goals"] == 1
            assert terminated == (env is v0)
        c = v1.config
        gap = float(np.hypot(*(v1.target_pos - v1.ball_pos[:2])))
        first_gained = 0.3 - float(np.hypot(*(first - v1.ball_pos[:2])))
        assert c.target_distance_range[0] - 0.05 <= gap <= c.target_distance_range[1] + 0.05
        while True:
            _, _, terminated, truncated, info = v1.step(zero)
            assert info["reward_terms"]["goal"] == 0.0  # paid once, at the goal
            if terminated or truncated:
                break
        # the speed counts what the ball gained on the first target and then on the next
        gained = first_gained + gap - info["ball_to_target_m"]
        assert info["ball_speed_to_target_mps"] == pytest.approx(
            gained / (v1.episode_step * 0.02), abs=1e-6
        )
        assert info["goals"] == 1 and not info["fallen"]
    finally:
        v0.close()
        v1.close()


@pytest.mark.parametrize(
    "task", ["RobocupGym/TargetKick-v0", "RobocupGym/TargetKick-v1", "RobocupGym/Dribble-v0"]
)
@pytest.mark.parametrize("robot_type", [0, 4])
def test_the_skills_run_on_nao_types(task, robot_type):
    from gymnasium.utils.env_checker import check_env

    env = gym.make(task, robot_type=robot_type)
    try:
        check_env(env.unwrapped, skip_render_check=True)
    finally:
        env.close()


def test_the_kick_benchmark_prints_json_last(run_benchmark):
    res, lines = run_benchmark("kick.py", "zero", "--episodes", 1, timeout=300)
    assert res["task"] == "TargetKick" and res["episodes"] == 35 and len(lines) == 35
    # zero actions play TargetKick-v1's kick for each command: every ball kicked, as far and
    # in the direction commanded within the targets (measured: distance error 0.11, direction
    # error 3.4°, every robot standing)
    assert res["kicked_rate"] == 1.0 and res["stand_after_kick_rate"] >= 0.9
    assert res["distance_error_median"] <= 0.15 and res["direction_error_deg_median"] <= 5.0
    assert res["meets_target"]
    straight = [r for r in res["per_command"] if r["command"][1] == 0.0]
    assert max(r["direction_error_deg_median"] for r in straight) < 5.0
    assert [r["command"] for r in res["per_command"]][:2] == [[2.0, -45.0], [2.0, -30.0]]


def test_the_kick_landings_benchmark_prints_json_last(run_benchmark):
    from robocup_gym.envs.tasks.commanded_kicks import kick_library

    res, lines = run_benchmark("kick_landings.py")
    assert res["kicks"] == len(kick_library()) and set(res["types"]) == {"0", "1", "2", "3", "4"}
    for figures in res["types"].values():  # the library covers the kick benchmark's commands
        assert figures["predicted_distance_error_median"] <= 0.15
        assert figures["predicted_direction_error_deg_median"] <= 5.0
    assert any("benchmark commands" in line for line in lines)


def test_the_kick_benchmark_plays_the_long_kick(run_benchmark):
    res, lines = run_benchmark("kick.py", "zero", "--task", "long-kick", "--episodes", 2)
    assert res["task"] == "LongKick" and res["episodes"] == 2 and len(lines) == 1
    assert "distance_error_median" not in res  # no command: scored along the heading
    assert res["ball_distance_median_m"] > 8.5 and res["stand_after_kick_rate"] == 1.0
    assert res["direction_error_deg_median"] < 5.0
    # --env sets the environment's options: noisy starts kick to other spots
    noisy, _ = run_benchmark(
        "kick.py", "zero", "--task", "long-kick", "--episodes", 2, "--env", "ball_spawn_noise=0.02"
    )
    assert noisy["ball_distance_median_m"] != res["ball_distance_median_m"]
    assert noisy["ball_distance_median_m"] > 5.0


def test_a_benchmark_refuses_a_malformed_env_option():
    proc = subprocess.run(
        [sys.executable, "benchmarks/kick.py", "zero", "--env", "ball_spawn_noise"],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=Path(__file__).resolve().parents[2],
    )
    assert proc.returncode != 0
    assert "--env expects KEY=VALUE, got 'ball_spawn_noise'" in proc.stderr


def test_the_dribble_benchmark_prints_json_last(run_benchmark):
    res, lines = run_benchmark("dribble.py", "zero", "--episodes", 1, timeout=300)
    assert res["episodes"] == 3 and len(lines) == 3
    assert res["ball_speed_to_target_mps"] > 0.15 and res["falls"] == 0
    assert res["meets_target"] == (res["ball_speed_to_target_mps"] >= 0.6)
    low, high = res["ball_speed_to_target_ci95"]
    assert low < res["ball_speed_to_target_mps"] < high

"""The policies shipped in ``robocup_gym/data/policies``: they load, describe themselves, and do
what their names say in-process on the default engine."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("onnxruntime")

from robocup_gym.envs.observations import heading_frame
from robocup_gym.envs.tasks.getup import GetUp
from robocup_gym.sim.engines.ode import available
from robocup_gym.train.pretrained import (
    describe,
    pretrained_env,
    pretrained_names,
    pretrained_policy,
    pretrained_types,
    recorded_env_options,
)
from robocup_gym.train.tasks import make_env


def test_the_get_up_is_shipped_and_describes_itself():
    assert {"get-up", "walk", "game-walk"} <= set(pretrained_names())
    meta = describe("get-up")
    assert meta["env_id"] == "RobocupGym/GetUp-v1" and meta["backend"] == "ode"
    assert meta["env_config"]["self_collisions"] is True  # learnt under rcssserver3d's rule
    assert meta["env_config"]["mirror_actions"] is True
    assert meta["env_config"]["reference_motion"] is True  # a residual over the script
    assert meta["env_config"]["start_side"] == "random"
    assert meta["verification"]["max_abs_diff"] <= 1e-5
    assert len(meta["action_labels"]) == 10 and meta["training"]["n_envs"] == 16


def test_a_policy_for_a_robot_type_that_does_not_exist_is_refused():
    assert pretrained_policy("run", np.int64(1)).path.name == "run.type1.onnx"
    for bad in (9, "1", True):
        with pytest.raises(ValueError, match=f"robot_type must be a Nao type 0-4, got {bad!r}"):
            pretrained_policy("run", bad)
    with pytest.raises(ValueError, match="env_kwargs must map option names to values"):
        make_env("RobocupGym/Walk-v0", env_kwargs="robot_type=1")


@pytest.mark.skipif(not available(), reason="no libode")
@pytest.mark.parametrize("side", ["front", "back"])
def test_the_get_up_lifts_the_robot_within_80_cycles(side):
    """On ODE with rcssserver3d's self-collision rule (GetUp-v1), from the 16 lying poses of
    either side it trained on and 4 beyond them (40–43): up within 80 cycles, and held up, from
    at least 18 of the 20 (measured: 20 each side, as its scripts alone)."""
    policy = pretrained_policy("get-up")
    env = pretrained_env(policy, "ode")
    assert env.unwrapped.backend.world.self_collision_rule
    up = []
    try:
        for pose in [*range(16), 40, 41, 42, 43]:
            obs, _ = env.reset(seed=0, options={"start_side": side, "lying_pose": pose})
            start_z = env.unwrapped.torso_pos[2]
            done, info = False, {}
            while not done:
                obs, _, terminated, truncated, info = env.step(policy(obs))
                done = terminated or truncated
            assert info["start_side"] == side
            steps = info["steps_to_up"]
            held = env.unwrapped.torso_pos[2] > max(0.28, start_z + 0.1)
            if info["success"] and steps is not None and steps <= 80 and held:
                up.append(pose)
    finally:
        env.close()
    assert len(up) >= 18, up


def test_a_shipped_policy_runs_in_the_environment_it_was_exported_with():
    """Every recorded option, not today's task defaults: a later change of a default must not
    change what a shipped policy sees or does."""
    for name in ("get-up", "walk", "game-walk", "run"):
        policy = pretrained_policy(name)
        meta = policy.metadata
        env = pretrained_env(policy, "mujoco")
        try:
            config = env.unwrapped.config.to_dict()
            for key, value in meta["env_config"].items():
                if key == "controlled_joints" and value is None:
                    # the default (all but the head) named: the joints the policy drives
                    assert list(config[key]) == meta["controlled_joints"]
                elif key != "backend_options":
                    assert config[key] == value, key
        finally:
            env.close()
    meta = describe("get-up")
    changed = {**meta, "env_config": {**meta["env_config"], "w_height": 2.0, "height_cap": 0.3}}
    changed["env_kwargs"] = {"start_side": "front"}
    options = recorded_env_options(changed)
    assert options["w_height"] == 2.0 and options["height_cap"] == 0.3
    assert options["start_side"] == "front" and "backend_options" not in options
    # an export from before GetUp had its script ran without it, and still does
    old = {k: v for k, v in meta["env_config"].items() if k != "reference_motion"}
    old_meta = {**meta, "env_id": "RobocupGym/GetUp-v0", "env_config": old}
    assert recorded_env_options(old_meta)["reference_motion"] is False
    # the shipped get-up learnt over type 0's script; on the other types it plays theirs,
    # unless told another
    assert recorded_env_options(meta).get("script_robot_type") is None
    targets = {}
    for name, kw in (("shipped", {}), ("pinned", {"script_robot_type": 0})):
        env = pretrained_env(pretrained_policy("get-up"), "mujoco", {"robot_type": 3, **kw})
        targets[name] = [t for _, t in env.unwrapped._script["back"]]
        env.close()
    for name, kw in (("own", {}), ("zero", {"script_robot_type": 0})):
        env = GetUp(robot_type=3, engine="mujoco", **kw)
        targets[name] = [t for _, t in env._script["back"]]
        env.close()
    for a, b in (("shipped", "own"), ("pinned", "zero")):
        assert all(np.array_equal(x, y) for x, y in zip(targets[a], targets[b], strict=True))
    assert not np.array_equal(targets["own"][0], targets["zero"][0])
    env = make_env(meta["env_id"], backend="mujoco", env_kwargs=options)
    assert env.unwrapped.config.w_height == 2.0
    env.close()
    legacy = {"env_kwargs": {"start_side": "back"}}  # a description without env_config
    assert recorded_env_options(legacy) == {"start_side": "back"}


@pytest.mark.skipif(not available(), reason="no libode")
@pytest.mark.parametrize("name", ["walk", "game-walk"])
def test_the_walk_goes_where_it_is_told_and_stands_when_told(name):
    """The shipped walks on ODE, from several start phases of the gait clock: 4 s at 0.5 m/s
    forward moves the robot ~2 m forward without a fall; 0.3 m/s to the left moves it left,
    30°/s turns it counter-clockwise; told to stand, it stays put."""
    meta = describe(name)
    assert meta["env_id"] == "RobocupGym/Walk-v0" and meta["env_config"]["reference_gait"]
    policy = pretrained_policy(name)
    env = pretrained_env(policy, "ode", {"command_change_steps": 0})
    u = env.unwrapped
    try:
        for command, seeds in (
            ((0.5, 0.0, 0.0), 3),
            ((0.0, 0.0, 0.0), 3),
            ((0.0, 0.3, 0.0), 1),
            ((0.0, 0.0, 30.0), 1),
        ):
            for seed in range(seeds):
                obs, _ = env.reset(seed=seed, options={"velocity_command": command})
                start, yaw0 = u.torso_pos.copy(), _yaw(u)
                turned = 0.0
                for _ in range(200):
                    obs, _, terminated, _, info = env.step(policy(obs))
                    assert not terminated, f"fell (command {command}, seed {seed})"
                    yaw = _yaw(u)
                    turned += (yaw - yaw0 + math.pi) % (2 * math.pi) - math.pi
                    yaw0 = yaw
                moved = u.torso_pos - start  # the robot starts facing +x
                if command[0]:
                    assert 1.6 < moved[0] < 3.0 and abs(moved[1]) < moved[0] / 2, (seed, moved)
                elif command[1]:
                    assert 0.6 < moved[1] < 2.0 and abs(moved[0]) < moved[1], (seed, moved)
                elif command[2]:
                    assert 40.0 < math.degrees(turned) < 180.0, (seed, math.degrees(turned))
                    assert np.hypot(moved[0], moved[1]) < 0.4, (seed, moved)
                else:
                    assert np.hypot(moved[0], moved[1]) < 0.2, (seed, moved)
                assert info["velocity_command"][0] == command[0]
    finally:
        env.close()


@pytest.mark.skipif(not available(), reason="no libode")
@pytest.mark.parametrize("robot_type", [0, 3])
def test_the_walk_meets_the_omnidirectional_targets(robot_type):
    """The shipped ``walk`` (its command loop on, as recorded) by ``benchmarks/walk.py
    --tracking``'s measure (type 0 over 4 episodes; type 3 over the benchmark's 10, whose
    mean the documented figures are): over seconds 4 to 10, 0.8 m/s forward, 0.4 m/s to the left
    and 60°/s each within 10 %; told to stop, slower than 0.05 m/s; no fall. Nao type 3 plays a
    file of its own: the shared network over ± 26° of its ± 30° window (steadier on that type at
    middle speeds; one 10 s episode's drift at 0.8 m/s can be 10–20 % of the command)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    from walk import tracking

    assert pretrained_types("walk") == [3]
    policy = pretrained_policy("walk", robot_type)
    config = policy.metadata["env_config"]
    assert config["command_feedback_gain"] > 0.0
    assert config["robot_type"] == robot_type
    assert config["target_around_start_deg"] == (26 if robot_type == 3 else 30)
    env = pretrained_env(policy, "ode")
    try:
        out = tracking(env, policy, episodes=4 if robot_type == 0 else 10, seed=0)
    finally:
        env.close()
    assert out["meets_tracking_target"], out
    assert out["tracking"]["forward"]["forward_speed_mps"] > 0.72


@pytest.mark.skipif(not available(), reason="no libode")
def test_the_shipped_walk_sets_off_gradually():
    """The shipped ``walk`` records a limit on its command's growth (0.5 m/s² forward and
    sideways; type 3's own file none): told 0.5 m/s from standing at once, Nao type 1 fell
    within 1.5 s of three of the 100 starts of ``benchmarks/walk.py --tracking --seed
    700000``'s stop test; setting off gradually it walks on from them."""
    policy = pretrained_policy("walk", 1)
    recorded = policy.metadata["env_config"]["command_accel_limit"]
    assert tuple(recorded) == (0.5, 0.5, 0.0)
    assert "command_accel_limit" not in pretrained_policy("walk", 3).metadata["env_config"]
    for limit, expected in ((recorded, 0), ((0.0, 0.0, 0.0), 3)):
        overrides = {"robot_type": 1, "command_change_steps": 0, "command_accel_limit": limit}
        env = pretrained_env(policy, "ode", overrides)
        falls = 0
        try:
            for seed in (700024, 700029, 700057):
                obs, _ = env.reset(seed=seed, options={"velocity_command": (0.5, 0.0, 0.0)})
                for _ in range(100):
                    obs, _, terminated, _, _ = env.step(policy(obs))
                    if terminated:
                        falls += 1
                        break
        finally:
            env.close()
        assert falls == expected, (limit, falls)


@pytest.mark.skipif(not available(), reason="no libode")
def test_the_command_loop_takes_the_shipped_walk_straight():
    """The walk was trained with its command loop on: without it, told 0.5 m/s forward, it
    turns left (~7°/s); with the loop it goes 0.5 m/s straight (seconds 2 to 8). The game's
    walk, trained without a loop, drifts right (~0.19 m/s) and goes ~0.56 m/s; the loop takes
    it straight as well."""
    for name, gain, check in (
        ("walk", 0.0, lambda v, turn: turn > 3.0),
        ("walk", None, lambda v, turn: abs(v[0] - 0.5) < 0.02 and abs(v[1]) < 0.05),
        ("game-walk", 0.0, lambda v, turn: v[0] > 0.54 and v[1] < -0.15),
        ("game-walk", 1.0, lambda v, turn: abs(v[0] - 0.5) < 0.02 and abs(v[1]) < 0.1),
    ):
        policy = pretrained_policy(name)
        extra = {"command_change_steps": 0}
        if gain is not None:
            extra["command_feedback_gain"] = gain
        env = pretrained_env(policy, "ode", extra)
        u = env.unwrapped
        for seed in range(2):
            obs, _ = env.reset(seed=seed, options={"velocity_command": (0.5, 0.0, 0.0)})
            for k in range(400):
                obs, _, terminated, _, _ = env.step(policy(obs))
                assert not terminated, (name, gain, seed)
                if k == 99:
                    start, yaw0 = u.torso_pos.copy(), _yaw(u)
            velocity = (u.torso_pos - start) / 6.0  # the robot starts facing +x
            turn = math.degrees((_yaw(u) - yaw0 + math.pi) % (2 * math.pi) - math.pi) / 6.0
            assert check(velocity, turn), (name, gain, seed, velocity, turn)
        env.close()


@pytest.mark.skipif(not available(), reason="no libode")
def test_the_shipped_walk_runs_on_the_nao_with_toes():
    """Nao type 4 has two joints more (the toes) than the type the walk was trained on: the
    policy drives its own joints, the toes stay at rest, and it walks 4 s forward at 0.5 m/s
    without a fall."""
    policy = pretrained_policy("walk")
    env = pretrained_env(policy, "ode", {"command_change_steps": 0, "robot_type": 4})
    u = env.unwrapped
    try:
        assert env.action_space.shape == (20,)
        assert "lle7" not in u.config.controlled_joints
        toes = [u.robot_model.effector_names.index(n) for n in ("lle7", "rle7")]
        obs, _ = env.reset(seed=0, options={"velocity_command": (0.5, 0.0, 0.0)})
        start = u.torso_pos.copy()
        for _ in range(200):
            obs, _, terminated, _, _ = env.step(policy(obs))
            assert not terminated
        assert 1.6 < (u.torso_pos - start)[0] < 3.0
        assert np.abs(u.perception.joint_angles_deg[toes]).max() < 5.0
    finally:
        env.close()


@pytest.mark.skipif(not available(), reason="no libode")
def test_the_shipped_run_runs_straight_ahead_at_over_a_metre_a_second():
    """The shipped Run policy on ODE (Nao type 0 and type 4, whose toes it leaves at rest): 4 s
    from a standing start cover more than 4 m along the start heading, drifting left by less
    than 0.4 × that, and it is still up; the walk's fastest is ~0.55 m/s."""
    assert "run" in pretrained_names()
    meta = describe("run")
    assert meta["env_config"]["w_progress"] > 0.0 and meta["env_config"]["reference_gait"]
    for robot_type, seeds in ((0, (0, 1)), (4, (0,))):
        policy = pretrained_policy("run", robot_type)  # type 4: the shared network, its window
        env = pretrained_env(policy, "ode", {"robot_type": robot_type})
        u = env.unwrapped
        assert u.config.robot_type == robot_type
        try:
            for seed in seeds:
                obs, _ = env.reset(seed=seed)
                start = u.torso_pos.copy()
                for _ in range(200):
                    obs, _, terminated, _, _ = env.step(policy(obs))
                    assert not terminated, f"fell (type {robot_type}, seed {seed})"
                moved = u.torso_pos - start  # the robot starts facing +x
                # (it drifts to its left: ~0.3 m/s over 10 s runs)
                assert moved[0] > 4.0 and abs(moved[1]) < 0.4 * moved[0], (robot_type, seed, moved)
        finally:
            env.close()


@pytest.mark.skipif(not available(), reason="no libode")
def test_the_run_has_policies_of_their_own_for_the_longer_legged_types():
    """Nao types 1 and 3 run their own policies (the shared one, trained on type 0, falls in
    about half of their runs); types 0, 2 and 4 the shared one, each over the part of the ± 30°
    residual window it was trained with that is steadiest at 1.5 m/s or more on the type (type
    2 the whole window, type 4 a file of its own for its window): each made for its type, and
    4 s from a standing start cover more than 4 m on it without a fall."""
    assert pretrained_types("run") == [1, 2, 3, 4]
    assert describe("run")["env_config"]["target_around_start_deg"] == 22
    windows = {1: 26, 2: 30, 3: 24, 4: 24}
    for robot_type in (1, 2, 3, 4):
        policy = pretrained_policy("run", robot_type)
        assert policy.path.name == f"run.type{robot_type}.onnx"
        assert policy.metadata["env_config"]["robot_type"] == robot_type
        window = policy.metadata["env_config"]["target_around_start_deg"]
        assert window == windows[robot_type]
        env = pretrained_env(policy, "ode")
        u = env.unwrapped
        try:
            obs, _ = env.reset(seed=0)
            start = u.torso_pos.copy()
            for _ in range(200):
                obs, _, terminated, _, _ = env.step(policy(obs))
                assert not terminated, f"fell (type {robot_type})"
            moved = u.torso_pos - start
            assert moved[0] > 4.0 and abs(moved[1]) < 0.4 * moved[0], (robot_type, moved)
        finally:
            env.close()
    assert pretrained_policy("run", 0).path.name == "run.onnx"


def _yaw(env) -> float:
    """The torso's heading, rad (counter-clockwise from +x)."""
    cos, sin = heading_frame(env.ground_truth.torso_quat)
    return math.atan2(sin, cos)


SERVE_ODE = pytest.mark.parametrize("make_server", ["ode"], indirect=True)
"""The shipped policies were trained on ODE: ``serve`` on that engine only (tests/conftest.py)."""


def _serve(make_server):
    """An embedded ``robocup-gym serve`` with ground truth and no vision noise: its ports."""
    server = make_server(ground_truth=True, vision_noise=False)
    return server.agent_port, server.monitor_port


@pytest.mark.skipif(not available(), reason="no libode")
@SERVE_ODE
def test_the_agent_walks_the_shipped_walk_where_it_is_told_on_serve(make_server):
    """``robocup-gym agent --pretrained walk --command 0.5,0,0`` over the rcssserver3d protocol
    (the embedded server): the command holds for the episode and the robot walks forward;
    a malformed command, or one for a policy that takes none, is a clear error."""
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    agent_port, monitor_port = _serve(make_server)
    runner = CliRunner()
    base = ["agent", "--pretrained", "walk", "--port", str(agent_port)]
    base += ["--monitor-port", str(monitor_port), "--env", "max_episode_steps=100"]
    result = runner.invoke(app, [*base, "--command", "0.5,0,0"])
    assert result.exit_code == 0, result.output
    assert "episode: 100 steps, fallen=False" in result.output
    moved = result.output.split("torso moved (")[1].split(")")[0].split(",")
    assert float(moved[0]) > 0.5 and abs(float(moved[1])) < 0.4, result.output
    assert "success=" not in result.output  # Walk reports no success
    bad = runner.invoke(app, [*base, "--command", "0.5,fast"])
    assert bad.exit_code == 2 and "FORWARD,LEFT,TURN" in bad.output
    kick = ["agent", "--pretrained", "get-up", "--port", str(agent_port)]
    kick += ["--monitor-port", str(monitor_port), "--command", "0.5,0,0"]
    wrong = runner.invoke(app, kick)
    assert wrong.exit_code == 1 and "velocity_command" in wrong.output, wrong.output


@pytest.mark.skipif(not available(), reason="no libode")
@SERVE_ODE
def test_the_agent_gets_up_with_the_shipped_get_up_on_serve(make_server):
    """``robocup-gym agent --pretrained get-up`` over the rcssserver3d protocol (the embedded
    server, which turns robots as the SPL fork's trainer does) gets up and says so. Through the
    wire the robot starts within millimetres and the policy sees 2-decimal perceptions, and a
    get-up can be that sensitive: at least 3 of 6 from the plain drop pose within 80 cycles
    (measured: 6 of 6)."""
    import re

    from typer.testing import CliRunner

    from robocup_gym.cli import app

    agent_port, monitor_port = _serve(make_server)
    args = ["agent", "--pretrained", "get-up", "--port", str(agent_port), "--episodes", "6"]
    args += ["--monitor-port", str(monitor_port), "--env", "lying_poses=1"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    ups = [int(n) for n in re.findall(r"success=True \(up at step (\d+)\)", result.output)]
    assert result.output.count("success=") == 6
    assert sum(up <= 80 for up in ups) >= 3, result.output

"""Smoke runs of every robocup-gym command, checking real outputs."""

from __future__ import annotations

import json
import subprocess
import sys
import warnings

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")
pytest.importorskip("typer")

from .train_helpers import TINY_PPO, invoke, last_json


def test_train_writes_a_complete_run_folder(ppo_run):
    from stable_baselines3 import PPO

    from robocup_gym.train.config import TrainConfig

    cfg = TrainConfig.load(ppo_run / "config.yaml")
    assert cfg.env_id == "RobocupGym/VelocityKick-v0" and cfg.n_envs == 2 and cfg.seed == 3
    assert cfg.resolved_algo_kwargs()["gamma"] == 0.99  # paper defaults kept, overrides merged
    assert cfg.resolved_algo_kwargs()["n_steps"] == 16
    # every option of the environment recorded, as built
    assert cfg.env_config["wait_steps"] == 20 and cfg.env_config["max_episode_steps"] == 40
    assert (ppo_run / "model.zip").exists()
    ckpts = sorted((ppo_run / "checkpoints").glob("model_*_steps.zip"))
    assert len(ckpts) >= 2
    assert list((ppo_run / "tb").glob("events.out.tfevents.*"))
    rows = (ppo_run / "progress.csv").read_text().splitlines()
    assert rows[0].startswith("steps,wall_s,episodes,ep_return_mean")
    assert int(rows[-1].split(",")[0]) >= 1024
    evals = [json.loads(x) for x in (ppo_run / "evaluations.jsonl").read_text().splitlines()]
    assert evals and evals[0]["episodes"] == 5 and evals[0]["ball_dx_mean"] is not None
    # a checkpoint loads and acts
    model = PPO.load(ckpts[0], device="cpu")
    obs = np.zeros(model.observation_space.shape, dtype=np.float32)
    action, _ = model.predict(obs, deterministic=True)
    assert action.shape == model.action_space.shape


def test_eval_prints_json_last(ppo_run):
    result = invoke(["eval", ppo_run, "--episodes", 2])
    summary = last_json(result.stdout)
    for key in (
        "ball_dx_mean",
        "ball_dx_std",
        "ball_distance_mean",
        "fall_rate",
        "return_mean",
        "episodes",
    ):
        assert key in summary
    assert summary["episodes"] == 2 and summary["deterministic"] is True
    assert isinstance(summary["ball_dx_mean"], float)
    assert "ball x-displacement" in result.stdout  # the table
    assert json.loads((ppo_run / "eval.json").read_text())["episodes"] == 2


def test_eval_on_another_backend(ppo_run):
    """``--engine mujoco`` runs the policy (trained on the default engine, SimSpark's physics on
    ODE) closed-loop on the MuJoCo engine and writes eval-mujoco.json beside the run's own
    eval.json; an unknown backend or engine is a clear error."""
    from typer.testing import CliRunner

    from robocup_gym.cli import app
    from robocup_gym.sim.engines.ode import available

    bad = CliRunner().invoke(app, ["eval", str(ppo_run), "--episodes", "1", "--backend", "bullet"])
    assert bad.exit_code == 1
    assert "unknown backend 'bullet'" in bad.output and "'ode'" in bad.output
    bad = CliRunner().invoke(app, ["eval", str(ppo_run), "--episodes", "1", "--engine", "bullet"])
    assert bad.exit_code == 1 and "unknown engine 'bullet'" in bad.output
    if not available():
        pytest.skip("no double-precision libode here (apt-get install libode8)")
    before = (ppo_run / "eval.json").read_text() if (ppo_run / "eval.json").exists() else None
    result = invoke(["eval", ppo_run, "--episodes", 1, "--engine", "mujoco"])
    summary = last_json(result.stdout)
    assert summary["backend"] == "mujoco" and summary["episodes"] == 1
    assert isinstance(summary["ball_dx_mean"], float)
    assert json.loads((ppo_run / "eval-mujoco.json").read_text())["backend"] == "mujoco"
    after = (ppo_run / "eval.json").read_text() if (ppo_run / "eval.json").exists() else None
    assert after == before  # the run's own evaluation is left alone


def test_export_matches_policy_and_drives_a_robot(ppo_run, tmp_path):
    import onnxruntime as ort
    from stable_baselines3 import PPO

    onnx_path = tmp_path / "kick.onnx"
    result = invoke(["export", ppo_run, "--onnx", onnx_path])
    out = last_json(result.stdout)
    assert out["verification"]["max_abs_diff"] <= 1e-5
    # independent check on fresh observations
    model = PPO.load(ppo_run / "model.zip", device="cpu")
    rng = np.random.default_rng(5)
    obs = rng.uniform(-1, 1, (64, *model.observation_space.shape)).astype(np.float32)
    sess = ort.InferenceSession(str(onnx_path), providers=["CPUExecutionProvider"])
    got = sess.run(["action"], {"obs": obs})[0]
    expected, _ = model.predict(obs, deterministic=True)
    np.testing.assert_allclose(got, expected, atol=1e-5, rtol=0)
    meta = json.loads(onnx_path.with_suffix(".json").read_text())
    assert meta["env_id"] == "RobocupGym/VelocityKick-v0"
    assert len(meta["observation_labels"]) == model.observation_space.shape[0]

    # the runner drives a robot over the rcssserver3d protocol (embedded server in a thread)
    from robocup_gym.server import SimServer
    from robocup_gym.train.agent import run_onnx_agent

    server = SimServer(
        agent_port=0,
        monitor_port=0,
        host="127.0.0.1",
        sync=True,
        real_time=False,
        ground_truth=True,
        vision_noise=False,
    )
    agent_port, monitor_port = server.start_in_thread()
    try:
        reports = run_onnx_agent(
            str(onnx_path), port=agent_port, monitor_port=monitor_port, episodes=2
        )
    finally:
        server.stop()
    assert len(reports) == 2
    for rep in reports:
        assert 1 <= rep.steps <= 40
        assert rep.ball_displacement is not None and len(rep.ball_displacement) == 3
    # same start state every episode → the (deterministic) policy behaves the same
    assert reports[0].steps == reports[1].steps


def test_resume_continues_the_run(ppo_run, tmp_path):
    import shutil

    from stable_baselines3 import PPO

    run = tmp_path / "copy"
    shutil.copytree(ppo_run, run)
    invoke(["train", "--resume", run, "--timesteps", 1536, "--no-progress"])
    assert PPO.load(run / "model.zip", device="cpu").num_timesteps >= 1536
    steps = [int(r.split(",")[0]) for r in (run / "progress.csv").read_text().splitlines()[1:]]
    assert steps == sorted(steps) and steps[-1] >= 1536


def test_sac_train_and_export(tmp_path):
    out = tmp_path / "runs"
    invoke(
        [
            "train",
            "velocity-kick",
            "--algo",
            "sac",
            "--n-envs",
            1,
            "--timesteps",
            300,
            "--out",
            out,
            "--checkpoint-freq",
            0,
            "--eval-freq",
            0,
            "--hp",
            "learning_starts=100",
            "--hp",
            "batch_size=32",
            "--hp",
            "policy_kwargs={net_arch: [32, 32]}",
        ]
    )
    (run,) = list(out.iterdir())
    result = invoke(["export", run, "--onnx", tmp_path / "sac.onnx"])
    assert last_json(result.stdout)["verification"]["max_abs_diff"] <= 1e-5


def test_eval_video(ppo_run, tmp_path, offscreen_gl):
    video = tmp_path / "kick.mp4"
    env = offscreen_gl
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "robocup_gym.cli",
            "eval",
            str(ppo_run),
            "--episodes",
            "1",
            "--video",
            str(video),
        ],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert last_json(proc.stdout)["video"] == str(video)
    import imageio.v2 as imageio

    frames = list(imageio.get_reader(str(video), format="FFMPEG").iter_data())
    assert len(frames) >= 10 and frames[0].ndim == 3 and frames[0].std() > 1  # not blank


def test_experiments_writes_csv_and_plots(tmp_path):
    from rich.console import Console

    from robocup_gym.train.experiments import Scale, run_paper

    tiny = Scale(
        timesteps=256,
        task_timesteps=256,
        algo_envs=(1,),
        task_envs=1,
        worker_counts=(1, 2),
        worker_timesteps=128,
        seeds=1,
        eval_episodes=1,
        checkpoints=1,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import robocup_gym.train.experiments as ex

        orig = ex._base

        def tiny_base(scale, **kw):  # tests only: small PPO/SAC networks and rollouts
            cfg = orig(scale, **kw)
            hp = (
                {"n_steps": 64, "batch_size": 64, "n_epochs": 1}
                if cfg.algo == "ppo"
                else {"learning_starts": 64, "batch_size": 32}
            )
            return cfg.merged(algo_kwargs={**hp, "policy_kwargs": {"net_arch": [16]}})

        ex._base = tiny_base
        try:
            summary = run_paper(tiny, tmp_path, console=Console(quiet=True))
        finally:
            ex._base = orig
    for fig in ("algos", "tasks", "workers"):
        assert (tmp_path / f"fig_{fig}.png").stat().st_size > 1000
        assert (tmp_path / f"fig_{fig}.csv").read_text().count("\n") >= 2
    assert set(summary["figures"]["algos"]["final"]) == {"PPO, 1 workers", "SAC, 1 workers"}
    assert set(summary["figures"]["workers"]["final"]) == {1, 2}
    # a second call reuses the finished runs
    again = run_paper(tiny, tmp_path, only=["workers"], console=Console(quiet=True))
    assert again["figures"]["workers"]["final"].keys() == {1, 2}


def test_serve_is_wired_lazily(monkeypatch):
    """``robocup-gym serve`` is ``python -m robocup_gym.server``: same options, same values."""
    import robocup_gym.server.__main__ as server_main

    seen = {}
    monkeypatch.setattr(server_main, "serve", lambda **kw: seen.update(kw))
    invoke(
        [
            "serve",
            "--agent-port",
            3111,
            "--monitor-port",
            3211,
            "--host",
            "127.0.0.1",
            "--sync",
            "--no-real-time",
            "--sync-timeout",
            "2.5",
            "--seed",
            "7",
        ]
    )
    assert seen["agent_port"] == 3111 and seen["monitor_port"] == 3211
    assert seen["host"] == "127.0.0.1" and seen["sync"] is True and seen["real_time"] is False
    assert seen["sync_timeout"] == 2.5 and seen["seed"] == 7


def test_serve_missing_module_is_a_clear_error(monkeypatch):
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    monkeypatch.setitem(sys.modules, "robocup_gym.server.__main__", None)
    result = CliRunner().invoke(app, ["serve"])
    assert result.exit_code == 1
    assert "server is not available" in result.output


def test_ray_without_the_ray_package_says_how_to_install_it(monkeypatch, tmp_path):
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    monkeypatch.setitem(sys.modules, "ray", None)  # import ray fails as where it is missing
    result = CliRunner().invoke(app, ["train", "velocity-kick", "--ray", "--out", str(tmp_path)])
    assert result.exit_code == 1
    assert "pip install 'robocup-gym[ray]'" in result.output
    assert not list(tmp_path.iterdir())  # no run folder started


def test_unknown_task_is_a_clear_error(tmp_path):
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    result = CliRunner().invoke(app, ["train", "penalty-kick", "--out", str(tmp_path)])
    assert result.exit_code == 1
    assert "unknown task" in result.output and "velocity-kick" in result.output


def test_the_command_list_gives_each_command_its_summary_on_whole_lines():
    """``robocup-gym --help`` lists each command with its docstring's first paragraph, its
    sentences unbroken by the docstring's line breaks."""
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    wide = {"TERMINAL_WIDTH": "200", "COLUMNS": "200"}
    out = CliRunner().invoke(app, ["--help"], env=wide).output
    rows = [line for line in out.splitlines() if line.startswith("│ ")]
    train = next(k for k, line in enumerate(rows) if line.split()[1] == "train")
    text = " ".join(line.strip("│ ").strip() for line in rows[train : train + 3])
    # at 200 columns the summary wraps only at the panel's edge, never after "or a team"
    assert "Stable-Baselines3 (defaults: the paper's PPO setup), or a team on a team" in text
    assert rows[train + 1].split()[1] != "on"
    exp = CliRunner().invoke(app, ["experiments", "--help"], env=wide).output
    assert "(PPO vs SAC, SimpleKick vs VelocityKick, wall-clock vs workers)" in exp


def test_tiny_ppo_flags_are_valid():
    assert TINY_PPO.count("--hp") == 4


def test_normalized_observations_are_folded_into_the_onnx_graph(tmp_path):
    cfg = tmp_path / "norm.yaml"
    cfg.write_text(
        "task: velocity-kick\nn_envs: 1\ntimesteps: 256\nnormalize_obs: true\n"
        "checkpoint_freq: 0\neval_freq: 0\n"
        "algo_kwargs: {n_steps: 64, batch_size: 64, n_epochs: 1, "
        "policy_kwargs: {net_arch: [16]}}\n"
    )
    out = tmp_path / "runs"
    invoke(["train", "--config", cfg, "--out", out, "--no-progress"])
    (run,) = list(out.iterdir())
    assert (run / "vecnormalize.pkl").exists()
    meta = last_json(invoke(["export", run, "--onnx", tmp_path / "n.onnx"]).stdout)
    assert meta["verification"]["max_abs_diff"] <= 1e-5
    summary = last_json(invoke(["eval", run, "--episodes", 1]).stdout)
    assert summary["episodes"] == 1


def test_ode_transfer_replays_a_trained_policy_on_the_reference(ppo_run):
    """``benchmarks/ode_transfer.py`` on a trained run: the MuJoCo replay reproduces the
    environment's own episode exactly (the recording is complete), the ODE replay reports."""
    import importlib.util
    from pathlib import Path

    from robocup_gym.sim.engines.ode import available

    if not available():
        pytest.skip("no double-precision libode here (apt-get install libode8)")
    path = Path(__file__).resolve().parents[2] / "benchmarks" / "ode_transfer.py"
    spec = importlib.util.spec_from_file_location("ode_transfer", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    res = module.main([str(ppo_run), "--episodes", "1"])
    (ep,) = res["episodes"]
    assert ep["cycles"] > 0
    assert ep["mujoco_replay_ball_dx_m"] == ep["env_ball_dx_m"]
    assert isinstance(ep["ode_replay_ball_dx_m"], float)
    assert isinstance(ep["ode_closed_loop_ball_dx_m"], float)
    assert res["ode_closed_loop_ball_dx_mean"] == ep["ode_closed_loop_ball_dx_m"]


def test_progress_lines_report_the_rate_of_a_short_run(tmp_path):
    """Without a terminal the progress is printed as lines; a run shorter than the 2-s rate
    window reports its overall rate, not 0 steps/s."""
    import re

    out = tmp_path / "runs"
    result = invoke(
        [
            "train",
            "velocity-kick",
            "--n-envs",
            1,
            "--timesteps",
            256,
            "--out",
            out,
            "--checkpoint-freq",
            0,
            "--eval-freq",
            0,
            *TINY_PPO,
        ]
    )
    final = [line for line in result.stdout.splitlines() if " 100% " in line]
    assert final, result.stdout
    rate = re.search(r"(\d[\d,]*) steps/s", final[-1])
    assert rate and int(rate.group(1).replace(",", "")) > 0, final[-1]
    done = [line for line in result.stdout.splitlines() if line.startswith("done: ")]
    assert re.search(r"recent ball Δx [\d.]+ m · recent reward", done[0]), done  # its measure


def test_init_from_starts_a_new_run_from_a_trained_policy(ppo_run, tmp_path):
    """``--init-from RUN``: a new run (here on another backend when libode is present) starts
    from RUN's policy. With learning rate 0 the saved policy is RUN's exactly; a run whose
    observation differs is refused, naming the mismatch."""
    import torch
    from stable_baselines3 import PPO

    from robocup_gym.sim.engines.ode import available

    backend = "ode" if available() else "mujoco"
    out = tmp_path / "runs"
    args = ["train", "velocity-kick", "--n-envs", 1, "--timesteps", 64, "--out", out]
    args += ["--checkpoint-freq", 0, "--eval-freq", 0, "--no-progress", "--backend", backend]
    invoke([*args, "--init-from", ppo_run, *TINY_PPO, "--hp", "learning_rate=0.0"])
    (run,) = list(out.iterdir())
    assert f"init_from: {ppo_run}" in (run / "config.yaml").read_text()
    source = PPO.load(ppo_run / "model.zip").policy.state_dict()
    tuned = PPO.load(run / "model.zip").policy.state_dict()
    assert source.keys() == tuned.keys()
    assert all(torch.equal(source[k], tuned[k]) for k in source)

    from typer.testing import CliRunner

    from robocup_gym.cli import app

    stacked = [*args, "--init-from", str(ppo_run), *map(str, TINY_PPO), "--env", "frame_stack=2"]
    bad = CliRunner().invoke(app, [str(a) for a in stacked])
    assert bad.exit_code == 1
    assert "observation space has shape" in bad.output
    cfg = tmp_path / "norm.yaml"
    cfg.write_text("task: velocity-kick\nnormalize_obs: true\n")
    normalised = ["train", "--config", cfg, *args[2:], "--init-from", ppo_run, *TINY_PPO]
    bad = CliRunner().invoke(app, [str(a) for a in normalised])
    assert bad.exit_code == 1 and "normalize_obs" in bad.output


def test_init_from_a_shipped_policy(tmp_path):
    """``--init-from pretrained:NAME``: a new run starts from the shipped policy's actor, in the
    environment it was exported with, driving the joints it drives (with learning rate 0 the
    saved policy acts as the shipped one); on another task whose spaces match, with the options
    that shape how it acts (the task's own otherwise). A name that
    is not shipped, a network of another shape and a folder that does not exist are refused,
    each named."""
    from stable_baselines3 import PPO
    from typer.testing import CliRunner

    from robocup_gym.cli import app
    from robocup_gym.envs.tasks.walk import WALK_OBSERVATIONS
    from robocup_gym.train.config import TrainConfig
    from robocup_gym.train.pretrained import describe, pretrained_policy
    from robocup_gym.train.tasks import make_env

    base = ["train", "--n-envs", 1, "--timesteps", 32, "--checkpoint-freq", 0, "--eval-freq", 0]
    base += ["--no-progress", "--hp", "n_steps=16", "--hp", "batch_size=16", "--hp", "n_epochs=1"]
    base += ["--hp", "learning_rate=0.0", "--init-from", "pretrained:walk"]
    # on type 4, whose toes the walk (trained on types 0-3) holds still
    invoke(["train", "walk", *base[1:], "--robot-types", 4, "--out", tmp_path / "walk"])
    (run,) = list((tmp_path / "walk").iterdir())
    cfg = TrainConfig.load(run / "config.yaml")
    assert cfg.init_from == "pretrained:walk"
    for key, value in describe("walk")["env_kwargs"].items():
        assert cfg.env_kwargs[key] == value, key
    assert cfg.env_kwargs["controlled_joints"] == describe("walk")["controlled_joints"]
    obs = np.random.default_rng(0).uniform(-1, 1, (64, 94)).astype(np.float32)
    tuned = PPO.load(run / "model.zip", device="cpu").predict(obs, deterministic=True)[0]
    np.testing.assert_allclose(tuned, pretrained_policy("walk")(obs), atol=1e-5)

    # Dribble is a Walk: the walk's gait options carry over, its observations are given
    walk_obs = "observations=[" + ", ".join(WALK_OBSERVATIONS) + "]"
    invoke(["train", "dribble", *base[1:], "--env", walk_obs, "--out", tmp_path / "dribble"])
    (run,) = list((tmp_path / "dribble").iterdir())
    cfg = TrainConfig.load(run / "config.yaml")
    gait = describe("walk")["env_kwargs"]["gait_frequency_hz"]
    assert cfg.env_kwargs["gait_frequency_hz"] == gait
    assert "command_change_steps" not in cfg.env_kwargs  # Dribble's own (its guide's)
    assert "fall_penalty" not in cfg.env_kwargs  # a reward's: Dribble's own
    tuned = PPO.load(run / "model.zip", device="cpu").predict(obs, deterministic=True)[0]
    np.testing.assert_allclose(tuned, pretrained_policy("walk")(obs), atol=1e-5)

    # Dribble observing the ball and the target too: those start with zero weights, so the
    # run acts as the walk on the walk's observations whatever the ball's
    invoke(["train", "dribble", *base[1:], "--out", tmp_path / "dribble-ball"])
    (run,) = list((tmp_path / "dribble-ball").iterdir())
    cfg = TrainConfig.load(run / "config.yaml")
    env = make_env(cfg.env_id, backend="ode", env_kwargs=cfg.env_options())
    mine = env.unwrapped.observation_labels
    env.close()
    walk_labels = describe("walk")["observation_labels"]
    assert len(mine) > len(walk_labels) and "ball_rel/x" in mine
    wide = np.random.default_rng(1).uniform(-1, 1, (64, len(mine))).astype(np.float32)
    tuned = PPO.load(run / "model.zip", device="cpu").predict(wide, deterministic=True)[0]
    walk_part = wide[:, [mine.index(lab) for lab in walk_labels]]
    np.testing.assert_allclose(tuned, pretrained_policy("walk")(walk_part), atol=1e-5)

    # the run's stance and gait go with it to Dribble; its observations (no ball), reward (no
    # tracking of a command), starts and episode length do not
    run_args = [*base[1:-1], "pretrained:run", "--out", tmp_path / "dribble-from-run"]
    invoke(["train", "dribble", *run_args])
    (run,) = list((tmp_path / "dribble-from-run").iterdir())
    cfg = TrainConfig.load(run / "config.yaml")
    shipped = describe("run")["env_kwargs"]
    for key in ("gait_frequency_hz", "gait_stride_max_deg", "joint_start_deg"):
        assert cfg.env_kwargs[key] == shipped[key], key
    for key in ("observations", "w_tracking_linear", "robot_start_pos", "max_episode_steps"):
        assert key in shipped and key not in cfg.env_kwargs, key
    env = make_env(cfg.env_id, backend="ode", env_kwargs=cfg.env_options())
    mine = env.unwrapped.observation_labels
    env.close()
    run_labels = describe("run")["observation_labels"]
    assert "ball_rel/x" in mine and set(run_labels) < set(mine)
    tuned = PPO.load(run / "model.zip", device="cpu").predict(wide, deterministic=True)[0]
    run_part = wide[:, [mine.index(lab) for lab in run_labels]]
    np.testing.assert_allclose(tuned, pretrained_policy("run")(run_part), atol=1e-5)

    for extra, message in (
        (["--init-from", "pretrained:no-such"], "no pretrained policy 'no-such'"),
        (["--hp", "policy_kwargs={net_arch: [32, 32]}"], "does not fit this run's policy"),
        (["--init-from", tmp_path / "none"], "neither a run folder, an exported policy"),
        (["--init-from", tmp_path / "none.onnx"], "none.onnx: no such exported policy"),
        (["--env", "frame_stack=2"], "this run does not observe its joint_pos/"),
        (["--env", "observations=[joint_pos, gyro]"], "does not observe its joint_vel/"),
    ):
        args = ["train", "walk", *base[1:], *extra, "--out", tmp_path / "refused"]
        bad = CliRunner().invoke(app, [str(a) for a in args])
        assert bad.exit_code == 1, bad.output
        assert message in " ".join(bad.output.split()), bad.output
    assert not (tmp_path / "refused").exists() or not any((tmp_path / "refused").iterdir())


def test_an_exported_policy_carries_its_action_noise_into_a_run_from_it(tmp_path):
    """An export records a PPO policy's action noise (``action_log_std``); a run that starts
    from the exported file (``--init-from POLICY.onnx``) starts with that noise and acts as it."""
    from stable_baselines3 import PPO

    from robocup_gym.train.export import export_onnx

    base = ["train", "walk", "--n-envs", 2, "--checkpoint-freq", 0, "--eval-freq", 0]
    base += ["--no-progress", *TINY_PPO]
    invoke([*base, "--timesteps", 96, "--hp", "learning_rate=0.01", "--out", tmp_path / "a"])
    (source,) = list((tmp_path / "a").iterdir())
    trained = PPO.load(source / "model.zip", device="cpu")
    log_std = trained.policy.log_std.detach().numpy()
    assert np.abs(log_std).max() > 1e-4  # moved from its initial 0
    meta = export_onnx(source, tmp_path / "my-walk.onnx")
    np.testing.assert_allclose(meta["action_log_std"], log_std, atol=1e-7)

    args = [*base, "--timesteps", 32, "--hp", "learning_rate=0.0"]
    invoke([*args, "--init-from", tmp_path / "my-walk.onnx", "--out", tmp_path / "b"])
    (run,) = list((tmp_path / "b").iterdir())
    tuned = PPO.load(run / "model.zip", device="cpu")
    np.testing.assert_allclose(tuned.policy.log_std.detach().numpy(), log_std, atol=1e-7)
    obs = np.random.default_rng(0).uniform(-1, 1, (32, 94)).astype(np.float32)
    np.testing.assert_allclose(
        tuned.predict(obs, deterministic=True)[0],
        trained.predict(obs, deterministic=True)[0],
        atol=1e-5,
    )


def test_value_warmup_holds_the_policy_while_the_value_network_learns(tmp_path):
    """``--hp value_warmup_steps=N``: the updates of a run's first N steps leave the policy as
    it started (here the shipped walk) and train the value network; without it the same
    updates move the policy."""
    import torch
    from stable_baselines3 import PPO

    from robocup_gym.train.pretrained import pretrained_policy

    args = ["train", "walk", "--n-envs", 2, "--timesteps", 64, "--checkpoint-freq", 0]
    args += ["--eval-freq", 0, "--no-progress", "--hp", "n_steps=16", "--hp", "batch_size=16"]
    args += ["--hp", "learning_rate=0.001", "--init-from", "pretrained:walk", "--seed", 3]
    obs = np.random.default_rng(0).uniform(-1, 1, (64, 94)).astype(np.float32)
    shipped = pretrained_policy("walk")(obs)
    models = {}
    for name, extra in (
        ("held", ["--hp", "value_warmup_steps=64"]),
        ("moved", []),
        ("fresh", ["--hp", "learning_rate=0.0"]),  # the value network as it started
    ):
        invoke([*args, *extra, "--out", tmp_path / name])
        (run,) = list((tmp_path / name).iterdir())
        models[name] = PPO.load(run / "model.zip", device="cpu")
    held = models["held"].predict(obs, deterministic=True)[0]
    np.testing.assert_allclose(held, shipped, atol=1e-5)
    moved = models["moved"].predict(obs, deterministic=True)[0]
    assert np.abs(moved - shipped).max() > 1e-3
    value = {k: m.policy.state_dict()["value_net.weight"] for k, m in models.items()}
    assert not torch.equal(value["held"], value["fresh"])


def test_init_from_carries_the_observation_statistics(tmp_path):
    """A run with ``normalize_obs`` passes its running observation statistics on: the new run
    continues them (its count starts at the source's)."""
    import pickle

    cfg = tmp_path / "norm.yaml"
    cfg.write_text("task: velocity-kick\nn_envs: 1\nnormalize_obs: true\n")
    base = ["train", "--config", cfg, "--timesteps", 128, "--checkpoint-freq", 0]
    base += ["--eval-freq", 0, "--no-progress", *TINY_PPO]
    invoke([*base, "--out", tmp_path / "a"])
    (source,) = list((tmp_path / "a").iterdir())
    invoke([*base, "--out", tmp_path / "b", "--init-from", source])
    (tuned,) = list((tmp_path / "b").iterdir())

    def count(run):
        with open(run / "vecnormalize.pkl", "rb") as f:
            return pickle.load(f).obs_rms.count

    assert count(tuned) > count(source) > 100


def test_locomotion_experiments_write_learning_curves(tmp_path):
    """``robocup-gym experiments locomotion``: per task a CSV of the periodic evaluations
    (Walk: mean forward speed and tracking error; GetUp: success rate) and a PNG; finished runs
    are reused; bad choices are one clear error."""
    import csv

    from rich.console import Console

    from robocup_gym.train.experiments import run_locomotion

    tiny = {"n_steps": 64, "batch_size": 64, "n_epochs": 1, "policy_kwargs": {"net_arch": [16]}}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        summary = run_locomotion(
            "quick",
            tmp_path,
            timesteps=256,
            evaluations=2,
            eval_episodes=1,
            n_envs=2,
            algo_kwargs=tiny,
            console=Console(quiet=True),
        )
    for task, metric in (("walk", "forward_speed_mps_mean"), ("get-up", "success_rate")):
        assert (tmp_path / f"fig_{task}.png").stat().st_size > 1000
        with (tmp_path / f"fig_{task}.csv").open() as f:
            rows = list(csv.DictReader(f))
        assert [int(r["steps"]) for r in rows] == [128, 256]
        assert all(r["metric"] == metric and r["value"] != "" for r in rows)
        assert all(float(r["wall_s"]) >= 0 for r in rows)
        assert all((r["forward_error_mps"] != "") == (task == "walk") for r in rows)
        assert summary["tasks"][task]["last"][0]["steps"] == 256
        if task == "get-up":
            assert all(0.0 <= float(r["value"]) <= 1.0 for r in rows)
    again = run_locomotion(
        "quick", tmp_path, tasks=["walk"], timesteps=256, evaluations=2, console=Console(quiet=True)
    )
    assert again["tasks"]["walk"]["last"][0]["steps"] == 256  # reused, not retrained
    with pytest.raises(ValueError, match="unknown task"):
        run_locomotion("quick", tmp_path, tasks=["swim"])
    with pytest.raises(ValueError, match="unknown scale"):
        run_locomotion("huge", tmp_path)


def test_episode_metrics_carry_the_locomotion_measures():
    """GetUp's ``success`` and Walk's forward speed and tracking error reach the summaries
    (and so evaluations.jsonl and the curves); a kick episode has none of them."""
    import numpy as np

    from robocup_gym.train.metrics import episode_record, summarize

    ups = [episode_record({"success": s, "fallen": False}, 1.0, 10) for s in (True, False, True)]
    walks = [
        episode_record({"forward_speed_mps": v, "forward_error_mps": e}, 0.0, 5)
        for v, e in ((0.4, 0.1), (np.float64(0.6), 0.3))
    ]
    assert summarize(ups)["success_rate"] == pytest.approx(2 / 3)
    w = summarize(walks)
    assert w["forward_speed_mps_mean"] == pytest.approx(0.5)
    assert w["forward_error_mps_mean"] == pytest.approx(0.2) and w["success_rate"] is None
    kick = summarize([episode_record({"ball_dx": 1.0}, 1.0, 3)])
    assert kick["success_rate"] is None and kick["forward_speed_mps_mean"] is None
    assert kick["assist_share_mean"] is None
    helped = [episode_record({"success": False, "assist_share": a}, 0.0, 5) for a in (0.8, 0.6)]
    assert summarize(helped)["assist_share_mean"] == pytest.approx(0.7)
    aimed = summarize(
        [
            episode_record({"distance_error": d, "direction_error_deg": a}, 0.0, 60)
            for d, a in ((0.2, 4.0), (0.4, 8.0))
        ]
    )
    assert aimed["distance_error_mean"] == pytest.approx(0.3)
    assert aimed["direction_error_deg_mean"] == pytest.approx(6.0)
    dribbles = [
        episode_record({"ball_speed_to_target_mps": v, "losses": n}, 0.0, 500)
        for v, n in ((0.5, 1), (0.7, 3))
    ]
    assert summarize(dribbles)["ball_speed_to_target_mps_mean"] == pytest.approx(0.6)
    assert summarize(dribbles)["losses_mean"] == pytest.approx(2.0)


def test_walk_reports_its_forward_speed_and_tracking_error():
    import gymnasium

    import robocup_gym.envs  # noqa: F401

    env = gymnasium.make("RobocupGym/Walk-v0")
    try:
        env.reset(seed=0, options={"velocity_command": (0.5, 0.0, 0.0)})
        for _ in range(5):
            _, _, terminated, truncated, info = env.step(env.action_space.sample() * 0.0)
            if terminated or truncated:
                break
        speed, error = info["forward_speed_mps"], info["forward_error_mps"]
        assert abs(speed) < 0.5  # standing still, barely moving
        assert error == pytest.approx(abs(0.5 - speed), abs=0.2) and error > 0.2
    finally:
        env.close()


def test_the_training_display_shows_each_tasks_own_measure():
    from robocup_gym.train.callbacks import task_measure

    assert task_measure({"success_rate": 0.5, "ball_dx_mean": 0.1}) == "success 0.50"
    assert task_measure({"forward_speed_mps_mean": 0.41, "forward_error_mps_mean": 0.1}) == (
        "forward 0.41 m/s (error 0.10)"
    )
    assert task_measure({"ball_dx_mean": 2.24}) == "ball Δx 2.24 m"
    assert task_measure(
        {"distance_error_mean": 0.25, "direction_error_deg_mean": 7.04, "ball_dx_mean": 2.0}
    ) == ("distance error 0.25 · direction error 7.0°")
    dribble = {"ball_speed_to_target_mps_mean": 0.55, "losses_mean": 1.0}
    assert task_measure({**dribble, "forward_speed_mps_mean": 0.4}) == (
        "ball → target 0.55 m/s (losses 1.0)"
    )
    team = {"rating_mu": 26.04, "goal_difference_vs_scripted": 0.5, "ball_dx_mean": None}
    assert task_measure(team) == "vs scripted +0.50 goals/game · rating 26.0"


def test_train_and_eval_a_league_robot(tmp_path):
    """``--env robot=T1`` trains on the league's simulator in-process (backend rcsssmj, chosen
    for the robot), and the run evaluates there and on a real rcssservermj."""
    pytest.importorskip("rcsssmj", reason="the optional rcsssmj package is not installed")
    from robocup_gym.train.config import TrainConfig

    args = "train velocity-kick --env robot=T1 --n-envs 2 --timesteps 256 --seed 1"
    args += " --eval-freq 0 --checkpoint-freq 0"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        invoke([*args.split(), "--out", tmp_path, *TINY_PPO])
    (run,) = list(tmp_path.iterdir())
    cfg = TrainConfig.load(run / "config.yaml")
    assert cfg.backend == "rcsssmj" and cfg.env_kwargs["robot"] == "T1"
    result = last_json(invoke(["eval", run, "--episodes", "2"]).output)
    assert result["episodes"] == 2
    real = last_json(invoke(["eval", run, "--episodes", "1", "--backend", "rcssservermj"]).output)
    assert real["episodes"] == 1
    with pytest.raises(AssertionError, match="'rcsssmj' in-process"):
        invoke(["eval", run, "--episodes", "1", "--engine", "mujoco"])


def test_tasks_lists_the_tasks_and_the_robots():
    out = invoke(["tasks"]).output
    assert "velocity-kick" in out and "RobocupGym/GetUp-v1" in out
    assert "robots: the Nao, types 0-4" in out
    assert "team scenarios" in out and "game-1v1 … game-11v11" in out
    assert "motion skills of the game's skill actions (--env skills=[NAME, ...]): kick" in out
    try:
        import rcsssmj  # noqa: F401
    except ImportError:
        assert "pip install 'robocup-gym[mj]'" in out
    else:
        assert "T1" in out and "K1" in out and "--env robot=NAME" in out


def test_train_with_an_assist_records_it_and_resume_keeps_it(tmp_path):
    from typer.testing import CliRunner

    from robocup_gym.cli import app
    from robocup_gym.train.config import TrainConfig
    from robocup_gym.train.trainer import _steps_done

    out = tmp_path / "runs"
    args = ["train", "get-up", "--engine", "mujoco", "--n-envs", 2, "--timesteps", 64]
    args += ["--assist-force", 0.5, "--assist-steps", 1000, "--assist-max-tilt", 60]
    args += ["--out", out, "--no-progress"]
    invoke([*args, "--eval-freq", 0, "--checkpoint-freq", 0, *TINY_PPO])
    (run,) = out.iterdir()
    cfg = TrainConfig.load(run / "config.yaml")
    assert (cfg.assist_force, cfg.assist_steps, cfg.assist_max_tilt_deg) == (0.5, 1000, 60)
    assert _steps_done(run / "model.zip") >= 64 and _steps_done(None) == 0
    # the assist belongs to the run: a resume takes it from the run's config
    result = CliRunner().invoke(
        app, ["train", "--resume", str(run), "--assist-force", "0.2", "--no-progress"]
    )
    assert result.exit_code != 0 and "--assist-force cannot change it" in result.output
    bad = ["train", "get-up", "--assist-force", "0.5", "--out", str(tmp_path / "x")]
    result = CliRunner().invoke(app, bad)
    assert result.exit_code == 1 and "assist_steps >= 1" in result.output


def test_train_over_several_robot_types_records_them(tmp_path):
    from robocup_gym.train.config import TrainConfig

    out = tmp_path / "runs"
    args = ["train", "velocity-kick", "--engine", "mujoco", "--n-envs", 2, "--timesteps", 32]
    args += ["--robot-types", 1, "--robot-types", 3, "--out", out, "--no-progress"]
    invoke([*args, "--eval-freq", 0, "--checkpoint-freq", 0, *TINY_PPO])
    (run,) = out.iterdir()
    assert TrainConfig.load(run / "config.yaml").robot_types == [1, 3]
    invoke(["train", "--resume", run, "--timesteps", 32, "--no-progress"])  # kept, not refused


def test_pretrained_policies_are_found_evaluated_and_listed(ppo_run, tmp_path, monkeypatch):
    """The shipped-policy machinery on a policy put where the package keeps them: found by
    its name (loosely), evaluated in-process like a run, listed by `tasks`, unknown names
    refused with the list."""
    from robocup_gym.train import pretrained

    shipped = tmp_path / "policies"
    invoke(["export", ppo_run, "--onnx", shipped / "quick-kick.onnx"])
    monkeypatch.setattr(pretrained, "POLICY_DIR", shipped)
    assert pretrained.pretrained_names() == ["quick-kick"]
    assert pretrained.pretrained_path("Quick_Kick") == shipped / "quick-kick.onnx"
    assert pretrained.describe("quick-kick")["training"]["n_envs"] == 2
    out = last_json(invoke(["eval", "--pretrained", "quick-kick", "--episodes", 2]).stdout)
    assert out["pretrained"] == "quick-kick" and out["episodes"] == 2
    assert out["env_id"] == "RobocupGym/VelocityKick-v0" and out["backend"] == "ode"
    run_eval = last_json(invoke(["eval", ppo_run, "--episodes", 2]).stdout)
    # the ONNX graph is the policy (to 1e-5): the same episodes, the same kicks
    assert out["ball_dx_mean"] == pytest.approx(run_eval["ball_dx_mean"], abs=0.02)
    assert "quick-kick" in invoke(["tasks"]).stdout
    with pytest.raises(ValueError, match="shipped: quick-kick"):
        pretrained.pretrained_path("walk")
    # a Nao type's own policy: listed under the name, given for that type, the shared for others
    assert pretrained.pretrained_types("quick-kick") == []
    for suffix in (".onnx", ".json"):
        (shipped / f"quick-kick.type3{suffix}").write_bytes(
            (shipped / f"quick-kick{suffix}").read_bytes()
        )
    assert pretrained.pretrained_names() == ["quick-kick"]
    assert pretrained.pretrained_types("quick-kick") == [3]
    assert pretrained.pretrained_path("quick-kick", 3) == shipped / "quick-kick.type3.onnx"
    assert pretrained.pretrained_path("quick-kick", 1) == shipped / "quick-kick.onnx"
    on3 = last_json(
        invoke(["eval", "--pretrained", "quick-kick", "--episodes", 1, "--robot-type", 3]).stdout
    )
    assert on3["pretrained"] == "quick-kick.type3" and on3["robot_type"] == 3
    on1 = last_json(
        invoke(["eval", "--pretrained", "quick-kick", "--episodes", 1, "--robot-type", 1]).stdout
    )
    assert on1["pretrained"] == "quick-kick" and on1["robot_type"] == 1
    assert out["robot_type"] == 0
    run_on1 = last_json(invoke(["eval", ppo_run, "--episodes", 1, "--robot-type", 1]).stdout)
    assert run_on1["robot_type"] == 1 and run_on1["written"].endswith("eval-type1.json")
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    result = CliRunner().invoke(app, ["eval", str(ppo_run), "--pretrained", "quick-kick"])
    assert result.exit_code == 1 and "not both" in result.output
    result = CliRunner().invoke(app, ["agent", "--pretrained", "nothing"])
    assert result.exit_code == 1 and "no pretrained policy 'nothing'" in result.output


def test_getup_refuses_an_agent_connection_that_cannot_lay_the_robot_down():
    """An agent alone can only beam a robot upright: GetUp says so instead of starting from a
    pose it cannot make."""
    from robocup_gym.envs import EnvConfigError, GetUp
    from robocup_gym.server import SimServer
    from robocup_gym.train.agent import AgentConnectionBackend

    server = SimServer(agent_port=0, monitor_port=0, host="127.0.0.1", sync=True, real_time=False)
    agent_port, _ = server.start_in_thread()
    backend = AgentConnectionBackend("127.0.0.1", agent_port)
    try:
        with pytest.raises(EnvConfigError, match="'agent-connection' backend cannot place"):
            GetUp(backend=backend)
    finally:
        backend.close()
        server.stop()


def test_export_records_the_environment_the_policy_is_meant_for(ppo_run, tmp_path):
    """``export --env KEY=VALUE``: options over the run's go into the description (a get-up
    from the front only, say); options that change the spaces are refused."""
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    onnx = tmp_path / "k.onnx"
    invoke(["export", ppo_run, "--onnx", onnx, "--env", "ball_spawn_noise=0.01"])
    meta = json.loads(onnx.with_suffix(".json").read_text())
    assert meta["env_kwargs"]["ball_spawn_noise"] == 0.01
    assert meta["env_config"]["ball_spawn_noise"] == 0.01
    bad = ["export", str(ppo_run), "--onnx", str(tmp_path / "b.onnx"), "--env", "robot_type=4"]
    result = CliRunner().invoke(app, bad)
    assert result.exit_code == 1 and "do not fit this policy" in result.output
    assert not (tmp_path / "b.onnx").exists()


def test_every_train_config_field_is_an_option_of_train(tmp_path):
    """The train command's options come from TrainConfig: one per field (those it takes in
    its own way aside), with the field's docstring as help, reaching the run's config."""
    import dataclasses

    import typer

    from robocup_gym.cli import _NOT_TRAIN_OPTIONS, app
    from robocup_gym.train.config import TrainConfig

    command = typer.main.get_command(app).commands["train"]
    flags = {f for p in command.params for f in (*p.opts, *p.secondary_opts)}
    for f in dataclasses.fields(TrainConfig):
        if f.name not in _NOT_TRAIN_OPTIONS:
            assert "--" + f.name.replace("_", "-") in flags, f.name
    assert "--no-normalize-obs" in flags and "--assist-max-tilt" in flags
    helps = {p.name: p.help for p in command.params}
    assert helps["eval_episodes"] == "Episodes of each periodic evaluation (default: 5)."
    assert helps["torch_threads"].startswith("Torch intra-op threads")

    from robocup_gym.sim.engines.ode import available

    out = tmp_path / "runs"
    args = ["train", "velocity-kick", "--n-envs", 1, "--timesteps", 64, "--out", out]
    args += ["--checkpoint-freq", 0, "--eval-freq", 0, "--no-progress", *TINY_PPO]
    args += ["--backend", "ode" if available() else "mujoco"]
    invoke([*args, "--eval-episodes", 3, "--torch-threads", 2, "--checkpoint-every-s", 0])
    (run,) = list(out.iterdir())
    cfg = TrainConfig.load(run / "config.yaml")
    assert (cfg.eval_episodes, cfg.torch_threads, cfg.checkpoint_every_s) == (3, 2, 0.0)


def test_train_refuses_a_malformed_assignment(tmp_path):
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    for option in ("--hp", "--env"):
        args = ["train", "velocity-kick", "--out", str(tmp_path), option, "learning_rate"]
        bad = CliRunner().invoke(app, args)
        assert bad.exit_code == 1
        assert f"{option} expects KEY=VALUE, got 'learning_rate'" in bad.output
    assert not any(tmp_path.iterdir())  # nothing started

"""A user's first hour with training: what the run shows, what it saves, how it stops, and that
the evaluation, the info and the over-the-wire agent tell the same story."""

from __future__ import annotations

import itertools
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from _waits import pid_alive, wait_until

pytest.importorskip("stable_baselines3")
pytest.importorskip("typer")

from .train_helpers import TINY_PPO, invoke


# ------------------------------------------------------------------ the progress display
class _FakeStats:
    """What the display reads of :class:`EpisodeStatsCallback`."""

    episodes = 4854

    def summary(self):
        return {"return_mean": 1.234, "ball_dx_mean": 0.41}


def _progress(total=1_000_000, width=80, terminal=True):
    from rich.console import Console

    from robocup_gym.train.callbacks import RichProgressCallback

    console = Console(width=width, force_terminal=terminal, record=True, color_system=None)
    cb = RichProgressCallback(_FakeStats(), total, description="velocity-kick", console=console)
    return cb, console


def test_format_duration():
    from robocup_gym.train.callbacks import format_duration

    assert format_duration(0) == "0:00"
    assert format_duration(75) == "1:15"
    assert format_duration(3725) == "1:02:05"
    assert format_duration(None) == "?" and format_duration(float("nan")) == "?"


@pytest.mark.parametrize("width", [80, 60, 120])
def test_the_live_display_fits_the_terminal_and_labels_its_times(monkeypatch, width):
    from robocup_gym.train import callbacks
    from robocup_gym.train.callbacks import _Display

    cb, console = _progress(width=width)
    now = [1000.0]
    monkeypatch.setattr(callbacks.time, "perf_counter", lambda: now[0])
    cb._t0, cb._start_steps = 1000.0, 0
    cb.num_timesteps = 450_000
    now[0] = 1000.0 + 225.0  # 2,000 steps/s
    console.print(_Display(cb))
    lines = [ln for ln in console.export_text().splitlines() if ln.strip()]
    assert len(lines) == 2
    assert all(len(ln) <= width for ln in lines), lines
    assert "45%" in lines[0] and "450,000/1,000,000" in lines[0]
    assert "2,000 steps/s" in lines[1] and "elapsed 3:45" in lines[1]
    assert "left ~4:35" in lines[1]  # 550,000 steps at 2,000 steps/s
    if width >= 80:
        assert "ball Δx 0.41 m" in lines[1]


def test_the_remaining_time_is_steady_when_the_rate_wobbles(monkeypatch):
    """The estimate divides by the session's average rate: a slow rollout (an update, an
    evaluation) moves it a little, not by half."""
    from robocup_gym.train import callbacks

    cb, _ = _progress(total=100_000)
    now = [0.0]
    monkeypatch.setattr(callbacks.time, "perf_counter", lambda: now[0])
    cb._t0, cb._start_steps = 0.0, 0
    estimates = []
    for k in range(1, 21):  # 2,000 steps/s, with every fifth second four times slower
        now[0] += 1.0
        cb.num_timesteps += 500 if k % 5 == 0 else 2000
        if k >= 10:
            estimates.append(cb.remaining_s())
    spread = (max(estimates) - min(estimates)) / np.mean(estimates)
    # a slow second raises the estimate by a few per cent, not fourfold as the second's own rate
    # would (the 0:42 → 1:28 → 0:57 of a per-rollout estimate)
    assert all(b <= a * 1.1 for a, b in itertools.pairwise(estimates)), estimates
    assert spread < 0.6


def test_plain_lines_for_logs_carry_the_remaining_time():
    cb, _ = _progress(terminal=False)
    cb._t0 -= 10.0
    cb.num_timesteps = 20_000
    line = cb.line()
    assert line.startswith("velocity-kick   2% 20,000/1,000,000")
    assert "elapsed 0:10" in line and "left ~" in line and "steps/s" in line
    assert len(cb.line(width=80)) <= 80


# ------------------------------------------------------------------ whole runs
def _quiet_run(tmp_path, **fields):
    """A tiny in-process PPO run on VelocityKick; returns (result, everything it printed)."""
    from rich.console import Console

    from robocup_gym.train.config import TrainConfig
    from robocup_gym.train.trainer import train

    console = Console(width=80, record=True, force_terminal=False, soft_wrap=True)
    settings = {"n_envs": 2, "seed": 3, "checkpoint_freq": 0, "eval_freq": 0, "vec_env": "dummy"}
    cfg = TrainConfig(
        **{**settings, **fields},
        algo_kwargs={
            "n_steps": 16,
            "batch_size": 32,
            "n_epochs": 1,
            "policy_kwargs": {"net_arch": [16]},
        },
    )
    result = train(cfg, out=tmp_path, console=console, log_every_s=0.5)
    return result, console.export_text()


def test_a_run_says_how_long_it_takes_and_shows_each_evaluation(tmp_path):
    from robocup_gym.train import callbacks

    orig = callbacks.RichProgressCallback.__init__

    def quick(self, *a, **k):  # estimate after 0.2 s instead of 15 s
        orig(self, *a, **k)
        self.estimate_after_s = 0.2

    callbacks.RichProgressCallback.__init__ = quick
    try:
        result, text = _quiet_run(
            tmp_path, timesteps=1024, checkpoint_every_s=0.5, eval_freq=512, eval_episodes=2
        )
    finally:
        callbacks.RichProgressCallback.__init__ = orig
    assert "checkpoints every 0.5 s;" in text
    assert "SIGTERM" in text  # it says how to stop it safely
    assert "measured" in text and "steps left, about" in text
    evals = [ln for ln in text.splitlines() if ln.startswith("eval at ")]
    assert len(evals) == 2 and "512 steps" in evals[0] and "ball Δx" in evals[0]
    logged = [
        json.loads(x) for x in (result.run_dir / "evaluations.jsonl").read_text().splitlines()
    ]
    assert [e["steps"] for e in logged] == [512, 1024]
    assert "left ~" in text and "elapsed" in text  # the plain progress lines of a log


@pytest.mark.skipif(not hasattr(signal, "SIGTERM") or sys.platform != "linux", reason="Linux")
@pytest.mark.parametrize("sig", ["SIGTERM", "SIGHUP"])
def test_sigterm_and_sighup_save_the_run_and_say_where(tmp_path, sig, child_pids):
    """A job scheduler's SIGTERM (or a closed terminal's SIGHUP) saves like Ctrl-C: the model,
    a message saying where and how to continue, exit status 128 + signal, no worker left."""
    cmd = [
        sys.executable,
        "-m",
        "robocup_gym.cli",
        "train",
        "velocity-kick",
        "--n-envs",
        "2",
        "--n-workers",
        "2",
        "--timesteps",
        "100000000",
        "--checkpoint-freq",
        "0",
        "--eval-freq",
        "0",
        "--out",
        str(tmp_path),
        *TINY_PPO,
    ]
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "COLUMNS": "80"}
    proc = subprocess.Popen(
        cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env
    )
    lines = []
    try:
        deadline = time.monotonic() + 120
        for line in proc.stdout:
            lines.append(line)
            if "velocity-kick: 0/100,000,000 steps" in line or time.monotonic() > deadline:
                break
        time.sleep(2.0)  # a few rollouts
        workers = child_pids(proc.pid)
        proc.send_signal(getattr(signal, sig))
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    text = "".join(lines) + out
    assert proc.returncode == 128 + getattr(signal, sig), text
    (run,) = list(tmp_path.iterdir())
    assert (run / "model.zip").exists()
    assert f"stopped by {sig}: model saved" in text
    assert f"continue: robocup-gym train --resume {run}" in text
    # the workers end with the run (on a loaded machine not within any fixed sleep)
    wait_until(lambda: not any(map(pid_alive, workers)), timeout=30.0, what="the workers' end")


def test_a_time_checkpoint_comes_early_and_replaces_the_previous_one(tmp_path):
    result, text = _quiet_run(tmp_path, timesteps=2048, seed=1, checkpoint_every_s=1e-3)
    run = result.run_dir
    assert "first checkpoint: " in text
    kept = list((run / "checkpoints").glob("model_*_steps.zip"))
    assert len(kept) == 1  # time-triggered ones replace each other
    assert text.count("checkpoint: ") > 2


def test_resume_continues_episode_counts_and_measures_only_its_own_steps(ppo_run, tmp_path):
    import shutil

    run = tmp_path / "run"
    shutil.copytree(ppo_run, run)
    before = (run / "progress.csv").read_text().splitlines()
    invoke(["train", "--resume", run, "--timesteps", 1536, "--no-progress"])
    rows = [r.split(",") for r in (run / "progress.csv").read_text().splitlines()[1:]]
    old = len(before) - 1
    episodes = [int(r[2]) for r in rows]
    assert episodes == sorted(episodes) and episodes[old] >= episodes[old - 1]
    steps, wall = [int(r[0]) for r in rows], [float(r[1]) for r in rows]
    # the resumed rows' rate counts the resumed steps over the resumed time only
    new_rate = float(rows[-1][8])
    assert new_rate <= (steps[-1] - steps[old - 1]) / max(wall[-1] - wall[old - 1], 1e-9) * 1.5


def test_bad_options_fail_in_one_line_and_leave_no_run_folder(tmp_path):
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    for args, expected in (
        (["--env", "nosuch=1"], "unknown option(s) 'nosuch' for VelocityKickConfig"),
        (["--hp", "nosuch=1"], "unknown PPO hyperparameter(s) 'nosuch'"),
        (["--hp", "learning_rate=fast"], "learning_rate must be a number >= 0, got 'fast'"),
        (["--hp", "gamma=2"], "PPO hyperparameter gamma must be a number in [0, 1], got 2"),
        (["--hp", "n_steps=0"], "PPO hyperparameter n_steps must be an integer >= 1, got 0"),
        (["--env", "robot_start_pos=[100, 100]"], "robot_start_pos (100, 100) is off the field"),
        (["--env", "play_mode=NoSuchMode"], "unknown play_mode 'NoSuchMode'"),
        (["--env", "fall_penalty=high"], "fall_penalty must be a number, got 'high'"),
        (["--env", "observations=joint_pos"], "observations must be a list of component names"),
    ):
        out = tmp_path / "runs"
        res = CliRunner().invoke(
            app, ["train", "velocity-kick", "--timesteps", "64", "--out", str(out), *args]
        )
        assert res.exit_code == 1, res.output
        assert res.exception is None or isinstance(res.exception, SystemExit)
        errors = [ln for ln in res.output.splitlines() if ln.startswith("error:")]
        assert len(errors) == 1 and expected in errors[0], res.output
        assert "Traceback" not in res.output
        assert not out.exists() or not any(out.iterdir())


def test_eval_refuses_zero_episodes_and_names_the_file_it_writes(ppo_run):
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    res = CliRunner().invoke(app, ["eval", str(ppo_run), "--episodes", "0"])
    assert res.exit_code == 1 and "error: episodes must be >= 1, got 0" in res.output
    missing = ppo_run / "checkpoints" / "model_999_steps.zip"
    res = CliRunner().invoke(app, ["eval", str(ppo_run), "--checkpoint", str(missing)])
    assert res.exit_code == 1 and f"error: checkpoint {missing} does not exist" in res.output
    out = invoke(["eval", ppo_run, "--episodes", 1]).stdout
    assert f"written: {ppo_run / 'eval.json'}" in out


def test_agent_refuses_a_garbage_onnx_file_in_one_line(tmp_path):
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    bad = tmp_path / "bad.onnx"
    bad.write_text("garbage")
    res = CliRunner().invoke(app, ["agent", str(bad), "--port", "1"])
    assert res.exit_code == 1
    assert f"error: {bad} is not a valid ONNX policy" in res.output
    assert "Traceback" not in res.output
    res = CliRunner().invoke(app, ["agent", str(bad), "--port", "70000"])
    assert res.exit_code == 1 and "error: port 70000 is not a port number" in res.output


@pytest.mark.parametrize(
    "env, expected",
    [({"MUJOCO_GL": "nosuch"}, "MUJOCO_GL=nosuch")],
)
def test_a_video_without_a_working_renderer_is_one_clear_error(ppo_run, tmp_path, env, expected):
    code = (
        "import sys; from robocup_gym.cli import main; "
        f"sys.argv=['robocup-gym','eval',{str(ppo_run)!r},'--episodes','1','--video',"
        f"{str(tmp_path / 'k.mp4')!r}]; main()"
    )
    res = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={**os.environ, **env},
        timeout=120,
    )
    assert res.returncode == 1
    assert "Traceback" not in res.stderr
    assert f"error: cannot render the video with {expected}" in res.stderr


# ------------------------------------------------------------------ one truth about a policy
def test_the_agent_over_the_wire_sees_and_does_what_eval_does(ppo_run, tmp_path):
    """The exported policy driven by ``robocup-gym agent`` against ``serve`` (monitor ground
    truth) starts from the same state, observes the same values and ends its episodes as the
    in-process evaluation does."""
    from robocup_gym.server import SimServer
    from robocup_gym.train.agent import run_onnx_agent
    from robocup_gym.train.evaluate import evaluate_run

    onnx = tmp_path / "p.onnx"
    invoke(["export", ppo_run, "--onnx", onnx])
    server = SimServer(
        0, 0, "127.0.0.1", sync=True, real_time=False, ground_truth=True, vision_noise=False
    )
    agent_port, monitor_port = server.start_in_thread()
    try:
        reports = run_onnx_agent(str(onnx), port=agent_port, monitor_port=monitor_port, episodes=2)
    finally:
        server.stop()
    summary = evaluate_run(ppo_run, episodes=2, seed=100_000, write=False)
    wire_dx = np.mean([r.ball_displacement[0] for r in reports])
    assert abs(wire_dx - summary["ball_dx_mean"]) < 0.05
    assert abs(np.mean([r.steps for r in reports]) - summary["length_mean"]) <= 2
    assert np.mean([r.fallen for r in reports]) == pytest.approx(summary["fall_rate"], abs=0.5)


@pytest.mark.parametrize(
    "args, expected",
    [
        (["train", "--timesteps", "abc"], "Invalid value for '--timesteps'"),
        (["eval"], "Missing argument 'run'"),
        (["nosuchcommand"], "No such command 'nosuchcommand'"),
        (["train", "--nosuch"], "No such option: --nosuch"),
    ],
)
def test_usage_errors_are_one_line(args, expected):
    res = subprocess.run(
        [sys.executable, "-m", "robocup_gym.cli", *args],
        capture_output=True,
        text=True,
        timeout=60,
    )
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1, res.stderr
    assert lines[0].startswith("error: ") and expected in lines[0] and "--help" in lines[0]

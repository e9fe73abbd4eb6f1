"""Stable-Baselines3 callbacks of a training run: statistics, live progress, checkpoints, evals."""

from __future__ import annotations

import csv
import json
import time
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

from robocup_gym.train.metrics import episode_record, summarize

CURVE_FIELDS = (
    "steps",
    "wall_s",
    "episodes",
    "ep_return_mean",
    "ep_length_mean",
    "ball_dx_mean",
    "ball_distance_mean",
    "fall_rate",
    "steps_per_s",
)


def _fmt(x: float | None, spec: str = ".2f") -> str:
    return "–" if x is None else format(x, spec)


class EpisodeStatsCallback(BaseCallback):
    """Collects finished episodes (return, length, ball displacement, falls) from the infos.

    Keeps the most recent ``window`` episodes for running means, logs them to TensorBoard
    (``kick/*``) and appends a row to ``curve_path`` (CSV: the learning curve against steps and
    wall-clock) at most every ``curve_every`` steps.
    """

    def __init__(
        self,
        curve_path: Path | None = None,
        curve_every: int = 5_000,
        window: int = 100,
        wall_offset_s: float = 0.0,
    ) -> None:
        super().__init__()
        self.curve_path = curve_path
        self.curve_every = max(1, int(curve_every))
        self.recent: deque[dict[str, float]] = deque(maxlen=window)
        self.episodes = 0
        self.wall_offset_s = wall_offset_s
        self._t0 = time.perf_counter()
        self._ep_returns: np.ndarray | None = None
        self._ep_lengths: np.ndarray | None = None
        self._last_row_steps = -1
        self._rate_t = self._t0
        self._rate_steps = 0
        self.steps_per_s = 0.0

    # ------------------------------------------------------------------ SB3 hooks
    def _on_training_start(self) -> None:
        self._t0 = time.perf_counter()
        self._rate_t = self._t0
        self._rate_steps = self.num_timesteps
        n = self.training_env.num_envs
        self._ep_returns = np.zeros(n)
        self._ep_lengths = np.zeros(n, dtype=int)
        if self.curve_path is not None and not self.curve_path.exists():
            with self.curve_path.open("w", newline="") as f:
                csv.writer(f).writerow(CURVE_FIELDS)

    def _on_step(self) -> bool:
        rewards = self.locals.get("rewards")
        dones = self.locals.get("dones")
        infos = self.locals.get("infos") or []
        if rewards is not None and self._ep_returns is not None:
            self._ep_returns += np.asarray(rewards, dtype=float).reshape(-1)
            self._ep_lengths += 1
        if dones is not None:
            for i in np.flatnonzero(np.asarray(dones)):
                info = infos[i] if i < len(infos) else {}
                ep = info.get("episode") or {}
                ret = ep.get("r", self._ep_returns[i] if self._ep_returns is not None else 0.0)
                length = ep.get("l", self._ep_lengths[i] if self._ep_lengths is not None else 0)
                self.recent.append(episode_record(info, ret, int(length)))
                self.episodes += 1
                if self._ep_returns is not None:
                    self._ep_returns[i] = 0.0
                    self._ep_lengths[i] = 0
        now = time.perf_counter()
        if now - self._rate_t >= 2.0:
            self.steps_per_s = (self.num_timesteps - self._rate_steps) / (now - self._rate_t)
            self._rate_t, self._rate_steps = now, self.num_timesteps
        return True

    def _on_rollout_end(self) -> None:
        s = self.summary()
        for key in ("ball_dx_mean", "ball_distance_mean", "fall_rate"):
            if s[key] is not None:
                self.logger.record(f"kick/{key}", s[key])
        if self.num_timesteps - self._last_row_steps >= self.curve_every:
            self.write_row()

    def _on_training_end(self) -> None:
        if self.num_timesteps != self._last_row_steps:
            self.write_row()

    # ------------------------------------------------------------------ helpers
    @property
    def wall_s(self) -> float:
        return self.wall_offset_s + time.perf_counter() - self._t0

    def summary(self) -> dict[str, Any]:
        return summarize(self.recent)

    def overall_steps_per_s(self) -> float:
        elapsed = time.perf_counter() - self._t0
        return 0.0 if elapsed <= 0 else (self.num_timesteps - self._start_steps) / elapsed

    def _init_callback(self) -> None:
        self._start_steps = self.num_timesteps

    def write_row(self) -> None:
        self._last_row_steps = self.num_timesteps
        if self.curve_path is None:
            return
        s = self.summary()
        row = [
            self.num_timesteps,
            round(self.wall_s, 2),
            self.episodes,
            s["return_mean"],
            s["length_mean"],
            s["ball_dx_mean"],
            s["ball_distance_mean"],
            s["fall_rate"],
            round(self.overall_steps_per_s(), 1),
        ]
        with self.curve_path.open("a", newline="") as f:
            csv.writer(f).writerow(["" if v is None else v for v in row])


class RichProgressCallback(BaseCallback):
    """A rich progress bar: steps, steps/s, recent mean episode reward and ball displacement.

    On a terminal it is a live bar; otherwise (logs, CI) a plain line every ``log_every_s``.
    """

    def __init__(
        self,
        stats: EpisodeStatsCallback,
        total_timesteps: int,
        description: str = "training",
        console=None,
        log_every_s: float = 30.0,
    ) -> None:
        super().__init__()
        from rich.console import Console

        self.stats = stats
        self.total = int(total_timesteps)
        self.description = description
        self.console = console or Console()
        self.log_every_s = log_every_s
        self.progress = None
        self.task = None
        self._last_update = 0.0
        self._last_log = 0.0

    def _fields(self) -> dict[str, str]:
        s = self.stats.summary()
        return {
            # the recent rate once a 2-s window has passed, the overall rate before
            "sps": f"{self.stats.steps_per_s or self.stats.overall_steps_per_s():,.0f}",
            "rew": _fmt(s["return_mean"]),
            "dx": _fmt(s["ball_dx_mean"]),
            "eps": f"{self.stats.episodes:,}",
        }

    def _on_training_start(self) -> None:
        from rich.progress import (
            BarColumn,
            Progress,
            SpinnerColumn,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self._last_log = time.perf_counter()
        if not self.console.is_terminal:
            self.console.print(
                f"{self.description}: {self.num_timesteps:,}/{self.total:,} steps (progress "
                f"every {self.log_every_s:.0f} s)"
            )
            return
        self.progress = Progress(
            SpinnerColumn(),
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            TextColumn("{task.completed:,.0f}/{task.total:,.0f}"),
            TextColumn("[cyan]{task.fields[sps]} steps/s"),
            TextColumn("reward [green]{task.fields[rew]}"),
            TextColumn("ball Δx [magenta]{task.fields[dx]} m"),
            TextColumn("eps {task.fields[eps]}"),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
            console=self.console,
            refresh_per_second=4,
        )
        self.progress.start()
        self.task = self.progress.add_task(
            self.description, total=self.total, completed=self.num_timesteps, **self._fields()
        )

    def _on_step(self) -> bool:
        now = time.perf_counter()
        if self.progress is not None:
            if now - self._last_update >= 0.25:
                self._last_update = now
                self.progress.update(self.task, completed=self.num_timesteps, **self._fields())
        elif now - self._last_log >= self.log_every_s:
            self._last_log = now
            self.console.print(self.line())
        return True

    def line(self) -> str:
        f = self._fields()
        pct = 100.0 * self.num_timesteps / max(self.total, 1)
        return (
            f"{self.description}: {self.num_timesteps:,}/{self.total:,} steps ({pct:.0f}%)  "
            f"{f['sps']} steps/s  reward {f['rew']}  ball Δx {f['dx']} m  episodes {f['eps']}  "
            f"{self.stats.wall_s:.0f} s"
        )

    def _on_training_end(self) -> None:
        if self.progress is not None:
            self.progress.update(self.task, completed=self.num_timesteps, **self._fields())
            self.progress.stop()
        else:
            self.console.print(self.line())


class TorchThreadsCallback(BaseCallback):
    """Torch uses ``rollout_threads`` while the environments run (so that its idle worker threads
    do not compete with the environment processes) and ``train_threads`` for the gradient steps.
    """

    def __init__(self, rollout_threads: int = 1, train_threads: int = 0) -> None:
        super().__init__()
        import torch

        self.rollout_threads = max(1, rollout_threads)
        self.train_threads = train_threads or torch.get_num_threads()

    def _on_rollout_start(self) -> None:
        import torch

        torch.set_num_threads(self.rollout_threads)

    def _on_rollout_end(self) -> None:
        import torch

        torch.set_num_threads(self.train_threads)

    def _on_step(self) -> bool:
        return True

    def _on_training_end(self) -> None:
        import torch

        torch.set_num_threads(self.train_threads)


class CheckpointCallback(BaseCallback):
    """Saves ``checkpoints/model_<steps>_steps.zip`` every ``every`` environment steps.

    Also keeps the newest ``vecnormalize.pkl`` (when observations are normalised) and, for
    off-policy algorithms, the newest replay buffer (``checkpoints/replay_buffer.pkl``) so that
    ``--resume`` continues exactly.
    """

    def __init__(self, directory: Path, every: int, save_replay_buffer: bool = False) -> None:
        super().__init__()
        self.directory = Path(directory)
        self.every = int(every)
        self.save_replay_buffer = save_replay_buffer
        self._next = 0

    def _on_training_start(self) -> None:
        self.directory.mkdir(parents=True, exist_ok=True)
        self._next = (self.num_timesteps // self.every + 1) * self.every

    def _on_step(self) -> bool:
        if self.num_timesteps >= self._next:
            self.save()
            self._next = (self.num_timesteps // self.every + 1) * self.every
        return True

    def save(self) -> Path:
        path = self.directory / f"model_{self.num_timesteps}_steps.zip"
        self.model.save(path)
        vn = self.model.get_vec_normalize_env()
        if vn is not None:
            vn.save(str(self.directory / "vecnormalize.pkl"))
        if self.save_replay_buffer and hasattr(self.model, "save_replay_buffer"):
            self.model.save_replay_buffer(self.directory / "replay_buffer.pkl")
        return path


class PeriodicEvalCallback(BaseCallback):
    """Deterministic evaluation on a separate environment every ``every`` steps.

    Logs ``eval/*`` to TensorBoard and appends one JSON line per evaluation to ``log_path``.
    """

    def __init__(self, make_env, every: int, episodes: int, log_path: Path, seed: int = 10_000):
        super().__init__()
        self.make_env = make_env
        self.every = int(every)
        self.episodes = int(episodes)
        self.log_path = Path(log_path)
        self.seed = seed
        self.env = None
        self._next = 0
        self.last: dict[str, Any] | None = None

    def _on_training_start(self) -> None:
        self._next = (self.num_timesteps // self.every + 1) * self.every

    def _on_step(self) -> bool:
        if self.num_timesteps >= self._next:
            self._next = (self.num_timesteps // self.every + 1) * self.every
            self.evaluate()
        return True

    def evaluate(self) -> dict[str, Any]:
        from robocup_gym.train.evaluate import run_episodes

        if self.env is None:
            self.env = self.make_env()
        obs_norm = self.model.get_vec_normalize_env()
        records = run_episodes(
            self.model,
            self.env,
            self.episodes,
            seed=self.seed,
            obs_normalizer=obs_norm.normalize_obs if obs_norm is not None else None,
        )
        s = summarize(records)
        for key in ("return_mean", "ball_dx_mean", "ball_distance_mean", "fall_rate"):
            if s[key] is not None:
                self.logger.record(f"eval/{key}", s[key])
        self.last = {"steps": self.num_timesteps, **s}
        with self.log_path.open("a") as f:
            f.write(json.dumps(self.last) + "\n")
        return self.last

    def _on_training_end(self) -> None:
        if self.env is not None:
            self.env.close()
            self.env = None

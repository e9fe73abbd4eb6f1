"""Stable-Baselines3 callbacks of a training run: statistics, live progress, checkpoints, evals."""

from __future__ import annotations

import contextlib
import csv
import json
import time
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

from robocup_gym.train.metrics import episode_record, summarize


def task_measure(summary: dict[str, Any]) -> str:
    """The task's own measure in a summary, for the training display: a team's goal difference
    against the scripted team and its rating, GetUp's success rate, Walk's forward speed and
    tracking error, Dribble's ball speed toward the target, TargetKick's errors, else (the other
    kicks) the ball's x-displacement."""
    if "rating_mu" in summary:  # a team: its recent games
        return (
            f"vs scripted {_fmt(summary.get('goal_difference_vs_scripted'), '+.2f')} goals/game"
            f" · rating {_fmt(summary.get('rating_mu'), '.1f')}"
        )
    if summary.get("success_rate") is not None:
        return f"success {_fmt(summary['success_rate'])}"
    if summary.get("ball_speed_to_target_mps_mean") is not None:  # Dribble
        return (
            f"ball → target {_fmt(summary['ball_speed_to_target_mps_mean'])} m/s "
            f"(losses {_fmt(summary.get('losses_mean'), '.1f')})"
        )
    if summary.get("distance_error_mean") is not None:  # TargetKick
        return (
            f"distance error {_fmt(summary['distance_error_mean'])} · direction error "
            f"{_fmt(summary.get('direction_error_deg_mean'), '.1f')}°"
        )
    if summary.get("forward_speed_mps_mean") is not None:
        return (
            f"forward {_fmt(summary['forward_speed_mps_mean'])} m/s "
            f"(error {_fmt(summary.get('forward_error_mps_mean'))})"
        )
    return f"ball Δx {_fmt(summary.get('ball_dx_mean'))} m"


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
    (``kick/*``; each reward term's mean episode sum as ``reward/<term>``, from
    ``info["reward_terms"]``) and appends a row to ``curve_path`` (CSV: the learning curve
    against steps and wall-clock) at most every ``curve_every`` steps.
    """

    def __init__(
        self,
        curve_path: Path | None = None,
        curve_every: int = 5_000,
        window: int = 100,
        wall_offset_s: float = 0.0,
        episodes_offset: int = 0,
        extra_fields: tuple[str, ...] = (),
        extra: Any = None,
    ) -> None:
        super().__init__()
        self.extra_fields = tuple(extra_fields)
        """More columns of ``curve_path``, after :data:`CURVE_FIELDS`, …"""
        self.extra = extra
        """… and what gives their values: ``extra() → {field: value}`` (a self-play run's
        games)."""
        self.curve_path = curve_path
        self.curve_every = max(1, int(curve_every))
        self.recent: deque[dict[str, float]] = deque(maxlen=window)
        self.recent_terms: deque[dict[str, float]] = deque(maxlen=window)
        """Each recent episode's reward summed by term."""
        self._ep_terms: list[dict[str, float]] = []
        self.episodes = int(episodes_offset)
        """Episodes finished in the whole run (a resumed run continues its earlier count)."""
        self.wall_offset_s = wall_offset_s
        self._start_steps = 0
        self._t0 = time.perf_counter()
        self._ep_returns: np.ndarray | None = None
        self._ep_lengths: np.ndarray | None = None
        self._last_row_steps = -1

    # ------------------------------------------------------------------ SB3 hooks
    def _on_training_start(self) -> None:
        # num_timesteps is the model's here (a resumed run's earlier steps included); in
        # _init_callback it is still 0, which made a resumed run's rate count its earlier steps
        self._t0 = time.perf_counter()
        self._start_steps = self.num_timesteps
        n = self.training_env.num_envs
        self._ep_returns = np.zeros(n)
        self._ep_lengths = np.zeros(n, dtype=int)
        if self.curve_path is not None and not self.curve_path.exists():
            with self.curve_path.open("w", newline="") as f:
                csv.writer(f).writerow(CURVE_FIELDS + self.extra_fields)

    def _on_step(self) -> bool:
        rewards = self.locals.get("rewards")
        dones = self.locals.get("dones")
        infos = self.locals.get("infos") or []
        if rewards is not None and self._ep_returns is not None:
            self._ep_returns += np.asarray(rewards, dtype=float).reshape(-1)
            self._ep_lengths += 1
        if len(self._ep_terms) < len(infos):
            self._ep_terms += [{} for _ in range(len(infos) - len(self._ep_terms))]
        for i, info in enumerate(infos):
            terms = info.get("reward_terms") if isinstance(info, dict) else None
            if terms:
                sums = self._ep_terms[i]
                for k, v in terms.items():
                    sums[k] = sums.get(k, 0.0) + float(v)
        if dones is not None:
            for i in np.flatnonzero(np.asarray(dones)):
                info = infos[i] if i < len(infos) else {}
                ep = info.get("episode") or {}
                ret = ep.get("r", self._ep_returns[i] if self._ep_returns is not None else 0.0)
                length = ep.get("l", self._ep_lengths[i] if self._ep_lengths is not None else 0)
                self.recent.append(episode_record(info, ret, int(length)))
                if i < len(self._ep_terms):
                    self.recent_terms.append(self._ep_terms[i])
                    self._ep_terms[i] = {}
                self.episodes += 1
                if self._ep_returns is not None:
                    self._ep_returns[i] = 0.0
                    self._ep_lengths[i] = 0
        return True

    def _on_rollout_end(self) -> None:
        s = self.summary()
        for key in ("ball_dx_mean", "ball_distance_mean", "fall_rate"):
            if s[key] is not None:
                self.logger.record(f"kick/{key}", s[key])
        for key in ("success_rate", "assist_share_mean"):  # GetUp; a run with an assist
            if s.get(key) is not None:
                self.logger.record(f"train/{key}", s[key])
        for term, mean in self.reward_term_means().items():
            self.logger.record(f"reward/{term}", mean)
        if self.num_timesteps - self._last_row_steps >= self.curve_every:
            self.write_row()

    def _on_training_end(self) -> None:
        if self.num_timesteps != self._last_row_steps:
            self.write_row()

    def reward_term_means(self) -> dict[str, float]:
        """Each reward term's mean episode sum over the recent episodes (an episode without
        the term counts 0)."""
        eps = list(self.recent_terms)
        names = sorted({k for e in eps for k in e})
        return {k: float(np.mean([e.get(k, 0.0) for e in eps])) for k in names}

    # ------------------------------------------------------------------ helpers
    @property
    def wall_s(self) -> float:
        return self.wall_offset_s + time.perf_counter() - self._t0

    def summary(self) -> dict[str, Any]:
        out = summarize(self.recent)
        if self.extra is not None:
            out.update(self.extra())
        return out

    def overall_steps_per_s(self) -> float:
        """Steps per second since this start (a resumed run's earlier steps not counted)."""
        elapsed = time.perf_counter() - self._t0
        return 0.0 if elapsed <= 0 else (self.num_timesteps - self._start_steps) / elapsed

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
        if self.extra_fields:
            values = self.extra() if self.extra is not None else {}
            row += [values.get(k) for k in self.extra_fields]
        with self.curve_path.open("a", newline="") as f:
            csv.writer(f).writerow(["" if v is None else v for v in row])


def format_duration(seconds: float | None) -> str:
    """``75`` → ``"1:15"``, ``3725`` → ``"1:02:05"``; ``None`` or not finite → ``"?"``."""
    if seconds is None or not np.isfinite(seconds) or seconds < 0:
        return "?"
    s = round(seconds)
    h, rest = divmod(s, 3600)
    m, sec = divmod(rest, 60)
    return f"{h}:{m:02d}:{sec:02d}" if h else f"{m}:{sec:02d}"


class RichProgressCallback(BaseCallback):
    """What a training run shows while it runs: progress, measured rate, labelled elapsed and
    remaining time, recent reward and ball displacement, and every periodic evaluation.

    The remaining time is the steps left divided by the rate measured since this start
    (evaluations and checkpoints included), so it settles instead of jumping with each rollout.
    Once ``estimate_after_s`` have passed it prints one line saying how long the whole run will
    take. On a terminal the display is two lines that fit the console's width (80 columns too);
    elsewhere (logs, CI) it prints a plain line every ``log_every_s`` seconds.
    """

    def __init__(
        self,
        stats: EpisodeStatsCallback,
        total_timesteps: int,
        description: str = "training",
        console=None,
        log_every_s: float = 30.0,
        estimate_after_s: float = 15.0,
    ) -> None:
        super().__init__()
        from rich.console import Console

        self.stats = stats
        self.total = int(total_timesteps)
        self.description = description
        self.console = console or Console()
        self.log_every_s = log_every_s
        self.estimate_after_s = estimate_after_s
        self.live = None
        self._t0 = time.perf_counter()
        self._start_steps = 0
        self._last_log = 0.0
        self._estimated = False

    # ------------------------------------------------------------------ measures
    def elapsed_s(self) -> float:
        """Wall-clock seconds since this start."""
        return time.perf_counter() - self._t0

    def rate(self) -> float:
        """Steps per second since this start (0 before the first step)."""
        elapsed = self.elapsed_s()
        done = self.num_timesteps - self._start_steps
        return done / elapsed if elapsed > 0 and done > 0 else 0.0

    def remaining_s(self) -> float | None:
        """Estimated seconds to ``total_timesteps`` at :meth:`rate`; ``None`` while unknown."""
        r = self.rate()
        if r <= 0:
            return None
        return max(0, self.total - self.num_timesteps) / r

    def parts(self) -> list[str]:
        """The status fields, most important first (a narrow display drops the last ones)."""
        s = self.stats.summary()
        left = self.remaining_s()
        return [
            f"{self.rate():,.0f} steps/s",
            f"elapsed {format_duration(self.elapsed_s())}",
            f"left ~{format_duration(left)}" if left is not None else "left ?",
            f"reward {_fmt(s['return_mean'])}",
            task_measure(s),
            f"episodes {self.stats.episodes:,}",
        ]

    def line(self, width: int | None = None) -> str:
        """One plain status line (for logs), cut at field boundaries to ``width`` if given."""
        pct = 100.0 * self.num_timesteps / max(self.total, 1)
        head = f"{self.description} {pct:3.0f}% {self.num_timesteps:,}/{self.total:,}"
        return _fit([head, *self.parts()], width)

    # ------------------------------------------------------------------ printing
    def say(self, text: str) -> None:
        """Print a line above the live display (or as a plain line); never raises (a closed
        terminal must not stop training or its final save)."""
        with contextlib.suppress(Exception):  # e.g. EIO after the terminal went away
            self.console.print(text, highlight=False)

    def report_eval(self, result: dict[str, Any]) -> None:
        """Show one periodic evaluation (called by :class:`PeriodicEvalCallback`)."""
        self.say(
            f"eval at {result['steps']:,} steps ({result.get('episodes', '?')} episodes, "
            f"deterministic): {task_measure(result)}, fall rate "
            f"{_fmt(result.get('fall_rate'))}, return {_fmt(result.get('return_mean'))}"
        )

    def _estimate(self) -> None:
        left = self.remaining_s()
        if left is None:
            return
        self._estimated = True
        finish = time.strftime("%H:%M", time.localtime(time.time() + left))
        self.say(
            f"measured {self.rate():,.0f} steps/s: {self.total - self.num_timesteps:,} steps "
            f"left, about {format_duration(left)} (until ~{finish})"
        )

    # ------------------------------------------------------------------ SB3 hooks
    def _on_training_start(self) -> None:
        self._t0 = time.perf_counter()
        self._start_steps = self.num_timesteps
        self._last_log = self._t0
        self.say(
            f"{self.description}: {self.num_timesteps:,}/{self.total:,} steps; the time it "
            f"takes is estimated after {self.estimate_after_s:.0f} s"
            + ("" if self.console.is_terminal else f" (progress every {self.log_every_s:.0f} s)")
        )
        if self.console.is_terminal:
            from rich.live import Live

            self.live = Live(
                _Display(self), console=self.console, refresh_per_second=4, transient=False
            )
            self.live.start()

    def _on_step(self) -> bool:
        now = time.perf_counter()
        if not self._estimated and now - self._t0 >= self.estimate_after_s:
            self._estimate()
        if self.live is None and now - self._last_log >= self.log_every_s:
            self._last_log = now
            self.say(self.line())
        return True

    def _on_training_end(self) -> None:
        if self.live is not None:
            with contextlib.suppress(Exception):  # the terminal may be gone
                self.live.stop()
            self.live = None
        else:
            self.say(self.line())


def _fit(parts: list[str], width: int | None, sep: str = " · ") -> str:
    """``parts`` joined by ``sep``, dropping trailing parts that do not fit in ``width``."""
    out = parts[0]
    for p in parts[1:]:
        if width is not None and len(out) + len(sep) + len(p) > width:
            break
        out += sep + p
    return out if width is None else out[:width]


class _Display:
    """The live two-line display of :class:`RichProgressCallback`, laid out for the console's
    width at every refresh: ``description ━━━━━━╸─── 45% 450,000/1,000,000`` and the status."""

    def __init__(self, cb: RichProgressCallback) -> None:
        self.cb = cb

    def __rich_console__(self, console, options):
        from rich.progress_bar import ProgressBar
        from rich.table import Table
        from rich.text import Text

        cb = self.cb
        width = max(20, options.max_width)
        pct = 100.0 * cb.num_timesteps / max(cb.total, 1)
        counts = f" {pct:3.0f}% {cb.num_timesteps:,}/{cb.total:,}"
        desc = cb.description[: max(4, width // 4)] + " "
        grid = Table.grid(expand=True)
        grid.add_column(no_wrap=True)
        grid.add_column(ratio=1)
        grid.add_column(no_wrap=True)
        grid.add_row(
            Text(desc, style="bold"),
            ProgressBar(total=max(cb.total, 1), completed=min(cb.num_timesteps, cb.total)),
            Text(counts),
        )
        yield grid
        yield Text(_fit(cb.parts(), width - 1), style="cyan", no_wrap=True)


class StopOnSignal(BaseCallback):
    """Ends training cleanly at the next environment step once :attr:`signal` is set (by the
    SIGTERM/SIGHUP handlers of :func:`robocup_gym.train.trainer.train`), so that the run is
    saved exactly as after Ctrl-C."""

    def __init__(self) -> None:
        super().__init__()
        self.signal: int | None = None

    def _on_step(self) -> bool:
        return self.signal is None


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
    """Saves ``checkpoints/model_<steps>_steps.zip`` every ``every`` environment steps, and
    every ``every_s`` seconds of wall-clock time (so that a slow run has something saved within
    its first minutes; a time-triggered checkpoint replaces the previous time-triggered one).

    Also keeps the newest ``vecnormalize.pkl`` (when observations are normalised) and, for
    off-policy algorithms, the newest replay buffer (``checkpoints/replay_buffer.pkl``) so that
    ``--resume`` continues exactly. ``on_save(path, first)`` is told about every save.
    """

    def __init__(
        self,
        directory: Path,
        every: int,
        save_replay_buffer: bool = False,
        every_s: float = 0.0,
        on_save=None,
    ) -> None:
        super().__init__()
        self.directory = Path(directory)
        self.every = int(every)
        self.every_s = float(every_s)
        self.save_replay_buffer = save_replay_buffer
        self.on_save = on_save
        self._next = 0
        self._next_t = 0.0
        self._timed: Path | None = None
        self.saved = 0

    def _on_training_start(self) -> None:
        self.directory.mkdir(parents=True, exist_ok=True)
        if self.every > 0:
            self._next = (self.num_timesteps // self.every + 1) * self.every
        self._next_t = time.perf_counter() + self.every_s

    def _on_step(self) -> bool:
        if self.every > 0 and self.num_timesteps >= self._next:
            self.save()
            self._next = (self.num_timesteps // self.every + 1) * self.every
            self._next_t = time.perf_counter() + self.every_s
        elif self.every_s > 0 and time.perf_counter() >= self._next_t:
            previous = self._timed
            self._timed = self.save()
            if previous is not None and previous != self._timed:
                previous.unlink(missing_ok=True)
            self._next_t = time.perf_counter() + self.every_s
        return True

    def save(self) -> Path:
        path = self.directory / f"model_{self.num_timesteps}_steps.zip"
        self.model.save(path)
        vn = self.model.get_vec_normalize_env()
        if vn is not None:
            vn.save(str(self.directory / "vecnormalize.pkl"))
        if self.save_replay_buffer and hasattr(self.model, "save_replay_buffer"):
            self.model.save_replay_buffer(self.directory / "replay_buffer.pkl")
        self.saved += 1
        if self.on_save is not None:
            self.on_save(path, self.saved == 1)
        return path


class PeriodicEvalCallback(BaseCallback):
    """Deterministic evaluation on a separate environment every ``every`` steps.

    Logs ``eval/*`` to TensorBoard and appends one JSON line per evaluation to ``log_path``.
    """

    def __init__(
        self,
        make_env,
        every: int,
        episodes: int,
        log_path: Path,
        seed: int = 10_000,
        on_result=None,
    ):
        super().__init__()
        self.on_result = on_result
        """Called with each evaluation's result (e.g. to show it in the progress display)."""
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
        from robocup_gym.train.episodes import run_episodes

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
        if self.on_result is not None:
            self.on_result(self.last)
        return self.last

    def _on_training_end(self) -> None:
        if self.env is not None:
            self.env.close()
            self.env = None

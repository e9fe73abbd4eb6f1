"""The paper's three experiments, reproduced on the embedded simulator, and the same kind of
figures for the locomotion tasks (:func:`run_locomotion`: Walk and GetUp learning curves).

1. ``algos``: PPO vs SAC on VelocityKick, each with fewer and more parallel workers;
2. ``tasks``: SimpleKick vs VelocityKick (PPO);
3. ``workers``: wall-clock time of a fixed PPO training budget against the number of workers.

Each figure is a CSV (long format, one row per curve point) and a PNG. Runs are ordinary run
folders under ``<out>/runs/`` (TensorBoard logs and models included), so ``robocup-gym eval`` works
on every one of them; a run that already finished is reused, so an interrupted reproduction
continues where it stopped.

Scales: ``quick`` keeps the whole reproduction under ~30 minutes on a 2-core machine (short runs,
one seed: shapes of the curves, not the paper's final numbers); ``full`` is the paper's budget
(5M steps per run, 3 seeds) and needs a large machine or a lot of patience.
"""

from __future__ import annotations

import csv
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from robocup_gym.backends import DEFAULT_ENGINE, ENGINES
from robocup_gym.train.config import TrainConfig
from robocup_gym.train.run import load_run


@dataclass(frozen=True)
class Scale:
    timesteps: int
    """Steps per run of the ``algos`` figure."""
    task_timesteps: int
    """Steps per run of the ``tasks`` figure (SimpleKick waits 200 cycles per episode)."""
    algo_envs: tuple[int, ...]
    """Numbers of parallel environments compared in the ``algos`` figure."""
    task_envs: int
    worker_counts: tuple[int, ...]
    worker_timesteps: int
    seeds: int
    eval_episodes: int = 5
    checkpoints: int = 4
    extra: dict[str, Any] = field(default_factory=dict)


SCALES: dict[str, Scale] = {
    "quick": Scale(
        timesteps=60_000,
        task_timesteps=40_000,
        algo_envs=(4, 16),
        task_envs=16,
        worker_counts=(1, 2, 4, 8),
        worker_timesteps=12_000,
        seeds=1,
    ),
    "full": Scale(
        timesteps=5_000_000,
        task_timesteps=5_000_000,
        algo_envs=(16, 32),
        task_envs=16,
        worker_counts=(1, 2, 4, 8, 16, 32),
        worker_timesteps=200_000,
        seeds=3,
        eval_episodes=10,
        checkpoints=10,
    ),
}

FIGURES = ("algos", "tasks", "workers")
CURVE_COLUMNS = (
    "figure",
    "label",
    "seed",
    "steps",
    "wall_s",
    "ball_dx_mean",
    "return_mean",
    "fall_rate",
)


@dataclass
class RunSpec:
    name: str
    config: TrainConfig


def _finished(run_dir: Path, timesteps: int) -> bool:
    if not (run_dir / "model.zip").exists() or not (run_dir / "progress.csv").exists():
        return False
    rows = _read_curve(run_dir)
    return bool(rows) and rows[-1]["steps"] >= timesteps


def _read_curve(run_dir: Path) -> list[dict[str, float]]:
    rows = []
    with (run_dir / "progress.csv").open() as f:
        for row in csv.DictReader(f):
            rows.append(
                {k: (float(v) if v not in ("", None) else float("nan")) for k, v in row.items()}
            )
    return rows


def _run(spec: RunSpec, root: Path, console) -> Path:
    """Train one run unless a finished one exists; returns its folder."""
    from robocup_gym.train.trainer import train

    run_dir = root / spec.name
    if _finished(run_dir, spec.config.timesteps):
        console.print(f"[dim]reusing finished run {run_dir}[/dim]")
        return run_dir
    if (run_dir / "config.yaml").exists() and (run_dir / "model.zip").exists():
        train(resume=run_dir, console=console)
    else:
        train(spec.config, run_dir=run_dir, console=console, log_every_s=60.0)
    return run_dir


def _base(scale: Scale, **kw: Any) -> TrainConfig:
    steps = kw.get("timesteps", scale.timesteps)
    freq = max(steps // scale.checkpoints, 1)
    return TrainConfig(
        checkpoint_freq=freq, eval_freq=freq, eval_episodes=scale.eval_episodes, **kw
    )


def plan(
    scale: Scale, seeds: int, only: list[str] | None = None, backend: str = DEFAULT_ENGINE
) -> dict[str, list[RunSpec]]:
    """The runs of each figure (a run shared by two figures appears in both), all on
    ``backend``."""
    figs = [f for f in FIGURES if not only or f in only]
    out: dict[str, list[RunSpec]] = {}
    if "algos" in figs:
        out["algos"] = [
            RunSpec(
                f"velocity-kick-{algo}-{n}envs-s{s}",
                _base(
                    scale,
                    task="velocity-kick",
                    algo=algo,
                    n_envs=n,
                    seed=s,
                    timesteps=scale.timesteps,
                    backend=backend,
                ),
            )
            for algo in ("ppo", "sac")
            for n in scale.algo_envs
            for s in range(seeds)
        ]
    if "tasks" in figs:
        out["tasks"] = [
            RunSpec(
                f"{task}-ppo-{scale.task_envs}envs-s{s}-t{scale.task_timesteps}",
                _base(
                    scale,
                    task=task,
                    algo="ppo",
                    n_envs=scale.task_envs,
                    seed=s,
                    timesteps=scale.task_timesteps,
                    backend=backend,
                ),
            )
            for task in ("simple-kick", "velocity-kick")
            for s in range(seeds)
        ]
    if "workers" in figs:
        out["workers"] = [
            RunSpec(
                f"workers-velocity-kick-ppo-{n}workers",
                TrainConfig(
                    task="velocity-kick",
                    algo="ppo",
                    n_envs=n,
                    n_workers=n,
                    seed=0,
                    timesteps=scale.worker_timesteps,
                    checkpoint_freq=0,
                    eval_freq=0,
                    backend=backend,
                ),
            )
            for n in scale.worker_counts
        ]
    return out


def _label(fig: str, cfg: TrainConfig) -> str:
    if fig == "algos":
        return f"{cfg.algo.upper()}, {cfg.n_envs} workers"
    if fig == "tasks":
        return {"simple-kick": "SimpleKick", "velocity-kick": "VelocityKick"}.get(
            cfg.task, cfg.task
        )
    return f"{cfg.n_envs} workers"


def _write_curves(fig: str, runs: list[Path], path: Path) -> list[dict[str, Any]]:
    rows = []
    for run_dir in runs:
        cfg = load_run(run_dir).config
        for r in _read_curve(run_dir):
            rows.append(
                {
                    "figure": fig,
                    "label": _label(fig, cfg),
                    "seed": cfg.seed,
                    "steps": int(r["steps"]),
                    "wall_s": r["wall_s"],
                    "ball_dx_mean": r["ball_dx_mean"],
                    "return_mean": r["ep_return_mean"],
                    "fall_rate": r["fall_rate"],
                }
            )
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=CURVE_COLUMNS)
        w.writeheader()
        w.writerows(rows)
    return rows


def _plot_curves(rows: list[dict[str, Any]], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    labels = list(dict.fromkeys(r["label"] for r in rows))
    for label in labels:
        mine = [r for r in rows if r["label"] == label]
        seeds = sorted({r["seed"] for r in mine})
        max_steps = min(max(r["steps"] for r in mine if r["seed"] == s) for s in seeds)
        grid = np.linspace(0, max_steps, 100)
        for ax, key in zip(axes, ("ball_dx_mean", "return_mean"), strict=True):
            ys = []
            for s in seeds:
                pts = sorted((r["steps"], r[key]) for r in mine if r["seed"] == s)
                xs = np.array([p[0] for p in pts], float)
                vs = np.array([p[1] for p in pts], float)
                ok = np.isfinite(vs)
                if ok.sum() >= 1:
                    ys.append(np.interp(grid, xs[ok], vs[ok]))
            if not ys:
                continue
            ys = np.array(ys)
            mean = ys.mean(axis=0)
            (line,) = ax.plot(grid, mean, label=label)
            if len(ys) > 1:
                std = ys.std(axis=0)
                ax.fill_between(grid, mean - std, mean + std, alpha=0.2, color=line.get_color())
    axes[0].set_ylabel("mean ball x-displacement (m)")
    axes[1].set_ylabel("mean episode return")
    for ax in axes:
        ax.set_xlabel("environment steps")
        ax.grid(alpha=0.3)
        ax.legend()
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _workers_table(runs: list[Path], path: Path) -> list[dict[str, Any]]:
    rows = []
    for run_dir in runs:
        cfg = load_run(run_dir).config
        curve = _read_curve(run_dir)
        last = curve[-1]
        rows.append(
            {
                "workers": cfg.n_envs,
                "steps": int(last["steps"]),
                "wall_s": last["wall_s"],
                "steps_per_s": last["steps"] / last["wall_s"] if last["wall_s"] > 0 else None,
            }
        )
    rows.sort(key=lambda r: r["workers"])
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=("workers", "steps", "wall_s", "steps_per_s"))
        w.writeheader()
        w.writerows(rows)
    return rows


def _plot_workers(rows: list[dict[str, Any]], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    w = [r["workers"] for r in rows]
    axes[0].plot(w, [r["wall_s"] for r in rows], "o-")
    axes[0].set_ylabel(f"wall-clock time for {rows[0]['steps']:,} steps (s)")
    axes[1].plot(w, [r["steps_per_s"] for r in rows], "o-")
    axes[1].set_ylabel("environment steps per second")
    for ax in axes:
        ax.set_xlabel("number of workers")
        ax.set_xscale("log", base=2)
        ax.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def run_paper(
    scale: str | Scale = "quick",
    out: str | Path = "runs/paper",
    *,
    only: list[str] | None = None,
    seeds: int | None = None,
    timesteps: int | None = None,
    engine: str = DEFAULT_ENGINE,
    console=None,
) -> dict[str, Any]:
    """Run (or reuse) every run of the chosen figures, on the physics ``engine``, and write
    their CSVs and PNGs.

    Returns a summary: the files written and, per curve, the final mean ball x-displacement.
    """
    from rich.console import Console

    console = console or Console()
    if isinstance(scale, str):
        name = scale
        if scale not in SCALES:
            raise ValueError(f"unknown scale {scale!r}; choose one of {', '.join(SCALES)}")
        scale = SCALES[scale]
    else:
        name = "custom"
    if only:
        bad = sorted(set(only) - set(FIGURES))
        if bad:
            raise ValueError(f"unknown figure(s) {bad}; choose from {', '.join(FIGURES)}")
    if timesteps is not None:
        scale = Scale(
            **{
                **scale.__dict__,
                "timesteps": timesteps,
                "task_timesteps": timesteps,
                "worker_timesteps": min(scale.worker_timesteps, timesteps),
            }
        )
    n_seeds = seeds or scale.seeds
    out = Path(out)
    root = out / "runs"
    root.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}; choose one of {', '.join(ENGINES)}")
    figures = plan(scale, n_seeds, only, backend=engine)
    total = sum(len(v) for v in figures.values())
    console.print(f"[bold]paper experiments[/bold] ({name}): {total} runs → {out}")
    summary: dict[str, Any] = {"scale": name, "out": str(out), "figures": {}}
    for fig, specs in figures.items():
        dirs = [_run(spec, root, console) for spec in specs]
        csv_path, png_path = out / f"fig_{fig}.csv", out / f"fig_{fig}.png"
        if fig == "workers":
            rows = _workers_table(dirs, csv_path)
            _plot_workers(
                rows, png_path, "Wall-clock time vs number of workers (PPO, VelocityKick)"
            )
            result: dict[str, Any] = {r["workers"]: round(r["wall_s"], 1) for r in rows}
        else:
            rows = _write_curves(fig, dirs, csv_path)
            title = (
                "PPO vs SAC on VelocityKick"
                if fig == "algos"
                else "SimpleKick vs VelocityKick (PPO)"
            )
            _plot_curves(rows, png_path, title)
            result = {}
            for label in dict.fromkeys(r["label"] for r in rows):
                finals = [r for r in rows if r["label"] == label]
                last_steps = max(r["steps"] for r in finals)
                vals = [r["ball_dx_mean"] for r in finals if r["steps"] == last_steps]
                vals = [v for v in vals if np.isfinite(v)]
                result[label] = round(float(np.mean(vals)), 3) if vals else None
        summary["figures"][fig] = {"csv": str(csv_path), "png": str(png_path), "final": result}
        console.print(f"[green]figure {fig}[/green]: {png_path} ({json.dumps(result)})")
    summary["wall_s"] = round(time.perf_counter() - t0, 1)
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return summary


# ---------------------------------------------------------------------------------- locomotion
LOCOMOTION_TASKS = {
    "walk": ("forward_speed_mps_mean", "mean forward speed (m/s)", "Walk (PPO)"),
    "get-up": ("success_rate", "success rate", "GetUp (PPO)"),
}
"""Task → (the evaluation metric of its curve, its axis label, the figure's title)."""
LOCOMOTION_SCALES = {"quick": 100_000, "full": 5_000_000}
"""Steps per run of each scale."""
LOCOMOTION_COLUMNS = (
    "task",
    "seed",
    "steps",
    "wall_s",
    "metric",
    "value",
    "forward_error_mps",
    "return_mean",
    "fall_rate",
)


def _wall_at(run_dir: Path, steps: float) -> float:
    """Wall-clock seconds of a run when it reached ``steps`` (from its ``progress.csv``)."""
    curve = _read_curve(run_dir)
    xs = np.array([r["steps"] for r in curve], float)
    ys = np.array([r["wall_s"] for r in curve], float)
    return float(np.interp(steps, xs, ys)) if len(xs) else float("nan")


def _locomotion_rows(task: str, runs: list[Path]) -> list[dict[str, Any]]:
    """One row per periodic evaluation of each run (deterministic episodes)."""
    metric = LOCOMOTION_TASKS[task][0]
    rows = []
    for run_dir in runs:
        cfg = load_run(run_dir).config
        path = run_dir / "evaluations.jsonl"
        evals = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
        for e in evals:
            rows.append(
                {
                    "task": task,
                    "seed": cfg.seed,
                    "steps": int(e["steps"]),
                    "wall_s": round(_wall_at(run_dir, e["steps"]), 1),
                    "metric": metric,
                    "value": e.get(metric),
                    "forward_error_mps": e.get("forward_error_mps_mean"),
                    "return_mean": e.get("return_mean"),
                    "fall_rate": e.get("fall_rate"),
                }
            )
    return rows


def _plot_locomotion(rows: list[dict[str, Any]], path: Path, ylabel: str, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for seed in sorted({r["seed"] for r in rows}):
        mine = sorted((r for r in rows if r["seed"] == seed), key=lambda r: r["steps"])
        steps = [r["steps"] for r in mine]
        for ax, key in zip(axes, ("value", "return_mean"), strict=True):
            vals = [np.nan if r[key] is None else r[key] for r in mine]
            ax.plot(steps, vals, "o-", label=f"seed {seed}")
    axes[0].set_ylabel(ylabel)
    axes[1].set_ylabel("mean episode return")
    for ax in axes:
        ax.set_xlabel("environment steps")
        ax.grid(alpha=0.3)
        ax.legend()
    fig.suptitle(title + " — deterministic evaluations during training")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def run_locomotion(
    scale: str = "quick",
    out: str | Path = "runs/locomotion",
    *,
    tasks: list[str] | None = None,
    seeds: int = 1,
    timesteps: int | None = None,
    evaluations: int = 8,
    eval_episodes: int = 5,
    engine: str = DEFAULT_ENGINE,
    n_envs: int | None = None,
    algo_kwargs: dict[str, Any] | None = None,
    console=None,
) -> dict[str, Any]:
    """Train (or reuse) PPO on the locomotion tasks and write each task's learning curve as a
    CSV (one row per periodic evaluation: steps, wall-clock, the task's metric — Walk: mean
    forward speed, GetUp: success rate —, return, fall rate) and a PNG, in the paper figures'
    style. ``n_envs`` and ``algo_kwargs`` override the training defaults (PPO's settings).
    Returns a summary with the last evaluation of each run.

    Raises:
        ValueError: an unknown scale, task or engine.
    """
    from rich.console import Console

    console = console or Console()
    if scale not in LOCOMOTION_SCALES:
        raise ValueError(f"unknown scale {scale!r}; choose one of {', '.join(LOCOMOTION_SCALES)}")
    chosen = tasks or list(LOCOMOTION_TASKS)
    bad = sorted(set(chosen) - set(LOCOMOTION_TASKS))
    if bad:
        raise ValueError(f"unknown task(s) {bad}; choose from {', '.join(LOCOMOTION_TASKS)}")
    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}; choose one of {', '.join(ENGINES)}")
    if int(seeds) < 1 or int(evaluations) < 1:
        raise ValueError("seeds and evaluations must be >= 1")
    steps = int(timesteps or LOCOMOTION_SCALES[scale])
    out = Path(out)
    root = out / "runs"
    root.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    summary: dict[str, Any] = {"scale": scale, "out": str(out), "timesteps": steps, "tasks": {}}
    console.print(f"[bold]locomotion experiments[/bold] ({scale}): {chosen} → {out}")
    for task in chosen:
        specs = []
        for seed in range(int(seeds)):
            cfg = TrainConfig(
                task=task,
                algo="ppo",
                seed=seed,
                timesteps=steps,
                backend=engine,
                eval_freq=max(steps // evaluations, 1),
                eval_episodes=eval_episodes,
                checkpoint_freq=max(steps // evaluations, 1),
                **({} if n_envs is None else {"n_envs": int(n_envs)}),
            )
            if algo_kwargs:
                cfg = cfg.merged(algo_kwargs={**cfg.algo_kwargs, **algo_kwargs})
            specs.append(RunSpec(f"{task}-ppo-s{seed}-t{steps}", cfg))
        dirs = [_run(spec, root, console) for spec in specs]
        rows = _locomotion_rows(task, dirs)
        csv_path, png_path = out / f"fig_{task}.csv", out / f"fig_{task}.png"
        with csv_path.open("w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=LOCOMOTION_COLUMNS)
            w.writeheader()
            w.writerows(rows)
        _, ylabel, title = LOCOMOTION_TASKS[task]
        _plot_locomotion(rows, png_path, ylabel, title)
        last = [
            max((r for r in rows if r["seed"] == s), key=lambda r: r["steps"])
            for s in range(int(seeds))
            if any(r["seed"] == s for r in rows)
        ]
        summary["tasks"][task] = {
            "csv": str(csv_path),
            "png": str(png_path),
            "last": [
                {k: r[k] for k in ("seed", "steps", "wall_s", "metric", "value")} for r in last
            ],
        }
        console.print(f"[green]{task}[/green]: {png_path}")
    summary["wall_s"] = round(time.perf_counter() - t0, 1)
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return summary


TEAM_COLUMNS = (
    "run",
    "seed",
    "steps",
    "wall_s",
    "games",
    "goal_difference_vs_scripted",
    "win_rate_vs_scripted",
    "goals_for_mean",
    "goals_against_mean",
    "rating_mu",
    "rating_sigma",
)
"""Columns of a team learning curve (:func:`team_curves`)."""


def team_curves(runs: list[str | Path], out: str | Path) -> dict[str, Any]:
    """The learning curves of team runs (``robocup-gym train game-2v2 …``) from their
    ``progress.csv``: the goal difference and win rate against the scripted team and the
    TrueSkill rating against steps, as ``fig_team.csv`` and ``fig_team.png`` in ``out``.
    Returns where they went and each run's last row.

    Raises:
        ValueError: a folder that is not a team run.
    """
    from robocup_gym.train.tasks import is_team_task

    rows: list[dict[str, Any]] = []
    for run in runs:
        info = load_run(run)
        if not is_team_task(info.config.env_id):
            raise ValueError(f"{info.path} is a run of {info.config.task}, not of a team scenario")
        for r in _read_curve(info.path):
            row = {k: r.get(k) for k in TEAM_COLUMNS if k not in ("run", "seed")}
            rows.append({"run": info.path.name, "seed": info.config.seed, **row})
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path, png_path = out / "fig_team.csv", out / "fig_team.png"
    with csv_path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=TEAM_COLUMNS)
        w.writeheader()
        w.writerows(rows)
    _plot_team(rows, png_path)
    last = {}
    for row in rows:
        if row["run"] not in last or row["steps"] >= last[row["run"]]["steps"]:
            last[row["run"]] = row
    return {"csv": str(csv_path), "png": str(png_path), "last": list(last.values())}


def _plot_team(rows: list[dict[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for run in sorted({r["run"] for r in rows}):
        mine = sorted((r for r in rows if r["run"] == run), key=lambda r: r["steps"])
        steps = np.array([r["steps"] for r in mine], float)

        def col(key: str, rows_: list[dict[str, Any]] = mine) -> np.ndarray:
            return np.array([np.nan if r[key] is None else r[key] for r in rows_], float)

        axes[0].plot(steps, col("goal_difference_vs_scripted"), "o-", ms=3, label=run)
        mu, sigma = col("rating_mu"), col("rating_sigma")
        axes[1].plot(steps, mu, "-", label=run)
        axes[1].fill_between(steps, mu - sigma, mu + sigma, alpha=0.2)
    axes[0].axhline(0.0, color="grey", lw=0.8)
    axes[0].set_ylabel("goal difference per game against the scripted team")
    axes[1].set_ylabel("TrueSkill rating (μ ± σ)")
    for ax in axes:
        ax.set_xlabel("environment steps (player decisions)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("Team self-play: recent training games")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)

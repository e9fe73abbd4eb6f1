"""Does PPO really learn to kick? Train on VelocityKick and print the learning curve.

Trains with the paper's PPO hyperparameters (``robocup-gym train velocity-kick`` defaults) on
the default engine (SimSpark's physics on ODE; ``--engine mujoco`` for the fast approximation),
then prints the learning curve — mean ball x-displacement of the recent
training episodes against environment steps and wall-clock time — a final deterministic
evaluation, and, as the last line, one JSON summary.

Targets on the 2-core reference machine: 1M steps in <= 15 minutes; mean ball x-displacement
>= 1.5 m by 1M steps (rcssserver3d's scripted kick moves the ball 2.31 m).

    python benchmarks/learning.py                      # 1M steps (the benchmark)
    python benchmarks/learning.py --timesteps 100000   # a short learning-signal check
    python benchmarks/learning.py --engine mujoco      # the same on the MuJoCo engine
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import time
import warnings
from pathlib import Path

TARGET_STEPS = 1_000_000
TARGET_WALL_S = 15 * 60
TARGET_BALL_DX = 1.5
SCRIPTED_KICK_DX = 2.31


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--timesteps", type=int, default=TARGET_STEPS)
    p.add_argument("--n-envs", type=int, default=None, help="default: the paper's 16")
    p.add_argument("--n-workers", type=int, default=None, help="default: one per CPU core")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--task", default="velocity-kick")
    p.add_argument("--out", type=Path, default=Path("runs/benchmark"))
    p.add_argument("--eval-episodes", type=int, default=20)
    p.add_argument(
        "--hp",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a PPO hyperparameter (YAML value), repeatable",
    )
    p.add_argument(
        "--env",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="environment option (YAML value), repeatable",
    )
    p.add_argument("--engine", choices=("ode", "mujoco"), default="ode", help="physics engine")
    p.add_argument("--no-progress", action="store_true")
    args = p.parse_args(argv)

    import yaml
    from rich.console import Console

    from robocup_gym.train.config import TrainConfig
    from robocup_gym.train.evaluate import evaluate_run
    from robocup_gym.train.trainer import train

    def kv(items):
        return {k: yaml.safe_load(v) for k, _, v in (s.partition("=") for s in items)}

    console = Console(soft_wrap=True)
    cfg = TrainConfig(
        task=args.task,
        algo="ppo",
        timesteps=args.timesteps,
        seed=args.seed,
        backend=args.engine,
        checkpoint_freq=max(args.timesteps // 4, 1),
        eval_freq=0,
        algo_kwargs=kv(args.hp),
        env_kwargs=kv(args.env),
    )
    cfg = cfg.merged(n_envs=args.n_envs, n_workers=args.n_workers)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        result = train(
            cfg,
            out=args.out,
            console=console,
            progress=not args.no_progress,
            curve_every=max(args.timesteps // 50, 1000),
        )
        evaluation = evaluate_run(result.run_dir, episodes=args.eval_episodes)
    total_s = time.perf_counter() - t0

    rows = list(csv.DictReader((result.run_dir / "progress.csv").open()))
    console.print("\nlearning curve (recent training episodes, stochastic policy):")
    console.print(f"{'steps':>10} {'wall s':>8} {'ball Δx m':>10} {'return':>8} {'falls':>6}")

    def num(x):
        return float(x) if x not in ("", None) else math.nan

    for r in rows:
        console.print(
            f"{int(r['steps']):>10,} {num(r['wall_s']):>8.0f} "
            f"{num(r['ball_dx_mean']):>10.3f} {num(r['ep_return_mean']):>8.3f} "
            f"{num(r['fall_rate']):>6.2f}"
        )
    dx_curve = [num(r["ball_dx_mean"]) for r in rows]
    best = max((x for x in dx_curve if math.isfinite(x)), default=None)
    # wall-clock at 1M steps (or extrapolated from the measured speed for shorter runs)
    wall_1m = result.wall_s * TARGET_STEPS / max(result.timesteps, 1)
    summary = {
        "task": args.task,
        "engine": args.engine,
        "run": str(result.run_dir),
        "timesteps": result.timesteps,
        "n_envs": cfg.n_envs,
        "train_wall_s": round(result.wall_s, 1),
        "steps_per_s": round(result.timesteps / result.wall_s, 1),
        "wall_s_per_1m_steps": round(wall_1m, 1),
        "final_train_ball_dx_mean": result.recent.get("ball_dx_mean"),
        "best_train_ball_dx_mean": best,
        "eval_ball_dx_mean": evaluation["ball_dx_mean"],
        "eval_ball_dx_std": evaluation["ball_dx_std"],
        "eval_fall_rate": evaluation["fall_rate"],
        "eval_episodes": evaluation["episodes"],
        "target_wall_s_1m": TARGET_WALL_S,
        "target_ball_dx": TARGET_BALL_DX,
        "scripted_kick_ball_dx": SCRIPTED_KICK_DX,
        "meets_speed_target": wall_1m <= TARGET_WALL_S,
        "meets_kick_target": (
            args.timesteps >= TARGET_STEPS and (evaluation["ball_dx_mean"] or 0.0) >= TARGET_BALL_DX
        ),
        "total_wall_s": round(total_s, 1),
    }
    print(json.dumps(summary), flush=True)
    return summary


if __name__ == "__main__":
    main()

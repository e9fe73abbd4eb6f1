"""PPO's rollout schedules side by side: where a PPO run's time goes, measured in one run.

Trains PPO (the paper's hyperparameters, 16 VelocityKick environments in one worker per core)
for a few rollouts with each schedule in turn — SB3's lock-step loop (``pipeline_rollouts``
off); :class:`robocup_gym.train.pipelined.PipelinedPPO`'s pipelined rollouts with the learner
computing every step's actions (``worker_rollouts`` off); the same with overlapped updates
(``overlap_updates``); and the workers playing whole rollouts with a copy of the policy, updates
overlapped (``workers``, the default of ``robocup-gym train``) — alternating A/B/C/D/A/B/C/D so
that all see the same machine load. Prints per schedule the mean wall
time of a rollout (1,024 steps) and of the update (the gradient steps; with overlapped updates
the update runs during the next rollout, whose time then includes any wait for it, and
"update" is only the time to start it), then, as
the LAST line, one JSON object with all of them and the ratios ``pipelined_vs_lockstep``,
``overlapped_vs_lockstep`` and ``workers_vs_lockstep`` of the steps per second.

    python benchmarks/rollouts.py            # 4 × 2 runs of 30,720 steps, ~5 minutes
    python benchmarks/rollouts.py --quick    # 4 × 1 run of 3,072 steps (smoke test)
"""

from __future__ import annotations

import argparse
import json
import os
import time
import warnings

import numpy as np

SCHEDULES = {
    "lockstep": {"pipeline_rollouts": False, "overlap_updates": False},
    "pipelined": {"pipeline_rollouts": True, "overlap_updates": False, "worker_rollouts": False},
    "overlapped": {"pipeline_rollouts": True, "overlap_updates": True, "worker_rollouts": False},
    "workers": {"pipeline_rollouts": True, "overlap_updates": True, "worker_rollouts": True},
}


def measure(schedule: str, steps: int, n_envs: int, seed: int = 0) -> dict:
    """One short PPO run; mean seconds per rollout and per update, steps/s overall."""
    import torch
    from stable_baselines3.common.callbacks import BaseCallback

    from robocup_gym.train.config import PPO_PAPER_DEFAULTS
    from robocup_gym.train.pipelined import PipelinedPPO
    from robocup_gym.train.vecenv import make_vec_env

    class Phases(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.rollout: list[float] = []
            self.update: list[float] = []
            self.mark: float | None = None

        def _on_rollout_start(self) -> None:
            now = time.perf_counter()
            if self.mark is not None:
                self.update.append(now - self.mark)
            self.mark = now

        def _on_rollout_end(self) -> None:
            now = time.perf_counter()
            self.rollout.append(now - self.mark)
            self.mark = now

        def _on_step(self) -> bool:
            return True

    torch.set_num_threads(1)
    venv = make_vec_env("RobocupGym/VelocityKick-v0", n_envs, seed=seed)
    try:
        model = PipelinedPPO(
            "MlpPolicy",
            venv,
            seed=seed,
            device="cpu",
            **SCHEDULES[schedule],
            **PPO_PAPER_DEFAULTS,
        )
        phases = Phases()
        t0 = time.perf_counter()
        model.learn(steps, callback=phases)
        wall = time.perf_counter() - t0
    finally:
        venv.close()
    return {
        "rollout_s": float(np.mean(phases.rollout)),
        "update_s": float(np.mean(phases.update)) if phases.update else float("nan"),
        "steps_per_s": model.num_timesteps / wall,
    }


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="one short run per loop")
    p.add_argument("--steps", type=int, default=None, help="steps per run (default 30,720)")
    p.add_argument("--repeats", type=int, default=None, help="runs per loop (default 2)")
    p.add_argument("--n-envs", type=int, default=16)
    args = p.parse_args(argv)
    steps = args.steps or (3072 if args.quick else 30720)
    repeats = args.repeats or (1 if args.quick else 2)
    results: dict[str, list[dict]] = {name: [] for name in SCHEDULES}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(repeats):
            for name in SCHEDULES:
                r = measure(name, steps, args.n_envs)
                results[name].append(r)
                print(
                    f"{name:10s} rollout {r['rollout_s'] * 1e3:7.0f} ms  update "
                    f"{r['update_s'] * 1e3:7.0f} ms  {r['steps_per_s']:7.0f} steps/s",
                    flush=True,
                )
    out: dict = {"steps_per_run": steps, "repeats": repeats, "n_envs": args.n_envs}
    for name, runs in results.items():
        for key in ("rollout_s", "update_s", "steps_per_s"):
            out[f"{name}_{key}"] = round(float(np.mean([r[key] for r in runs])), 4)
    for name in ("pipelined", "overlapped", "workers"):
        out[f"{name}_vs_lockstep"] = round(
            out[f"{name}_steps_per_s"] / out["lockstep_steps_per_s"], 3
        )
    out["rollout_time_ratio"] = round(out["pipelined_rollout_s"] / out["lockstep_rollout_s"], 3)
    out["loadavg"] = [round(x, 2) for x in os.getloadavg()]
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

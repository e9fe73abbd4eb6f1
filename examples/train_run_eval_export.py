"""Train, evaluate and export a VelocityKick policy from Python (the CLI does the same).

    python examples/train_run_eval_export.py --timesteps 100000

Equivalent commands::

    robocup-gym train velocity-kick --timesteps 100000
    robocup-gym eval runs/velocity-kick-ppo-<time> --episodes 20
    robocup-gym export runs/velocity-kick-ppo-<time> --onnx kick.onnx
"""

from __future__ import annotations

import argparse
import json

from robocup_gym.train.config import TrainConfig
from robocup_gym.train.evaluate import evaluate_run
from robocup_gym.train.export import export_onnx
from robocup_gym.train.trainer import train


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--timesteps", type=int, default=100_000)
    p.add_argument("--n-envs", type=int, default=16)
    p.add_argument("--out", default="runs")
    args = p.parse_args()

    # The paper's PPO hyperparameters are the defaults; override any of them here.
    config = TrainConfig(
        task="velocity-kick",
        algo="ppo",
        n_envs=args.n_envs,
        timesteps=args.timesteps,
        env_kwargs={"wait_steps": 20},  # any VelocityKickConfig field
        algo_kwargs={"learning_rate": 1e-4},  # any PPO argument
    )
    result = train(config, out=args.out)
    summary = evaluate_run(result.run_dir, episodes=20)
    print(json.dumps({k: summary[k] for k in ("ball_dx_mean", "ball_dx_std", "fall_rate")}))
    meta = export_onnx(result.run_dir, result.run_dir / "policy.onnx")
    print("ONNX matches the policy to", meta["verification"]["max_abs_diff"])


if __name__ == "__main__":  # needed: the environments run in worker processes
    main()

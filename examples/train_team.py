"""Train a team from Python, export it and play it against the scripted team (the CLI does
the same).

    python examples/train_team.py --scenario penalty --timesteps 200000

Equivalent commands::

    robocup-gym train penalty --timesteps 200000
    robocup-gym export runs/penalty-ppo-<time> --onnx striker.onnx
    robocup-gym match striker.onnx scripted --scenario penalty --games 20
    robocup-gym experiments team runs/penalty-ppo-<time>
"""

from __future__ import annotations

import argparse
import json

from robocup_gym.soccer.match import play_match
from robocup_gym.train.config import TrainConfig
from robocup_gym.train.export import export_onnx
from robocup_gym.train.trainer import train


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--scenario", default="penalty", help="penalty, keepaway, game-2v2, …")
    p.add_argument("--timesteps", type=int, default=200_000)
    p.add_argument("--games", type=int, default=20)
    p.add_argument("--out", default="runs")
    args = p.parse_args()

    config = TrainConfig(
        task=args.scenario,
        n_envs=16,  # games in parallel; each player of the learning team is one environment
        timesteps=args.timesteps,
        env_kwargs={"ball_progress": 0.1},  # any soccer option (robocup_gym.soccer.env)
        selfplay={"scripted_share": 0.5, "snapshot_every": 50_000},  # the opponents
    )
    result = train(config, out=args.out)
    meta = export_onnx(result.run_dir, result.run_dir / "team.onnx")
    print("ONNX matches the policy to", meta["verification"]["max_abs_diff"])
    if args.scenario == "keepaway":
        return  # matches are games and penalties
    penalty = args.scenario == "penalty"
    players = None if penalty else int(args.scenario.split("-")[1].split("v")[0])
    summary = play_match(
        str(result.run_dir / "team.onnx"),
        "scripted",
        games=args.games,
        players=players,
        scenario="penalty" if penalty else "game",
    ).summary
    print(json.dumps(summary))


if __name__ == "__main__":  # needed: the games run in worker processes
    main()

"""How well does a policy dribble? The ball's speed toward the target, losses and falls.

Runs a Dribble policy (a run folder of ``robocup-gym train dribble``, ``pretrained:NAME``, or
``zero``: zero actions, the guide and the reference gait alone) deterministically for
``--episodes`` episodes per target: 5 m from the ball's start, straight ahead and 30° to either
side of the robot's heading. For each episode (10 s, or until the ball is within 0.5 m of the
target):

* the ball's speed toward the target: the distance it gained on the target / the time;
* losses: times the ball went more than 1 m from the torso, per 10 s;
* falls, and whether the ball reached the target.

``--robot-type N`` runs another Nao type; ``--backend rcssserver3d`` runs on a real server,
``--backend serve`` on a ``robocup-gym serve`` of its own.
Prints one line per target and, last, one JSON object (``ball_speed_to_target_mps`` and its
95 % interval ``ball_speed_to_target_ci95``, ``losses_per_10s``, ``falls``, ``goal_rate``,
``meets_target``: speed ≥ 0.6 m/s). The touches make single episodes chaotic: two policies
that differ by less than the interval are not told apart by these episodes.

    python benchmarks/dribble.py runs/dribble-ppo-<time> --episodes 5
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from robocup_gym.sim.physics import CYCLE_S

TARGET_DISTANCE_M = 5.0
TARGET_DIRECTIONS_DEG = (-30.0, 0.0, 30.0)


def episode(env, act, seed: int, direction_deg: float) -> dict:
    """One episode toward the target ``direction_deg`` from the ball's start."""
    u = env.unwrapped
    obs, _ = env.reset(seed=seed)
    start = u.episode_start
    ball = start.ball_pos[:2]
    angle = math.radians(start.pose.heading_deg + direction_deg)
    target = ball + TARGET_DISTANCE_M * np.array([math.cos(angle), math.sin(angle)])
    obs, _ = env.reset(
        seed=seed,
        options={"dribble_target": target, "ball_pos": start.ball_pos},
    )
    done, info, steps = False, {}, 0
    while not done:
        obs, _, terminated, truncated, info = env.step(act(obs))
        steps += 1
        done = terminated or truncated
    seconds = steps * CYCLE_S
    gap = float(info["ball_to_target_m"])
    return {
        "ball_speed_to_target_mps": (TARGET_DISTANCE_M - gap) / seconds,
        "losses_per_10s": info["losses"] * 10.0 / seconds,
        "fell": bool(info.get("fallen")),
        "goal": gap <= u.config.goal_radius,
    }


def summary(rows: list[dict]) -> dict:
    from robocup_gym.train.metrics import mean_ci95

    speeds = [r["ball_speed_to_target_mps"] for r in rows]
    return {
        "episodes": len(rows),
        "ball_speed_to_target_mps": float(np.mean(speeds)),
        "ball_speed_to_target_ci95": mean_ci95(speeds),
        "losses_per_10s": float(np.mean([r["losses_per_10s"] for r in rows])),
        "falls": int(sum(r["fell"] for r in rows)),
        "goal_rate": float(np.mean([r["goal"] for r in rows])),
    }


def main(argv: list[str] | None = None) -> dict:
    from robocup_gym.train.evaluate import add_benchmark_options, benchmark_policy_and_env

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_benchmark_options(parser, "Dribble", episodes=5)
    args = parser.parse_args(argv)
    # every episode ends at its one target (a Dribble-v1 policy goes on to the next in training)
    env, act = benchmark_policy_and_env(
        args, "RobocupGym/Dribble-v1", {"next_target_at_goal": False}
    )
    out: dict = {
        "policy": args.policy,
        "robot_type": env.unwrapped.config.robot_type,
        "episodes_per_target": args.episodes,
        "target_distance_m": TARGET_DISTANCE_M,
    }
    rows, per_target = [], []
    try:
        for k, direction in enumerate(TARGET_DIRECTIONS_DEG):
            these = [
                episode(env, act, args.seed + 1000 * k + e, direction) for e in range(args.episodes)
            ]
            rows += these
            res = {**summary(these), "direction_deg": direction}
            per_target.append(res)
            print(
                f"target {TARGET_DISTANCE_M:.0f} m at {direction:+.0f}°: ball toward it "
                f"{res['ball_speed_to_target_mps']:.2f} m/s, losses {res['losses_per_10s']:.1f} "
                f"per 10 s, falls {res['falls']}/{args.episodes}, reached "
                f"{res['goal_rate']:.0%}"
            )
    finally:
        env.close()
    out.update(summary(rows))
    out["per_target"] = per_target
    out["meets_target"] = out["ball_speed_to_target_mps"] >= 0.6
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

"""How well does a policy kick? Distance and direction against the command, and standing after.

Runs a kick policy deterministically (a run folder of ``robocup-gym train target-kick``,
``long-kick`` or ``velocity-kick``; ``pretrained:NAME``; or ``zero``, zero actions: the
kicks made for each command alone on TargetKick-v1, or with ``--task long-kick`` the long kick
alone on LongKick-v1) for ``--episodes`` episodes per command. A TargetKick
policy gets every command of a grid (distances 2, 3, 5, 7, 9 m × directions −45°, −30°, −15°,
0°, 15°, 30°, 45° of its heading; most directions between the aims of TargetKick-v1's
kicks); the other kicks have no command and are scored against the robot's heading. For each
episode:

* where the ball comes to rest, predicted from its position and velocity at the end of the
  episode's wait (``robocup_gym.sim.physics.ball_rest_point``; within 1 % of where it stops);
* the distance error as a fraction of the commanded distance, and the direction error, deg;
* whether the robot still stands after the wait (1 s after the episode for the kicks shipped);
* the time from the start to the ball's first movement (> 0.1 m/s).

``--robot-type N`` runs another Nao type; ``--backend rcssserver3d`` runs on a real server
(``RCSSSERVER3D`` names its binary), ``--backend serve`` on a ``robocup-gym serve`` of its own.
Prints one line per command and, last, one JSON object (``distance_error_median``,
``direction_error_deg_median``, ``stand_after_kick_rate``, ``ball_distance_median_m``,
``contact_time_s_median``, …).

    python benchmarks/kick.py runs/target-kick-ppo-<time> --episodes 5
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from robocup_gym.envs.tasks.target_kick import CONTACT_SPEED, kick_outcome
from robocup_gym.sim.physics import CYCLE_S

DISTANCES_M = (2.0, 3.0, 5.0, 7.0, 9.0)
DIRECTIONS_DEG = (-45.0, -30.0, -15.0, 0.0, 15.0, 30.0, 45.0)


def episode(env, act, seed: int, command: tuple[float, float] | None) -> dict:
    """One episode (the TargetKick ``command``, (m, deg), or none): the kick's outcome."""
    u = env.unwrapped
    options = {"kick_target": command} if command is not None else {}
    obs, _ = env.reset(seed=seed, options=options)
    heading = u.episode_start.pose.heading_deg
    contact, done, info = None, False, {}
    while not done:
        obs, _, terminated, truncated, info = env.step(act(obs))
        done = terminated or truncated
        if contact is None and float(np.linalg.norm(u.ball_vel)) > CONTACT_SPEED and not done:
            contact = u.episode_step
    target = np.array(command if command is not None else (1.0, 0.0), dtype=float)
    out = kick_outcome(u.ball_spawn_pos, u.ball_pos, u.ball_vel, heading, target)
    out["standing"] = not bool(info.get("fallen"))
    out["contact_time_s"] = None if contact is None else contact * CYCLE_S
    return out


def summary(rows: list[dict], commanded: bool) -> dict:
    """Medians and rates over ``rows`` of :func:`episode`."""
    contacts = [r["contact_time_s"] for r in rows if r["contact_time_s"] is not None]
    out = {
        "episodes": len(rows),
        "ball_distance_median_m": float(np.median([r["kick_distance_m"] for r in rows])),
        "direction_error_deg_median": float(np.median([r["direction_error_deg"] for r in rows])),
        "stand_after_kick_rate": float(np.mean([r["standing"] for r in rows])),
        "kicked_rate": len(contacts) / len(rows),
        "contact_time_s_median": float(np.median(contacts)) if contacts else None,
    }
    if commanded:
        out["distance_error_median"] = float(np.median([r["distance_error"] for r in rows]))
        out["miss_m_median"] = float(np.median([r["miss_m"] for r in rows]))
    return out


def main(argv: list[str] | None = None) -> dict:
    from robocup_gym.train.evaluate import add_benchmark_options, benchmark_policy_and_env

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_benchmark_options(parser, "kick", episodes=5)
    parser.add_argument(
        "--task",
        choices=("target-kick", "long-kick"),
        default="target-kick",
        help="the task a 'zero' policy runs: TargetKick-v1 (the kick made for each command) or "
        "LongKick-v1 (the long kick); a run folder or a shipped policy brings its own",
    )
    args = parser.parse_args(argv)
    env_id = "RobocupGym/LongKick-v1" if args.task == "long-kick" else "RobocupGym/TargetKick-v1"
    env, act = benchmark_policy_and_env(args, env_id)
    u = env.unwrapped
    commanded = "kick_target" in u.config.observations and u.config.randomise_kick_target
    commands = [(d, a) for d in DISTANCES_M for a in DIRECTIONS_DEG] if commanded else [None]
    out: dict = {
        "policy": args.policy,
        "task": type(u).__name__,
        "robot_type": u.config.robot_type,
        "episodes_per_command": args.episodes,
    }
    rows: list[dict] = []
    per_command = []
    try:
        for k, command in enumerate(commands):
            these = [
                episode(env, act, args.seed + 1000 * k + e, command) for e in range(args.episodes)
            ]
            rows += these
            res = summary(these, commanded)
            res["command"] = command
            per_command.append(res)
            said = "no command" if command is None else f"{command[0]:4.1f} m {command[1]:+5.1f}°"
            err = f"distance error {res['distance_error_median']:.0%}, " if commanded else ""
            print(
                f"{said}: ball {res['ball_distance_median_m']:.2f} m, {err}direction error "
                f"{res['direction_error_deg_median']:.1f}°, standing "
                f"{res['stand_after_kick_rate']:.0%}"
            )
    finally:
        env.close()
    out.update(summary(rows, commanded))
    out["per_command"] = per_command
    if commanded:
        out["meets_target"] = (
            out["distance_error_median"] <= 0.15
            and out["direction_error_deg_median"] <= 5.0
            and out["stand_after_kick_rate"] >= 0.9
        )
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

"""How well does a policy get up? Success rate and cycles to up, from the front and the back.

Runs a trained GetUp run's policy (``robocup-gym train getup`` folder) deterministically on the
default engine, ``--episodes`` episodes from each side. Success: torso above 0.28 m, inclined
less than 30°, for 1 s (the task's definition); ``cycles_to_up`` counts the agent cycles until
the robot got up for good (the target: ≥ 90 % within 80 cycles; the reference team takes ~66
from the front and ~55 from the back on rcssserver3d).

``zero`` runs a zero-action policy (on the Nao: the scripted get-up alone, GetUp's
``reference_motion``); ``pretrained:get-up`` the policy shipped with the package. The
environment is deterministic: an episode from the same lying pose repeats. Each episode starts
from one of the run's ``lying_poses`` drops per side (tilt and joints varied ±10°;
``--lying-poses N`` another number), or with ``--pose-from N`` from pose N + k (``--pose-from
32``: poses a run trained on up to 32 never met); ``--robot-type N`` another Nao type
(``--script-robot-type N``: under another type's scripted get-up), ``--backend rcssserver3d`` a
real server, ``--backend serve`` a ``robocup-gym serve`` of its own (reached as a real server
is). A policy meant for one side (``start_side`` ``front`` or ``back`` in its options) is
measured on that side only. Prints one line per side and, as the last line, one JSON object
(``success_rate``, ``cycles_to_up_median``, per side the same).

    python benchmarks/getup.py runs/get-up-ppo-<time> --episodes 20
"""

from __future__ import annotations

import argparse
import json

import numpy as np


def run(
    env, act, side: str, episodes: int, seed: int, within: int, pose_from: int | None = None
) -> dict:
    ups = []
    successes = 0
    for k in range(episodes):
        options: dict = {"start_side": side}
        if pose_from is not None:
            options["lying_pose"] = (pose_from + k) % 64
        obs, _ = env.reset(seed=seed + k, options=options)
        done = False
        info: dict = {}
        while not done:
            obs, _, terminated, truncated, info = env.step(act(obs))
            done = terminated or truncated
        if info.get("success"):
            ups.append(int(info["steps_to_up"]))
            successes += int(info["steps_to_up"] <= within)
    return {
        "success_rate": successes / episodes,
        "got_up": len(ups),
        "cycles_to_up_median": float(np.median(ups)) if ups else None,
        "episodes": episodes,
    }


def main(argv: list[str] | None = None) -> dict:
    from robocup_gym.train.evaluate import add_benchmark_options, benchmark_policy_and_env

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_benchmark_options(parser, "GetUp", episodes=20)
    parser.add_argument("--within", type=int, default=80, help="cycles that count as success")
    parser.add_argument(
        "--lying-poses",
        type=int,
        default=None,
        help="start from this many lying poses per side, drawn per episode (GetUpConfig."
        "lying_poses; default: the run's own, 1 = the one drop pose)",
    )
    parser.add_argument(
        "--pose-from",
        type=int,
        default=None,
        help="episode k starts from lying pose N + k (GetUp's lying_pose reset option; "
        "default: drawn among the run's lying_poses); 32 measures poses that training with "
        "lying_poses <= 32 never met",
    )
    parser.add_argument(
        "--script-robot-type",
        type=int,
        default=None,
        help="play this Nao type's scripted get-up under the policy (GetUpConfig."
        "script_robot_type; default: the run's own, for 'zero' the robot's type's)",
    )
    args = parser.parse_args(argv)
    overrides = {}
    if args.lying_poses is not None:
        overrides["lying_poses"] = args.lying_poses
    if args.script_robot_type is not None:
        overrides["script_robot_type"] = args.script_robot_type
    env, act = benchmark_policy_and_env(args, "RobocupGym/GetUp-v0", overrides)
    if args.robot_type is not None:
        overrides["robot_type"] = args.robot_type
    fixed = getattr(env.unwrapped.config, "start_side", "random")
    sides = (fixed,) if fixed in ("front", "back") else ("front", "back")
    out: dict = {"policy": args.policy, "within_cycles": args.within, **overrides}
    if args.pose_from is not None:
        out["pose_from"] = args.pose_from
    try:
        for side in sides:
            res = run(env, act, side, args.episodes, args.seed, args.within, args.pose_from)
            out[side] = res
            print(
                f"{side:5s}: success {res['success_rate']:.0%} within {args.within} cycles, "
                f"got up {res['got_up']}/{args.episodes}, median cycles to up "
                f"{res['cycles_to_up_median']}"
            )
    finally:
        env.close()
    both = [out[s]["success_rate"] for s in sides]
    out["sides"] = list(sides)
    out["success_rate"] = float(np.mean(both))
    medians = [out[s]["cycles_to_up_median"] for s in sides]
    out["cycles_to_up_median"] = (
        None if None in medians else float(np.mean([m for m in medians if m is not None]))
    )
    out["meets_target"] = min(both) >= 0.9  # for the sides the policy is meant for
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

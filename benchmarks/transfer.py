"""Does a trained policy kick on every simulator? The transfer table of one run.

Evaluates a run's policy (``robocup-gym train`` folder) deterministically, closed-loop, on each
physics engine of the in-process world (``ode``: SimSpark's own step, what rcssserver3d runs;
``mujoco``: the fast approximation) and, where one is installed (``RCSSSERVER3D`` or
``rcssserver3d`` on ``PATH``), on a real rcssserver3d. Prints one row per simulator and, as the
last line, one JSON object (``"<simulator>": {ball_dx_mean, ball_dx_std, fall_rate, …}``).

    python benchmarks/transfer.py runs/velocity-kick-ppo-<time> --episodes 10

The same numbers one at a time: ``robocup-gym eval RUN --engine ode|mujoco`` and
``robocup-gym eval RUN --backend rcssserver3d``.
"""

from __future__ import annotations

import argparse
import json
import sys

SIMULATORS = ("ode", "mujoco", "rcssserver3d")


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", help="a run folder written by robocup-gym train")
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--seed", type=int, default=100_000)
    parser.add_argument(
        "--only", action="append", choices=SIMULATORS, help="evaluate only on these (repeatable)"
    )
    args = parser.parse_args(argv)

    from robocup_gym.backends import BackendNotAvailableError
    from robocup_gym.train.evaluate import evaluate_run
    from robocup_gym.train.run import load_run

    info = load_run(args.run)
    out: dict = {
        "run": str(info.path),
        "trained_on": info.config.backend,
        "episodes": args.episodes,
    }
    print(f"trained on {info.config.backend}; {args.episodes} deterministic episodes each")
    print(f"{'evaluated on':14s} {'ball Δx (m)':>12s} {'std':>7s} {'fall rate':>10s}")
    for sim in args.only or SIMULATORS:
        try:
            s = evaluate_run(
                info.path, episodes=args.episodes, seed=args.seed, backend=sim, write=False
            )
        except (BackendNotAvailableError, OSError, RuntimeError) as exc:
            out[sim] = {"unavailable": str(exc).splitlines()[0]}
            print(f"{sim:14s} {'–':>12s}   ({out[sim]['unavailable'][:60]})")
            continue
        keep = ("ball_dx_mean", "ball_dx_std", "ball_distance_mean", "fall_rate", "length_mean")
        out[sim] = {k: s[k] for k in keep}
        print(f"{sim:14s} {s['ball_dx_mean']:12.3f} {s['ball_dx_std']:7.3f} {s['fall_rate']:10.2f}")
    sys.stdout.flush()
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

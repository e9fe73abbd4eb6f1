"""Speed of training on a real rcssserver3d: VelocityKick env steps per second with resets, and
the reset time.

Runs where a real rcssserver3d is installed (``RCSSSERVER3D`` or on ``PATH``; see
docs/rcssserver3d.md); elsewhere it says so and exits 0 with ``{"skipped": ...}``. One environment
on the ``rcssserver3d`` backend in launch mode (its own server, sync mode, real time off), random
actions, the episodes as the task defines them (40 steps, then the 20 wait cycles), every reset
and wait cycle counted in the wall time. Reference: the paper's code ran VelocityKick at ~208 env
steps/s with resets on this machine class (issue 19); the target is twice that, and resets within
30 ms.

    python benchmarks/real_server.py [--steps 2000] [--robot-type 0]

Prints one JSON object last: ``env_steps_per_s``, ``reset_ms_median``, ``reset_ms_p90``,
``reset_cycles_median``, ``episodes``, ``vs_paper`` (env_steps_per_s / 208).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

PAPER_STEPS_PER_S = 208.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--robot-type", type=int, default=0)
    args = parser.parse_args()

    import gymnasium

    import robocup_gym.envs  # noqa: F401  (registers the environments)
    from robocup_gym.backends.process import RcssServerNotFoundError, find_binary

    try:
        binary = find_binary()
    except RcssServerNotFoundError as exc:
        print(json.dumps({"skipped": str(exc).split(". ")[0]}))
        return
    env = gymnasium.make(
        "RobocupGym/VelocityKick-v0",
        backend="rcssserver3d",
        backend_options={"binary": binary},
        robot_type=args.robot_type,
    )
    try:
        backend = env.unwrapped.backend
        env.action_space.seed(0)
        env.reset(seed=0)  # the server's start and the first reset are not timed
        reset_ms, reset_cycles, episodes = [], [], 0
        start = time.perf_counter()
        for _ in range(args.steps):
            _, _, terminated, truncated, _ = env.step(env.action_space.sample())
            if terminated or truncated:
                t0 = time.perf_counter()
                env.reset()
                reset_ms.append((time.perf_counter() - t0) * 1e3)
                reset_cycles.append(backend.last_reset.cycles)
                episodes += 1
        elapsed = time.perf_counter() - start
    finally:
        env.close()
    rate = args.steps / elapsed
    print(
        json.dumps(
            {
                "binary": binary,
                "env_steps_per_s": round(rate, 1),
                "vs_paper": round(rate / PAPER_STEPS_PER_S, 2),
                "reset_ms_median": round(float(np.median(reset_ms)), 1) if reset_ms else None,
                "reset_ms_p90": round(float(np.percentile(reset_ms, 90)), 1) if reset_ms else None,
                "reset_cycles_median": float(np.median(reset_cycles)) if reset_cycles else None,
                "episodes": episodes,
            }
        )
    )


if __name__ == "__main__":
    main()

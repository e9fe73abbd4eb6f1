"""What ODE's own island threading gives: 22 robots on the ODE engine, one thread against two.

ODE 0.16 can step the islands of a world (groups of bodies joined by joints or contacts: here
each robot, and the ball) in parallel threads (``dWorldSetStepThreadingImplementation`` with a
thread pool). This script steps the same 22 flailing robots of mixed types (as
``benchmarks/throughput.py``'s ``ode_22_robots_cycles_per_s``) single-threaded and with
``--threads`` threads, and reports the speed-up and whether the states stay bit-equal.

    python benchmarks/ode_threads.py            # 300 cycles, 2 threads

Measured on a 2-core machine: ×1.35–1.6 with two threads, but the states part
after some cycles by ~1e-10 (the threaded step rounds differently), and chaos amplifies that: the
world therefore steps single-threaded, as exactness comes first. Prints one JSON object last.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np


def run(threads: int, cycles: int, seed: int = 0) -> tuple[float, list[np.ndarray]]:
    """Cycles per second and the final state (torsos, joints, ball) with ``threads`` threads."""
    from throughput import ode_22_robots  # this folder's benchmark: the same workload

    from robocup_gym.sim.engines.ode import lib as ode

    lib = ode.load()
    w, commands = ode_22_robots(seed)
    impl = pool = None
    if threads > 1:
        impl = lib.dThreadingAllocateMultiThreadedImplementation()
        pool = lib.dThreadingAllocateThreadPool(threads, 0, 0, None)
        lib.dThreadingThreadPoolServeMultiThreadedImplementation(pool, impl)
        functions = lib.dThreadingImplementationGetFunctions(impl)
        lib.dWorldSetStepThreadingImplementation(w._world, functions, impl)
        lib.dWorldSetStepIslandsProcessingMaxThreadCount(w._world, threads)
    try:
        t0 = time.perf_counter()
        for c in range(cycles):
            w.step(commands[c % len(commands)])
        rate = cycles / (time.perf_counter() - t0)
        state = [w.ball_position()]
        for i in range(22):
            state += [w.torso_position(i), w.joint_angles_deg(i)]
    finally:
        if impl is not None:
            lib.dWorldSetStepThreadingImplementation(w._world, None, None)
            lib.dThreadingImplementationShutdownProcessing(impl)
            lib.dThreadingThreadPoolWaitIdleState(pool)
            lib.dThreadingFreeThreadPool(pool)
            lib.dThreadingFreeImplementation(impl)
        w.close()
    return rate, state


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=300)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args(argv)
    one, s1 = run(1, args.cycles)
    many, sn = run(args.threads, args.cycles)
    diff = max(float(np.abs(a - b).max()) for a, b in zip(s1, sn, strict=True))
    out = {
        "cycles": args.cycles,
        "threads": args.threads,
        "ode_22_robots_1_thread_cycles_per_s": one,
        f"ode_22_robots_{args.threads}_threads_cycles_per_s": many,
        "speedup": many / one,
        "bit_equal": diff == 0.0,
        "largest_state_difference": diff,
    }
    print(
        f"22 robots: {one:.0f} cycles/s on 1 thread, {many:.0f} on {args.threads} "
        f"(x{many / one:.2f}); states {'bit-equal' if diff == 0 else f'differ by {diff:.1e}'}"
    )
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

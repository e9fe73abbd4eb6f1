"""ODE worlds in different threads step at the same time (ctypes releases the GIL inside ODE's
calls: servers started with ``start_in_thread``, an environment beside one) without disturbing
each other: each ends exactly where it ends when stepped alone."""

from __future__ import annotations

import subprocess
import sys

import pytest

from robocup_gym.sim.engines.ode import lib as ode_lib

pytestmark = pytest.mark.skipif(
    not ode_lib.available(), reason="no libode here (apt-get install libode8)"
)

_CHILD = """
import threading
import numpy as np
from robocup_gym.sim.engines.ode.world import OdeWorld

N_WORLDS, CYCLES = 4, 600

def run(seed, out):
    world = OdeWorld(robot_types=(0, 1, 2), seed=seed)
    rng = np.random.default_rng(seed)
    for _ in range(CYCLES):
        world.step({i: rng.uniform(-6.0, 6.0, 22) for i in range(3)})
    out[seed] = np.concatenate([world.body_positions().ravel(), world.ball_position()])
    world.close()

alone, together = {}, {}
for seed in range(N_WORLDS):
    run(seed, alone)
threads = [threading.Thread(target=run, args=(s, together)) for s in range(N_WORLDS)]
for t in threads:
    t.start()
for t in threads:
    t.join()
assert sorted(together) == list(range(N_WORLDS)), "a world's thread failed"
for seed in range(N_WORLDS):
    assert np.array_equal(alone[seed], together[seed]), f"world {seed} differs"
print("same")
"""


def test_worlds_step_concurrently_in_threads_and_end_as_when_alone():
    # in a child process: a corrupted ODE aborts the process, which must fail this test only
    out = subprocess.run(
        [sys.executable, "-c", _CHILD], capture_output=True, text=True, timeout=600
    )
    assert out.returncode == 0, f"exit {out.returncode}: {out.stderr[-2000:]}"
    assert out.stdout.strip() == "same"

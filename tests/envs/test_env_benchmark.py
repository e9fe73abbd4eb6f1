"""benchmarks/throughput.py --quick runs and reports its JSON (no timing assertions)."""

from __future__ import annotations

import math

KEYS = (
    "world_cycles_per_s",
    "world_numpy_cycles_per_s",
    "compiled_speedup",
    "raw_cycles_per_s",
    "env_steps_per_s",
    "reset_ms",
    "env_steps_per_s_2_workers",
    "world_vs_raw",
    "env_vs_world",
)


ODE_KEYS = (
    "ode_world_cycles_per_s",
    "ode_raw_cycles_per_s",
    "ode_world_vs_raw",
    "ode_env_steps_per_s",
    "ode_env_vs_world",
    "ode_22_robots_cycles_per_s",
)


def test_throughput_quick_prints_json_last(run_benchmark):
    result, _ = run_benchmark("throughput.py", "--quick", timeout=120)
    assert result["quick"] is True
    for key in KEYS:
        assert isinstance(result[key], float) and math.isfinite(result[key]) and result[key] > 0
    assert result["world_vs_raw"] == result["world_cycles_per_s"] / result["raw_cycles_per_s"]
    assert result["env_vs_world"] == result["env_steps_per_s"] / result["world_cycles_per_s"]
    from robocup_gym.sim import compiled
    from robocup_gym.sim.engines.ode import available

    if available():  # the default engine's keys, and their ratios
        for key in ODE_KEYS:
            assert isinstance(result[key], float) and math.isfinite(result[key]), key
            assert result[key] > 0, key
        assert result["ode_world_vs_raw"] == (
            result["ode_world_cycles_per_s"] / result["ode_raw_cycles_per_s"]
        )
        assert result["ode_world_cycles_per_s"] < result["ode_raw_cycles_per_s"]
    # the world measured is the compiled one wherever it can be built, and says so
    assert result["stepper"] == ("compiled" if compiled.available() else "numpy")

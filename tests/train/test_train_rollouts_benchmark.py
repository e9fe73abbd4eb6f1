"""benchmarks/rollouts.py --quick runs the four PPO schedules and reports its JSON (no timing
assertions)."""

from __future__ import annotations

import math

import pytest


def test_rollouts_quick_prints_json_last(run_benchmark):
    pytest.importorskip("stable_baselines3")
    result, lines = run_benchmark(
        "rollouts.py", "--quick", "--n-envs", 4, "--steps", 1024, timeout=300
    )
    names = ["lockstep", "pipelined", "overlapped", "workers"]
    assert [line.split()[0] for line in lines] == names
    for name in names:
        for key in ("rollout_s", "update_s", "steps_per_s"):
            v = result[f"{name}_{key}"]
            assert isinstance(v, float) and math.isfinite(v) and v > 0, (name, key, v)
    for name in names[1:]:
        assert result[f"{name}_vs_lockstep"] == round(
            result[f"{name}_steps_per_s"] / result["lockstep_steps_per_s"], 3
        )

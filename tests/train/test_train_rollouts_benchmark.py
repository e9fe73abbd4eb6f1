"""benchmarks/rollouts.py --quick runs the four PPO schedules and reports its JSON (no timing
assertions)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_rollouts_quick_prints_json_last():
    pytest.importorskip("stable_baselines3")
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "rollouts.py"), "--quick", "--n-envs", "4"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = proc.stdout.strip().splitlines()
    result = json.loads(lines[-1])
    names = ["lockstep", "pipelined", "overlapped", "workers"]
    assert [line.split()[0] for line in lines[:-1]] == names
    for name in names:
        for key in ("rollout_s", "update_s", "steps_per_s"):
            v = result[f"{name}_{key}"]
            assert isinstance(v, float) and math.isfinite(v) and v > 0, (name, key, v)
    for name in names[1:]:
        assert result[f"{name}_vs_lockstep"] == round(
            result[f"{name}_steps_per_s"] / result["lockstep_steps_per_s"], 3
        )

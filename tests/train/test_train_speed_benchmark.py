"""benchmarks/training_speed.py --quick measures the limit, the vectorised rate and a PPO run and
reports them against each other (no timing assertions)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_training_speed_quick_prints_json_last():
    pytest.importorskip("stable_baselines3")
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "training_speed.py"), "--quick"],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    r = json.loads(proc.stdout.strip().splitlines()[-1])
    for key in ("env_agent_steps_per_s_one_core", "vec_steps_per_s", "train_steps_per_s"):
        assert r[key] > 0, key
    limit = r["cores"] * r["env_agent_steps_per_s_one_core"]
    assert r["train_vs_limit"] == pytest.approx(r["train_steps_per_s"] / limit, abs=2e-3)
    policy_limit = r["cores"] * r["env_agent_steps_per_s_one_core_policy"]
    assert r["train_vs_policy_limit"] == pytest.approx(
        r["train_steps_per_s"] / policy_limit, abs=2e-3
    )
    assert 0 < r["learner_cpu_share"] <= 1.0
    if r["workers_cpu_share"] is not None:  # Linux
        total = r["learner_cpu_share"] + r["workers_cpu_share"] + r["idle_share"]
        assert total == pytest.approx(1.0, abs=0.01) or r["idle_share"] == 0.0

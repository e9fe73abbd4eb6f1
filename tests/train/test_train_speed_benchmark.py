"""benchmarks/training_speed.py --quick measures the limit, the vectorised rate and a PPO run and
reports them against each other (no timing assertions)."""

from __future__ import annotations

import pytest


def test_training_speed_quick_prints_json_last(run_benchmark):
    pytest.importorskip("stable_baselines3")
    r, _ = run_benchmark("training_speed.py", "--quick", timeout=600)
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

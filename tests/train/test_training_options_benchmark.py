"""benchmarks/training_options.py --quick measures what a run's options cost on the learner's and
the workers' side, each against the default of the same run (no timing assertions)."""

from __future__ import annotations

import pytest


def test_training_options_quick_prints_json_last(run_benchmark):
    pytest.importorskip("stable_baselines3")
    r, lines = run_benchmark("training_options.py", "--quick", timeout=600)
    per_step = r["update_us_per_step"]
    assert set(per_step) == {
        "default", "batch_size_256", "batch_size_512", "batch_size_1024", "n_epochs_5",
        "no_gsde", "two_threads",
    }  # fmt: skip
    assert all(v > 0 for v in per_step.values()), per_step
    for name, us in per_step.items():  # each ratio is against the default of the same run
        # printed rounded: the ratio to 3 decimals, the times to 0.1 µs (their share of a ratio)
        slack = 0.05 / us + 0.05 / per_step["default"]
        ratio = us / per_step["default"]
        assert r[f"{name}_vs_default"] == pytest.approx(ratio, rel=slack, abs=2e-3)
    assert r["default_vs_default"] == 1.0
    assert "torch_compile" not in per_step  # --quick leaves the compilation out
    assert set(r["worker_agent_steps_per_s"]) == {"1", "2", "4", "8", "16"}
    assert all(v > 0 for v in r["worker_agent_steps_per_s"].values())
    assert r["transfer_us_per_step"] > 0
    assert any("block of 16" in line for line in lines)
    # the bounds follow from the measures above: one core's random-action rate is the unit
    block = str(max(1, r["n_envs"] // r["cores"]))
    worker_s = 1.0 / r["worker_agent_steps_per_s"][block]
    unit = r["env_agent_steps_per_s_one_core"]
    assert r["bound_train_vs_limit_free_learner"] == pytest.approx(1.0 / worker_s / unit, abs=2e-3)
    with_update = 1.0 / (worker_s + per_step["default"] * 1e-6) / unit
    assert r["bound_train_vs_limit"] == pytest.approx(with_update, abs=2e-3)
    assert r["bound_train_vs_limit"] < r["bound_train_vs_limit_free_learner"]

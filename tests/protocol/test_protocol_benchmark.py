"""The protocol benchmark script runs and ends with its JSON line (no timing assertions)."""

from __future__ import annotations


def test_benchmark_quick_prints_json_last(run_benchmark) -> None:
    result, _ = run_benchmark("protocol_parse.py", "--quick", timeout=120)
    for key in ("perception_msgs_per_s", "sexpr_msgs_per_s", "format_msgs_per_s"):
        assert isinstance(result[key], float) and result[key] > 0, key
    assert result["fixture_messages"] == 20
    assert result["quick"] is True

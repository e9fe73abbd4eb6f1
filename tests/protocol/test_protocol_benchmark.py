"""The protocol benchmark script runs and ends with its JSON line (no timing assertions)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "protocol_parse.py"


def test_benchmark_quick_prints_json_last() -> None:
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick"],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    last = proc.stdout.strip().splitlines()[-1]
    result = json.loads(last)
    for key in ("perception_msgs_per_s", "sexpr_msgs_per_s", "format_msgs_per_s"):
        assert isinstance(result[key], float) and result[key] > 0, key
    assert result["fixture_messages"] == 20
    assert result["quick"] is True

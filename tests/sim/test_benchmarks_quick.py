"""The sim benchmarks run in quick mode and print a JSON summary (no timing assertions)."""

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_fidelity_quick_reports_targets():
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "fidelity.py"), "--quick"],
        capture_output=True,
        text=True,
        check=True,
        timeout=300,
    ).stdout
    res = json.loads(out.strip().splitlines()[-1])
    assert res["total_mass_kg"] == 4.6071
    assert res["stand_fell"] is False
    assert abs(res["stand_torso_z_m"] - 0.384) < 0.005
    met = res["targets_met"]
    assert met["mass_within_1pct"] and met["stand_no_fall"] and met["stand_z_within_5mm"]
    assert met["kick_within_25pct"], res["kick_D_ball_m"]
    assert met["kick_first_move_within_2_cycles"], res["kick_D_first_move_cycle"]

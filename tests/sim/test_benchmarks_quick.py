"""The sim benchmarks run in quick mode and print a JSON summary (no timing assertions)."""

import pytest

from robocup_gym.sim.engines.ode import available


def test_fidelity_quick_reports_targets(run_benchmark):
    res, _ = run_benchmark("fidelity.py", "--quick")
    assert res["total_mass_kg"] == 4.6071
    assert res["stand_fell"] is False
    assert abs(res["stand_torso_z_m"] - 0.384) < 0.005
    met = res["targets_met"]
    assert met["mass_within_1pct"] and met["stand_no_fall"] and met["stand_z_within_5mm"]
    assert met["kick_within_25pct"], res["kick_D_ball_m"]
    assert met["kick_first_move_within_2_cycles"], res["kick_D_first_move_cycle"]
    if available():  # the default engine against its own, tighter targets
        ode = res["ode_targets_met"]
        assert ode["kick_within_1pct"], res["ode_kick_D_ball_m"]
        assert ode["kick_first_move_64_pm_1"], res["ode_kick_D_first_move_cycle"]
        assert ode["stand_z_within_2mm"] and ode["stand_no_fall"], res["ode_stand_torso_z_m"]


def test_ode_compare_quick_reports_the_motions(run_benchmark):
    """``benchmarks/ode_compare.py --quick`` (needs libode): the JSON names each motion with its
    distances, and the reference's own kick is the real server's."""
    if not available():
        pytest.skip("no double-precision libode here (apt-get install libode8)")
    res, _ = run_benchmark("ode_compare.py", "--quick")
    assert abs(res["ode_kick_D_ball_m"] - 2.307) < 0.05
    rows = {r["motion"]: r for r in res["motions"]}
    assert set(rows) == {"stand", "kick_D", "ball_roll"}
    assert rows["stand"]["torso_final_m"] < 0.002
    assert rows["kick_D"]["ball_travel_m"][1] == pytest.approx(res["ode_kick_D_ball_m"], abs=1e-3)


def test_ode_threads_reports_speed_and_exactness(run_benchmark):
    """``benchmarks/ode_threads.py``: ODE's island threading set up, run and torn down cleanly
    (a short run: the speed-up and the bit-equality verdict are what it reports)."""
    if not available():
        pytest.skip("no double-precision libode here (apt-get install libode8)")
    res, _ = run_benchmark("ode_threads.py", "--cycles", 5)
    assert res["ode_22_robots_1_thread_cycles_per_s"] > 0
    assert res["ode_22_robots_2_threads_cycles_per_s"] > 0
    assert isinstance(res["bit_equal"], bool) and res["largest_state_difference"] >= 0.0

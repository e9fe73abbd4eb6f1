"""Replay the real rcssserver3d's measured cases on the embedded world and compare.

Prints a table and, as its LAST line, one JSON object with ``total_mass_kg``, ``stand_fell``,
``stand_torso_z_m`` (mean over the last second of standing with zero joint velocities),
``kick_D_ball_m`` (ball displacement of the scripted kick ``kick_D.json``), the first-move and
peak-speed cycles, the real server's figures and pass/fail per target. Where ODE (``libode``) is
installed, the same kick replayed on ``robocup_gym.sim.ode.OdeWorld`` (SimSpark's physics on ODE
itself) is reported beside it as ``ode_kick_D_ball_m`` (``null`` without ODE).

    python benchmarks/fidelity.py            # full: 60 s stand
    python benchmarks/fidelity.py --quick    # short stand (for the test suite)
"""

from __future__ import annotations

import argparse
import json
import time

from robocup_gym.robot.nao import nao_model
from robocup_gym.sim.fidelity import load_data, scripted_kick, stand
from robocup_gym.sim.ode import OdeWorld, available


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="stand 2 s instead of 60 s")
    args = parser.parse_args()
    real = load_data("real_server_figures.json")
    t0 = time.perf_counter()
    mass = nao_model(0).total_mass
    st = stand(2.0 if args.quick else 60.0)
    kick = scripted_kick()
    ode_kick = scripted_kick(world=OdeWorld([0])) if available() else None
    out = {
        "total_mass_kg": round(mass, 5),
        "stand_seconds": 2.0 if args.quick else 60.0,
        "stand_fell": st.fell,
        "stand_torso_z_m": round(st.torso_z_m, 5),
        "stand_head_z_m": round(st.head_z_m, 5),
        "stand_max_joint_drift_deg": round(st.max_joint_drift_deg, 4),
        "kick_D_ball_m": round(kick.ball_displacement_m, 4),
        "kick_D_first_move_cycle": kick.first_move_cycle,
        "kick_D_peak_speed_mps": round(kick.peak_speed_mps, 3),
        "kick_D_peak_speed_cycle": kick.peak_speed_cycle,
        "kick_D_robot_fell": kick.robot_fell,
        "ode_kick_D_ball_m": round(ode_kick.ball_displacement_m, 4) if ode_kick else None,
        "ode_kick_D_first_move_cycle": ode_kick.first_move_cycle if ode_kick else None,
        "real": {k: v for k, v in real.items() if k != "source"},
    }
    first = kick.first_move_cycle
    out["targets_met"] = {
        "mass_within_1pct": abs(mass - real["total_mass_kg"]) <= 0.01 * real["total_mass_kg"],
        "stand_no_fall": not st.fell,
        "stand_z_within_5mm": abs(st.torso_z_m - real["stand_torso_z_m"]) <= 0.005,
        "kick_within_25pct": abs(kick.ball_displacement_m - real["kick_D_ball_m"])
        <= 0.25 * real["kick_D_ball_m"],
        "kick_first_move_within_2_cycles": first is not None
        and abs(first - real["kick_D_first_move_cycle"]) <= 2,
    }
    out["seconds"] = round(time.perf_counter() - t0, 2)
    print(f"{'quantity':32s} {'embedded':>12s} {'real server':>12s}")
    for name, ours, theirs in (
        ("total mass (kg)", mass, real["total_mass_kg"]),
        ("stand torso z (m)", st.torso_z_m, real["stand_torso_z_m"]),
        ("stand head z (m)", st.head_z_m, real["stand_head_z_m"]),
        ("kick D ball displacement (m)", kick.ball_displacement_m, real["kick_D_ball_m"]),
        ("kick D first move (cycle)", first or -1, real["kick_D_first_move_cycle"]),
        ("kick D peak speed (m/s)", kick.peak_speed_mps, real["kick_D_peak_speed_mps"]),
    ):
        print(f"{name:32s} {ours:12.4f} {theirs:12.4f}")
    if ode_kick is not None:
        print(f"{'kick D on the ODE reference (m)':32s} {ode_kick.ball_displacement_m:12.4f}")
    print(json.dumps(out))


if __name__ == "__main__":
    main()

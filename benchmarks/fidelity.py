"""Replay the real rcssserver3d's measured cases on both engines and compare.

Prints a table and, as its LAST line, one JSON object with ``total_mass_kg``, ``stand_fell``,
``stand_torso_z_m`` (mean over the last second of standing with zero joint velocities),
``kick_D_ball_m`` (ball displacement of the scripted kick ``kick_D.json``), the first-move and
peak-speed cycles, the real server's figures and pass/fail per target. Where ODE (``libode``) is
installed, the same kick replayed on ``robocup_gym.sim.engines.ode.OdeWorld`` (SimSpark's physics
on ODE
itself, the default engine) is reported beside it: ``ode_kick_D_ball_m``,
``ode_kick_D_first_move_cycle``, ``ode_stand_torso_z_m`` and ``ode_targets_met`` (kick within 1 %
of the real server, first move at cycle 64 ± 1, stand within 2 mm); ``null`` without ODE.

    python benchmarks/fidelity.py            # full: 60 s stand
    python benchmarks/fidelity.py --quick    # short stand (for the test suite)
"""

from __future__ import annotations

import argparse
import json
import time

from robocup_gym.robot.nao import nao_model
from robocup_gym.sim.engines.ode import OdeWorld, available
from robocup_gym.sim.fidelity import load_data, scripted_kick, stand


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
    ode_st = stand(2.0 if args.quick else 60.0, world=OdeWorld([0])) if available() else None
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
        "ode_kick_D_peak_speed_mps": round(ode_kick.peak_speed_mps, 3) if ode_kick else None,
        "ode_stand_fell": ode_st.fell if ode_st else None,
        "ode_stand_torso_z_m": round(ode_st.torso_z_m, 5) if ode_st else None,
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
    if ode_kick is not None:
        ode_first = ode_kick.first_move_cycle
        out["ode_targets_met"] = {
            "kick_within_1pct": abs(ode_kick.ball_displacement_m - real["kick_D_ball_m"])
            <= 0.01 * real["kick_D_ball_m"],
            "kick_first_move_64_pm_1": ode_first is not None
            and abs(ode_first - real["kick_D_first_move_cycle"]) <= 1,
            "stand_z_within_2mm": abs(ode_st.torso_z_m - real["stand_torso_z_m"]) <= 0.002,
            "stand_no_fall": not ode_st.fell,
        }
    out["seconds"] = round(time.perf_counter() - t0, 2)
    print(f"{'quantity':32s} {'MuJoCo':>12s} {'ODE':>12s} {'real server':>12s}")
    ode = ode_kick is not None
    nan = float("nan")
    for name, ours, on_ode, theirs in (
        ("total mass (kg)", mass, mass, real["total_mass_kg"]),
        (
            "stand torso z (m)",
            st.torso_z_m,
            ode_st.torso_z_m if ode else nan,
            real["stand_torso_z_m"],
        ),
        ("stand head z (m)", st.head_z_m, ode_st.head_z_m if ode else nan, real["stand_head_z_m"]),
        (
            "kick D ball displacement (m)",
            kick.ball_displacement_m,
            ode_kick.ball_displacement_m if ode else nan,
            real["kick_D_ball_m"],
        ),
        (
            "kick D first move (cycle)",
            first or -1,
            (ode_kick.first_move_cycle or -1) if ode else nan,
            real["kick_D_first_move_cycle"],
        ),
        (
            "kick D peak speed (m/s)",
            kick.peak_speed_mps,
            ode_kick.peak_speed_mps if ode else nan,
            real["kick_D_peak_speed_mps"],
        ),
    ):
        print(f"{name:32s} {ours:12.4f} {on_ode:12.4f} {theirs:12.4f}")
    print(json.dumps(out))


if __name__ == "__main__":
    main()

"""The embedded MuJoCo world against SimSpark's physics on ODE itself, motion by motion.

rcssserver3d steps ODE 0.16 once per 20 ms cycle. ``robocup_gym.sim.engines.ode.OdeWorld``
re-creates
that step from the spec on the same engine (the system library ``libode``; Debian/Ubuntu:
``apt-get install libode8``), and reproduces the real server's kick D (2.31 m) and standing
height. This script replays a library of scripted motions (``robocup_gym.sim.engines.ode.compare``)
on
both and prints, per motion, how far the MuJoCo world drifts from the reference; the last line
is one JSON object.

    python benchmarks/ode_compare.py            # all motions
    python benchmarks/ode_compare.py --quick    # three short ones (used by the test suite)
"""

from __future__ import annotations

import argparse
import json
import sys

from robocup_gym.sim.engines.ode import OdeUnavailableError, OdeWorld
from robocup_gym.sim.engines.ode.compare import compare, motions
from robocup_gym.sim.fidelity import scripted_kick

QUICK = ("stand", "kick_D", "ball_roll")


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="only " + ", ".join(QUICK))
    args = parser.parse_args(argv)
    try:
        reference = OdeWorld([0])
    except OdeUnavailableError as e:
        print(f"ode_compare: {e}", file=sys.stderr)
        raise SystemExit(2) from None
    kick = scripted_kick(world=reference)
    reference.close()
    rows = [compare(m).row() for m in motions() if not args.quick or m.name in QUICK]
    header = (
        f"{'motion':<13}{'cycles':>7}{'torso Δ end':>12}{'torso Δ max':>12}{'tilt Δ°':>9}"
        f"{'joints rms°':>12}{'ball Δ':>8}{'ball mj/ode m':>15}{'>1cm at':>9}{'fell mj/ode':>13}"
    )
    print(header)
    for r in rows:
        travel = "{:.2f}/{:.2f}".format(*r["ball_travel_m"])
        fell = "/".join("yes" if f else "no" for f in r["fell"])
        print(
            f"{r['motion']:<13}{r['cycles']:>7}{r['torso_final_m']:>12.4f}{r['torso_max_m']:>12.4f}"
            f"{r['tilt_final_deg']:>9.1f}{r['joints_rms_deg']:>12.2f}{r['ball_final_m']:>8.3f}"
            f"{travel:>15}{r['diverged_cycle'] or '-':>9}{fell:>13}"
        )
    summary = {
        "ode_kick_D_ball_m": round(kick.ball_displacement_m, 4),
        "ode_kick_D_first_move_cycle": kick.first_move_cycle,
        "motions": rows,
    }
    print(json.dumps(summary))
    return summary


if __name__ == "__main__":
    main()

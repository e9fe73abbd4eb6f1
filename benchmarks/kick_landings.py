"""Where TargetKick-v1's kicks land, and how well the library covers the commands.

For every Nao type, the table of measured landings
(``robocup_gym/data/commanded_kick_landings.json``, or measured again with ``--write``, which
also rewrites that file): per kick of the library, its
aim and its landings' median distance and direction. Then, for the kick benchmark's commands
(``benchmarks/kick.py``: 2, 3, 5, 7, 9 m × −45° … 45°), the kick :func:`commanded_kick` chooses
and the errors its measured landings predict (medians over the commands: distance error as a
fraction, direction error in deg), which ``benchmarks/kick.py zero`` then measures on fresh
episodes. Prints one JSON object last.

    python benchmarks/kick_landings.py [--write]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from robocup_gym.envs.tasks.commanded_kicks import (
    choose_kick,
    kick_landings,
    kick_library,
    write_landings,
)
from robocup_gym.robot.types import TYPE_NUMBERS

DISTANCES_M = (2.0, 3.0, 5.0, 7.0, 9.0)
DIRECTIONS_DEG = (-45.0, -30.0, -15.0, 0.0, 15.0, 30.0, 45.0)


def predicted_errors(robot_type: int) -> tuple[float, float]:
    """The medians over the benchmark's commands of the errors the chosen kicks' landings
    predict (distance error as a fraction, direction error deg)."""
    dist_err, dir_err = [], []
    for d in DISTANCES_M:
        for a in DIRECTIONS_DEG:
            _, _, rows = choose_kick(d, a, robot_type)
            dist_err.append(float(np.median(np.abs(rows[:, 0] - d) / d)))
            dir_err.append(float(np.median(np.abs(rows[:, 1] - a))))
    return float(np.median(dist_err)), float(np.median(dir_err))


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--write", action="store_true", help="measure again and write the table")
    parser.add_argument("--out", type=Path, help="with --write: where to (default: the package)")
    args = parser.parse_args(argv)
    if args.write:
        print(f"wrote {write_landings(args.out)}")
    out: dict = {"kicks": len(kick_library()), "types": {}}
    for robot_type in TYPE_NUMBERS:
        landings = kick_landings()[robot_type]
        print(f"type {robot_type}: aim -> median landing (distance m, direction deg), falls")
        for kick in kick_library():
            if robot_type not in kick.robot_types:
                continue
            rows = landings[kick.key]
            d, a = np.median(rows[:, 0]), np.median(rows[:, 1])
            print(f"  {kick.key:>17s} -> {d:5.2f} m {a:+6.1f} deg  {int(rows[:, 2].sum())}")
        dist, direction = predicted_errors(robot_type)
        print(
            f"  benchmark commands: distance error {dist:.1%}, direction error {direction:.1f} deg"
        )
        out["types"][str(robot_type)] = {
            "predicted_distance_error_median": round(dist, 4),
            "predicted_direction_error_deg_median": round(direction, 2),
        }
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

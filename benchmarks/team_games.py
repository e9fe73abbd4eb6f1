"""How fast can a team train on games of N a side? The learning team's decisions per second on
one core, against the world alone on the same robots, measured in the same run.

For each N (default 1, 2, 3, 5, 11): ``game-NvN`` seen by its learning team
(:class:`robocup_gym.soccer.team_view.TeamView`, skill actions, a decision every 10 cycles,
privileged observations, the scripted team as the opponent) with random walk commands; and the
same world stepped alone. Keys, per N:

* ``team_NvN_decisions_per_s``: the learning team's player decisions per second (what a
  training run counts as steps), resets included;
* ``team_NvN_cycles_per_s``: game cycles per second;
* ``physics_NvN_cycles_per_s``: the world alone (no perception, skills or rules);
* ``team_NvN_vs_physics``: the game's cycles over the physics'.

A run's steps per second on C cores approach C × ``team_NvN_decisions_per_s``.

    python benchmarks/team_games.py [--quick] [--sizes 1,2,3]

Prints one line per measure and, last, one JSON object.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from soccer import physics_per_s  # the sibling benchmark (benchmarks/ is on the path)

from robocup_gym.soccer.scripted import ScriptedTeam
from robocup_gym.soccer.team_view import TeamView


def _decisions_per_s(view: TeamView, steps: int) -> tuple[float, float]:
    """(decisions per second, cycles per second) over ``steps`` steps with random walks."""
    rng = np.random.default_rng(0)
    view.reset(seed=0)
    cycles = view.env.config.skill_cycles
    t0 = time.perf_counter()
    for _ in range(steps):
        actions = rng.uniform(-1, 1, (view.seats, 4))
        actions[:, 3] = -1.0  # walk (kicks make robots fall: get-ups would dominate)
        _, _, terminated, truncated, _ = view.step(actions)
        if terminated or truncated:
            view.reset()
    dt = time.perf_counter() - t0
    return steps * view.seats / dt, steps * cycles / dt


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer steps")
    parser.add_argument("--sizes", default="1,2,3,5,11", help="players a side, comma-separated")
    args = parser.parse_args(argv)
    sizes = [int(n) for n in args.sizes.split(",")]
    steps = 10 if args.quick else 60
    scripted = ScriptedTeam()
    out: dict = {"quick": args.quick}
    for n in sizes:
        view = TeamView(f"game-{n}v{n}", lambda rng: scripted, {"max_cycles": 100_000}, seed=0)
        try:
            decisions, cycles = _decisions_per_s(view, steps)
            physics = physics_per_s(view.env, steps * 10)
        finally:
            view.close()
        key = f"{n}v{n}"
        out[f"team_{key}_decisions_per_s"] = round(decisions, 1)
        out[f"team_{key}_cycles_per_s"] = round(cycles, 1)
        out[f"physics_{key}_cycles_per_s"] = round(physics, 1)
        out[f"team_{key}_vs_physics"] = round(cycles / physics, 3)
    for k, v in out.items():
        print(f"{k:34s} {v}")
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

"""How well does the ``kick-to`` motion skill kick in a game? Distance and direction against
the command, and standing after.

A one-player game (``game_v1`` with skill actions, ``skills=("kick-to",)``, the referee's rules
off) per kick: the player walks 3 s forward (0.3–0.5 m/s, by seed), stands 1 s, then starts
``kick-to`` with the command's action values. The ball is put at the kick's spot
(``robocup_gym.soccer.motions.kick_to_spot``) relative to the torso

* ``--ball after`` (default): when the prelude is over (the kick alone: what the skill does
  with the ball where it needs it);
* ``--ball before``: when the kick starts, relative to the standing torso (what a team that
  brings the ball to the spot and then kicks gets: the prelude moves the torso 1–3 cm).

``--lead AHEAD,LEFT`` (m) puts the ball that much farther ahead and to the left of the spot
(e.g. ``--ball before --lead 0.03,0.01``, ahead of where the prelude takes the torso).

Commands: distances 3, 6, 9 m × directions −45°, −22.5°, 0°, 22.5°, 45°. Per kick, where the
ball comes to rest (``robocup_gym.sim.physics.ball_rest_point``, 3 s after the prelude),
its distance error as a fraction of the command, its direction error (deg), and whether the
player stands 1 s after the motion. Prints one line per command and, last, one JSON object
(``distance_error_median``, ``direction_error_deg_median``, ``stand_after_kick_rate``, …).

    python benchmarks/game_kick.py --robot-type 0
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from robocup_gym.envs.observations import heading_frame
from robocup_gym.envs.tasks.target_kick import kick_outcome
from robocup_gym.sim.physics import BALL_REST_Z, CYCLE_S
from robocup_gym.soccer.env import SoccerConfig

DISTANCES_M = (3.0, 6.0, 9.0)
DIRECTIONS_DEG = (-45.0, -22.5, 0.0, 22.5, 45.0)
_STEP_S = SoccerConfig.skill_cycles * CYCLE_S
"""A skill step, s."""


def kick(
    robot_type: int,
    command: tuple[float, float],
    seed: int,
    ball: str,
    lead: tuple[float, float] = (0.0, 0.0),
) -> dict:
    """One kick-to in a game (see the module docstring); its outcome."""
    from robocup_gym.soccer import game_v1
    from robocup_gym.soccer.motions import KICK_TO_PRELUDE_S, kick_to_spot, kick_to_values

    values = kick_to_values(*command)
    ahead, left = kick_to_spot(*command, robot_type)
    spot = (ahead + lead[0], left + lead[1])
    env = game_v1.parallel_env(
        actions="skills",
        skills=("kick-to",),
        left_types=(robot_type,),
        right_types=(),
        rules=False,
        max_cycles=10**6,
    )
    try:
        env.reset(seed=seed)
        world = env.game.world
        walk = np.array([0.375 + 0.125 * (seed % 3 - 1), 0.0, 0.0, -1.0, 0.0, 0.0])
        for _ in range(round(3.0 / _STEP_S)):
            env.step({"left_1": walk})
        for _ in range(round(1.0 / _STEP_S)):
            env.step({"left_1": np.zeros(6)})

        def place() -> tuple[np.ndarray, float]:
            pos = world.torso_position(0)
            c, s = heading_frame(world.torso_quat(0))
            at = pos[:2] + np.array([c * spot[0] - s * spot[1], s * spot[0] + c * spot[1]])
            env.game.host.set_ball((at[0], at[1], BALL_REST_Z), (0.0, 0.0, 0.0))
            return at, math.degrees(math.atan2(s, c))

        if ball == "before":
            spawn, heading = place()
        env.step({"left_1": np.array([0.0, 0.0, 0.0, 1.0, *values])})
        for _ in range(round(KICK_TO_PRELUDE_S / _STEP_S) - 1):
            env.step({"left_1": np.zeros(6)})
        if ball == "after":
            spawn, heading = place()
        while env.skills.modes()[0] == "kick-to":
            env.step({"left_1": np.zeros(6)})
        for _ in range(round(1.0 / _STEP_S)):
            env.step({"left_1": np.zeros(6)})
        out = kick_outcome(
            spawn, world.ball_position(), world.ball_velocity(), heading, np.array(command)
        )
        out["standing"] = env.skills.modes()[0] == "walk"
        return out
    finally:
        env.close()


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot-type", type=int, default=0, choices=range(5))
    parser.add_argument("--ball", choices=("after", "before"), default="after")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--lead",
        type=lambda text: tuple(float(v) for v in text.split(",")),
        default=(0.0, 0.0),
        metavar="AHEAD,LEFT",
        help="put the ball this much farther ahead and to the left of the kick's spot, m",
    )
    args = parser.parse_args(argv)
    if len(args.lead) != 2:
        parser.error(f"--lead takes AHEAD,LEFT in m, got {args.lead}")
    rows = []
    for k, (d, a) in enumerate((d, a) for d in DISTANCES_M for a in DIRECTIONS_DEG):
        r = kick(args.robot_type, (d, a), args.seed + k, args.ball, args.lead)
        rows.append(r)
        print(
            f"{d:4.1f} m {a:+6.1f}°: {r['kick_distance_m']:5.2f} m "
            f"({100 * r['distance_error']:3.0f} % off), direction error "
            f"{r['direction_error_deg']:5.1f}°, {'up' if r['standing'] else 'down'}",
            flush=True,
        )
    out = {
        "robot_type": args.robot_type,
        "ball": args.ball,
        "lead_m": list(args.lead),
        "kicks": len(rows),
        "distance_error_median": float(np.median([r["distance_error"] for r in rows])),
        "direction_error_deg_median": float(np.median([r["direction_error_deg"] for r in rows])),
        "ball_distance_median_m": float(np.median([r["kick_distance_m"] for r in rows])),
        "stand_after_kick_rate": float(np.mean([r["standing"] for r in rows])),
    }
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

"""How well does a player kick to a target from where it stands? The ``approach-kick`` motion
skill: walk to the ball, facing where the kick chosen for the distance sends it along the
command's direction, then that kick (``--straight``: the library's kick for (distance, 0°)
facing the command instead).

A one-player game per episode (``game_v1`` with skill actions, ``skills=("approach-kick",)``,
the referee's rules off, ``--walk``: the omnidirectional ``walk`` by default): the player
stands 1 s, the ball is put 0.6–1.2 m ahead of its torso and up to 0.3 m to either side (drawn
from the episode's seed), then the player is told ``approach-kick`` with a command of the
grid of ``benchmarks/kick.py`` (distances 2, 3, 5, 7, 9 m × directions −45° … 45° of its
heading), and the action is repeated until the motion ends. Per episode:

* where the ball comes to rest (``robocup_gym.sim.physics.ball_rest_point``, 1 s after the
  motion) against the command from where the ball was put: the distance error as a fraction of
  the command, and the direction error, deg;
* whether the player stands 1 s after the motion;
* the time from the command to the player's arrival at the kicking pose, and to the kick's
  contact (the ball's first movement above 0.1 m/s after the arrival);
* how far the ball was from where the approach brings it at the arrival (the kick's spot,
  corrected for the type's prelude), cm, and where it lay against the kick's spot when the
  prelude was over (``kick_offset_cm``: ahead, left).

``--write-landings`` measures where every kick of the library lands after an approach, on every
Nao type, and writes the table the choice reads (``robocup_gym/data/approach_kick_landings.json``).

Prints one line per command and, last, one JSON object (``distance_error_median``,
``direction_error_deg_median``, ``stand_after_kick_rate``, ``contact_time_s_median``,
``arrived_rate``, ``spot_error_cm_median``, …).

    python benchmarks/approach_kick.py --robot-type 0
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from robocup_gym.envs.observations import heading_frame, in_heading_frame
from robocup_gym.envs.tasks.target_kick import CONTACT_SPEED, kick_outcome
from robocup_gym.sim.physics import BALL_REST_Z, CYCLE_S

DISTANCES_M = (2.0, 3.0, 5.0, 7.0, 9.0)
DIRECTIONS_DEG = (-45.0, -30.0, -15.0, 0.0, 15.0, 30.0, 45.0)
BALL_AHEAD_M = (0.6, 1.2)
BALL_SIDE_M = 0.3
_STEPS_AFTER = 5
"""Skill steps (10 cycles each) after the motion before the outcome is read: 1 s."""
_MAX_STEPS = 200
"""A motion still running after this many skill steps (40 s) is a failure of the benchmark."""


def make_game(robot_type: int, walk: str):
    from robocup_gym.soccer import game_v1
    from robocup_gym.soccer.skills import runs_a_command_loop

    return game_v1.parallel_env(
        actions="skills",
        skills=("approach-kick",),
        left_types=(robot_type,),
        right_types=(),
        rules=False,
        max_cycles=10**7,
        walk=walk,
        walk_faces_x=not runs_a_command_loop(walk),
    )


def episode(env, seed: int, command: tuple[float, float], kick=None) -> dict:
    """One approach and kick (``command``: distance m, direction deg from the heading; ``kick``:
    play this kick of the library, facing the command's direction, instead of the choice)."""
    from robocup_gym.soccer.motions import KICK_TO_PRELUDE_S, ApproachKick, kick_to_values

    rng = np.random.default_rng(seed)
    world = env.game.world
    env.reset(seed=seed)
    stand = np.zeros(6)
    for _ in range(_STEPS_AFTER):
        env.step({"left_1": stand})
    pos, heading = world.torso_position(0)[:2], heading_frame(world.torso_quat(0))
    ahead, side = rng.uniform(*BALL_AHEAD_M), rng.uniform(-BALL_SIDE_M, BALL_SIDE_M)
    c, s = heading
    spawn = pos + ahead * np.array([c, s]) + side * np.array([-s, c])
    env.game.host.set_ball((spawn[0], spawn[1], BALL_REST_Z), (0.0, 0.0, 0.0))
    action = np.array([0.0, 0.0, 0.0, 1.0, *kick_to_values(*command)])
    player = env.skills.players[0]
    if kick is not None:
        player.play("approach-kick", ApproachKick(env.skills.robot_types[0], *command, kick=kick))
    seen: dict = {"cycle": 0, "arrived": None, "contact": None, "spot_error": None, "shift": None}
    prelude = round(KICK_TO_PRELUDE_S / CYCLE_S)

    def watch(_env) -> None:
        seen["cycle"] += 1
        motion = player.motion
        if seen["arrived"] is None and getattr(motion, "arrived", False):
            seen["arrived"] = seen["cycle"]
            seen["torso"] = world.torso_position(0)[:2].copy()
            seen["heading"] = heading_frame(world.torso_quat(0))
            rel = in_heading_frame(seen["heading"], *(world.ball_position()[:2] - seen["torso"]))
            seen["spot_error"] = float(np.hypot(rel[0] - motion.spot[0], rel[1] - motion.spot[1]))
        if seen["arrived"] is not None and seen["cycle"] == seen["arrived"] + prelude:
            torso = world.torso_position(0)[:2]
            seen["shift"] = in_heading_frame(seen["heading"], *(torso - seen["torso"]))
            rel = in_heading_frame(
                heading_frame(world.torso_quat(0)), *(world.ball_position()[:2] - torso)
            )
            seen["offset"] = (rel[0] - motion.kick_spot[0], rel[1] - motion.kick_spot[1])
        if (
            seen["arrived"] is not None
            and seen["contact"] is None
            and float(np.linalg.norm(world.ball_velocity())) > CONTACT_SPEED
        ):
            seen["contact"] = seen["cycle"]

    env.cycle_hook = watch
    try:
        steps = 0
        env.step({"left_1": action})
        while env.skills.modes()[0] == "approach-kick":
            env.step({"left_1": action})
            steps += 1
            if steps > _MAX_STEPS:
                raise RuntimeError(f"approach-kick still running after {steps} skill steps")
    finally:
        env.cycle_hook = None
    for _ in range(_STEPS_AFTER):
        env.step({"left_1": stand})
    start_deg = math.degrees(math.atan2(heading[1], heading[0]))
    out = kick_outcome(
        spawn, world.ball_position(), world.ball_velocity(), start_deg, np.array(command)
    )
    out["standing"] = env.skills.modes()[0] == "walk"
    travel = math.atan2(out["rest_y"] - spawn[1], out["rest_x"] - spawn[0])
    goes = math.degrees(travel) - start_deg - command[1]
    out["direction_deg"] = (goes + 180.0) % 360.0 - 180.0  # from where the command points
    out["arrived"] = seen["arrived"] is not None
    out["arrival_time_s"] = None if seen["arrived"] is None else seen["arrived"] * CYCLE_S
    out["contact_time_s"] = None if seen["contact"] is None else seen["contact"] * CYCLE_S
    out["spot_error_cm"] = None if seen["spot_error"] is None else 100.0 * seen["spot_error"]
    out["prelude_shift_cm"] = None if seen["shift"] is None else [100.0 * v for v in seen["shift"]]
    out["kick_offset_cm"] = None if seen["shift"] is None else [100.0 * v for v in seen["offset"]]
    return out


def _median(values: list) -> float | None:
    present = [v for v in values if v is not None]
    return float(np.median(present)) if present else None


def _median_pair(values: list) -> list[float] | None:
    present = [v for v in values if v is not None]
    return [float(v) for v in np.median(present, axis=0)] if present else None


LANDING_EPISODES = 12
_LANDING_SEED = 20_000


def measure_landings(robot_type: int, walk: str = "walk") -> dict[str, list]:
    """Every kick of the library made for ``robot_type``, played :data:`LANDING_EPISODES` times
    by ``approach-kick`` facing the command (directions drawn within ±45°, seeds from 20000
    on): rows of (distance m, direction deg from the player's heading, 1.0 if down 1 s later)."""
    from robocup_gym.envs.tasks.commanded_kicks import kick_library

    env = make_game(robot_type, walk)
    out = {}
    try:
        for kick in (k for k in kick_library() if robot_type in k.robot_types):
            rows = []
            for e in range(LANDING_EPISODES):
                seed = _LANDING_SEED + e
                direction = float(np.random.default_rng(seed).uniform(-45.0, 45.0))
                r = episode(env, seed, (kick.aim[0], direction), kick=kick)
                rows.append([r["kick_distance_m"], r["direction_deg"], float(not r["standing"])])
            out[kick.key] = np.round(rows, 4).tolist()
    finally:
        env.close()
    return out


def write_landings(jobs: int = 2) -> str:
    """Measure every type's kicks (:func:`measure_landings`, ``jobs`` processes) and write the
    table ``robocup_gym.soccer.motions.approach_landings`` reads."""
    from concurrent.futures import ProcessPoolExecutor
    from importlib import resources

    from robocup_gym.soccer.motions import APPROACH_LANDINGS_FILE

    types = range(5)
    with ProcessPoolExecutor(jobs) as pool:
        landings = dict(zip(map(str, types), pool.map(measure_landings, types), strict=True))
    doc = {
        "about": (
            "Where each kick of the library lands when approach-kick plays it (the "
            "omnidirectional walk to its pose facing a direction within 45 deg of the heading, "
            "from 0.6-1.2 m behind the ball), by Nao type and kick (aim distance m / direction "
            "deg): distance m, direction deg from the player's heading, 1.0 if it was down 1 s "
            "later; ODE. Written by python benchmarks/approach_kick.py --write-landings."
        ),
        "episodes": LANDING_EPISODES,
        "landings": landings,
    }
    path = str(resources.files("robocup_gym.data").joinpath(APPROACH_LANDINGS_FILE))
    with open(path, "w") as f:
        f.write(json.dumps(doc, separators=(",", ":")) + "\n")
    return path


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot-type", type=int, default=0, choices=range(5))
    parser.add_argument("--episodes", type=int, default=1, help="episodes per command")
    parser.add_argument("--seed", type=int, default=0, help="episode k is seeded seed + k")
    parser.add_argument("--walk", default="walk", help="the shipped walk the player walks with")
    parser.add_argument(
        "--distances", type=float, nargs="+", default=DISTANCES_M, help="commanded distances, m"
    )
    parser.add_argument(
        "--straight",
        action="store_true",
        help="play the library's kick for (distance, 0°), facing the command, instead of the kick "
        "chosen by its landings after an approach",
    )
    parser.add_argument(
        "--write-landings",
        action="store_true",
        help="measure where every kick lands after an approach, on every type, and write the "
        "package's table (several minutes)",
    )
    args = parser.parse_args(argv)
    if args.write_landings:
        path = write_landings()
        out = {"written": path}
        print(json.dumps(out))
        return out
    if args.episodes < 1:
        parser.error(f"--episodes must be at least 1, got {args.episodes}")
    from robocup_gym.envs.tasks.commanded_kicks import choose_kick

    env = make_game(args.robot_type, args.walk)
    rows, k = [], 0
    try:
        for distance in args.distances:
            for direction in DIRECTIONS_DEG:
                these = []
                kick = choose_kick(distance, 0.0, args.robot_type)[0] if args.straight else None
                for _ in range(args.episodes):
                    these.append(episode(env, args.seed + k, (distance, direction), kick))
                    k += 1
                rows += these
                print(
                    f"{distance:4.1f} m {direction:+5.0f}°: ball "
                    f"{np.median([r['kick_distance_m'] for r in these]):5.2f} m, distance error "
                    f"{100 * np.median([r['distance_error'] for r in these]):3.0f} %, direction "
                    f"error {np.median([r['direction_error_deg'] for r in these]):5.1f}°, "
                    f"standing {sum(r['standing'] for r in these)}/{len(these)}",
                    flush=True,
                )
    finally:
        env.close()
    out = {
        "robot_type": args.robot_type,
        "walk": args.walk,
        "kicks": "straight" if args.straight else "landings after an approach",
        "episodes": len(rows),
        "distance_error_median": float(np.median([r["distance_error"] for r in rows])),
        "direction_error_deg_median": float(np.median([r["direction_error_deg"] for r in rows])),
        "ball_distance_median_m": float(np.median([r["kick_distance_m"] for r in rows])),
        "stand_after_kick_rate": float(np.mean([r["standing"] for r in rows])),
        "arrived_rate": float(np.mean([r["arrived"] for r in rows])),
        "arrival_time_s_median": _median([r["arrival_time_s"] for r in rows]),
        "contact_time_s_median": _median([r["contact_time_s"] for r in rows]),
        "spot_error_cm_median": _median([r["spot_error_cm"] for r in rows]),
        "prelude_shift_cm_median": _median_pair([r["prelude_shift_cm"] for r in rows]),
        "kick_offset_cm_median": _median_pair([r["kick_offset_cm"] for r in rows]),
    }
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

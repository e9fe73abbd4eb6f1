"""How well does a player play the ball along a direction (the ``plays`` action)?

A 1-against-1 game (``game_v1``, the standing team as the opponent) starts from a random
place in play; the ball is put 0.5 m from the learning player toward the middle of the field,
and the player plays it along a direction for ``--seconds`` of game time (the plays action
``play`` = 1, ``direction`` = 0, 0.5 and −0.5: straight at the opponent goal and 90° to either
side of that line; ``kick`` −1: a dribble). Per episode: how far the ball went and the error of
its direction against the one asked. Prints one line per episode and, last, one JSON object
(``ball_travel_median_m``, ``direction_error_deg_median`` over the episodes in which the ball
went more than 1 m, ``moved_rate``, ``on_course_rate``: more than 2 m within 20°).

    python benchmarks/ball_play.py --episodes 10
"""

from __future__ import annotations

import argparse
import json
import math
import statistics

import numpy as np

from robocup_gym.sim.field import FIELD_HALF_LENGTH
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.soccer.scripted import StandingTeam
from robocup_gym.soccer.team_view import TeamView

DIRECTIONS = (0.0, 0.5, -0.5)
"""The ``direction`` values played: 0°, +90° and −90° from the line to the goal's middle."""


def episode(seed: int, direction: float, seconds: float) -> tuple[float, float]:
    """(the ball's travel in m, its direction's error in degrees) of one episode."""
    game = TeamView(
        "game-1v1", lambda rng: StandingTeam(), {"plays": True, "random_start": True}, seed=seed
    )
    try:
        game.reset(seed=seed)
        world = game.env.game.world
        at = world.torso_position(game.env.game.index(game.mine[0]))[:2]
        world.place_ball(tuple(at - 0.5 * at / max(float(np.hypot(*at)), 1e-6)))
        start = world.ball_position()[:2].copy()
        steps = round(seconds / (game.env.config.skill_cycles * CYCLE_S))
        for _ in range(steps):
            _, _, terminated, truncated, _ = game.step(
                np.array([[0.0, 0.0, 0.0, -1.0, 1.0, direction]])
            )
            if terminated or truncated:
                break
        moved = world.ball_position()[:2] - start
        goal_x = FIELD_HALF_LENGTH if game.side == "left" else -FIELD_HALF_LENGTH
    finally:
        game.close()
    asked = math.atan2(-start[1], goal_x - start[0]) + math.pi * direction
    got = math.atan2(moved[1], moved[0])
    error = math.degrees(math.atan2(math.sin(got - asked), math.cos(got - asked)))
    return float(np.hypot(*moved)), error


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=10, help="random starts per direction")
    parser.add_argument("--seconds", type=float, default=20.0, help="game time per episode")
    parser.add_argument("--seed", type=int, default=0, help="seed of the first start")
    args = parser.parse_args(argv)
    travels, errors, on_course = [], [], 0
    for k in range(args.episodes):
        for direction in DIRECTIONS:
            travel, error = episode(args.seed + k, direction, args.seconds)
            print(
                f"start {args.seed + k} direction {direction * 180:+.0f}°: ball {travel:.2f} m, "
                f"{error:+.1f}° off",
                flush=True,
            )
            travels.append(travel)
            if travel > 1.0:
                errors.append(abs(error))
            on_course += travel > 2.0 and abs(error) < 20.0
    n = len(travels)
    summary = {
        "episodes": n,
        "seconds": args.seconds,
        "ball_travel_median_m": round(statistics.median(travels), 3),
        "direction_error_deg_median": round(statistics.median(errors), 2) if errors else None,
        "moved_rate": round(len(errors) / n, 3),
        "on_course_rate": round(on_course / n, 3),
    }
    print(json.dumps(summary), flush=True)
    return summary


if __name__ == "__main__":
    main()

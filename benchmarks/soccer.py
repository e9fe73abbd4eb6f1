"""How fast do the soccer environments run? Agent steps and game cycles per second, against the
world alone on the same robots, measured in the same run.

* ``penalty_env_steps_per_s``: ``penalty_v1`` (2 players), random joint actions, resets
  included (one step = one cycle, both agents act);
* ``game_2v2_steps_per_s``: ``game_v1`` 2 against 2, random joint actions;
* ``game_2v2_skill_steps_per_s``: agent decisions per second, 2 against 2 with skill actions
  (random walk commands, a decision every 10 cycles; the skills' policies run every cycle);
* ``game_11v11_cycles_per_s``: ``game_v1`` 11 against 11, robot types 0–4 mixed, every player's
  skills running (random walk commands) and every player observing (vision every third cycle);
* ``game_11v11_joint_cycles_per_s``: the same with joint-level actions every cycle;
* ``physics_22_robots_cycles_per_s``: the same world stepped alone (no perception, no rules);
* ``game_vs_physics``: the skill game's cycles over the physics', the two measured in
  alternating rounds of 50 cycles (a change of the machine's speed during the run hits both).

One core (the environments are single-process). ``--quick`` measures fewer cycles.

    python benchmarks/soccer.py [--quick] [--engine ode|mujoco]

Prints one line per measure and, last, one JSON object.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from robocup_gym.soccer import game_v1, penalty_v1

MIXED = (0, 1, 2, 3, 4, 0, 1, 2, 3, 4, 0)


def _random_steps(env, rng: np.random.Generator, steps: int) -> None:
    """``steps`` steps of ``env`` (one step: every agent acts) with random actions (skills:
    walk commands), starting a new episode where one ended."""
    skills = env.skills is not None
    for _ in range(steps):
        if not env.agents:
            env.reset()
        acts = {a: rng.uniform(-1, 1, env.action_space(a).shape) for a in env.agents}
        if skills:
            for a in acts.values():
                a[3] = -1.0  # walk (kicks make robots fall: get-ups would dominate the figure)
        env.step(acts)


def _steps_per_s(env, steps: int, seed: int = 0) -> float:
    """Steps per second (one step: every agent acts), random actions (skills: walk commands)."""
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    t0 = time.perf_counter()
    _random_steps(env, rng, steps)
    return steps / (time.perf_counter() - t0)


def _moving_world(env):
    """``env``'s world after a reset, its robots given constant random joint speeds (they
    move, as in the game), to be stepped alone."""
    world = env.game.world
    env.reset(seed=0)
    rng = np.random.default_rng(1)
    for p in env.game.players:
        world.command(p.index, 0.2 * rng.uniform(-1, 1, len(world.robots[p.index].model.joints)))
    return world


def physics_per_s(env, cycles: int) -> float:
    """Cycles per second of ``env``'s world stepped alone (no perception, no rules), its robots
    moving (also used by ``team_games.py``)."""
    world = _moving_world(env)
    t0 = time.perf_counter()
    for _ in range(cycles):
        world.step()
    return cycles / (time.perf_counter() - t0)


def game_and_physics_per_s(game_env, physics_env, rounds: int, steps: int) -> tuple[float, float]:
    """Cycles per second of ``game_env`` (skill actions: ``steps`` steps of ``skill_cycles``
    cycles per round, random walk commands) and of ``physics_env``'s world stepped alone (as
    :func:`physics_per_s`, as many cycles per round), measured in alternating rounds: a change
    of the machine's speed during the run (other work, clock scaling) slows both alike, so
    their ratio holds."""
    rng = np.random.default_rng(0)
    game_env.reset(seed=0)
    world = _moving_world(physics_env)
    cycles = steps * game_env.config.skill_cycles  # a round's cycles
    game_s = physics_s = 0.0
    for _ in range(rounds):
        t0 = time.perf_counter()
        _random_steps(game_env, rng, steps)
        t1 = time.perf_counter()
        for _ in range(cycles):
            world.step()
        t2 = time.perf_counter()
        game_s += t1 - t0
        physics_s += t2 - t1
    return rounds * cycles / game_s, rounds * cycles / physics_s


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer cycles")
    parser.add_argument("--engine", choices=("ode", "mujoco"), default="ode")
    args = parser.parse_args(argv)
    n = 200 if args.quick else 1000
    out: dict = {"engine": args.engine, "quick": args.quick}
    with penalty_v1.parallel_env(engine=args.engine) as env:
        out["penalty_env_steps_per_s"] = round(_steps_per_s(env, n), 1)
    with game_v1.parallel_env(engine=args.engine, left_types=(0, 1), right_types=(0, 1)) as env:
        out["game_2v2_steps_per_s"] = round(_steps_per_s(env, n), 1)
    two = {"left_types": (0, 1), "right_types": (0, 1)}
    with game_v1.parallel_env(engine=args.engine, actions="skills", **two) as env:
        decisions = _steps_per_s(env, n // 10) * 4  # four agents decide each step
        out["game_2v2_skill_steps_per_s"] = round(decisions, 1)
    eleven = {"left_types": MIXED, "right_types": MIXED, "max_cycles": 100_000}
    with game_v1.parallel_env(engine=args.engine, **eleven) as env:
        out["game_11v11_joint_cycles_per_s"] = round(_steps_per_s(env, n // 2), 1)
        with game_v1.parallel_env(engine=args.engine, actions="skills", **eleven) as skills:
            game, physics = game_and_physics_per_s(skills, env, rounds=n // 100, steps=5)
    out["game_11v11_cycles_per_s"] = round(game, 1)
    out["physics_22_robots_cycles_per_s"] = round(physics, 1)
    out["game_vs_physics"] = round(
        out["game_11v11_cycles_per_s"] / out["physics_22_robots_cycles_per_s"], 3
    )
    for k, v in out.items():
        print(f"{k:34s} {v}")
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

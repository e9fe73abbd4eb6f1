"""Does what a policy does on the MuJoCo engine kick on SimSpark's physics? Open- and closed-loop.

A diagnostic of the engines' difference (the closed-loop table of every engine is
``benchmarks/transfer.py``). Runs deterministic episodes of a trained run (``robocup-gym train``
folder, trained on either engine) on the MuJoCo engine's world, records every placement and
joint command the environment sent to its world, and
replays the same commands, cycle for cycle, on ``robocup_gym.sim.engines.ode.OdeWorld`` (SimSpark's
step
on ODE itself, which reproduces the real server's kick D; needs ``libode8``). The replay is
open-loop: the policy does not see the ODE world's state. Also replays on a fresh MuJoCo world,
which must give the environment's own result (a check of the recording). Then runs the same
episodes closed-loop on the ``ode`` backend (the policy reads the ODE world's perceptors, as it
would on rcssserver3d; ``robocup-gym eval RUN --backend ode`` does this alone).

    python benchmarks/ode_transfer.py runs/velocity-kick-ppo-<time> --episodes 3

Prints one row per episode and, as the last line, one JSON object.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", help="a run folder written by robocup-gym train")
    parser.add_argument("--episodes", type=int, default=3)
    parser.add_argument("--seed", type=int, default=100_000)
    args = parser.parse_args(argv)

    from robocup_gym.sim.engines.mujoco.world import World
    from robocup_gym.sim.engines.ode import OdeUnavailableError, OdeWorld
    from robocup_gym.sim.engines.ode.compare import record_world, replay_recording
    from robocup_gym.train.episodes import run_episodes
    from robocup_gym.train.run import load_model, load_run
    from robocup_gym.train.tasks import make_env

    info = load_run(args.run)
    cfg = info.config
    if cfg.backend not in ("mujoco", "ode"):
        raise SystemExit(f"ode_transfer: {args.run} was trained on {cfg.backend}, not an engine")
    model = load_model(info)
    normalizer = info.obs_normalizer()
    env = make_env(cfg.env_id, backend="mujoco", env_kwargs=cfg.env_options())  # recorded there
    world = env.unwrapped.backend.world
    rows = []
    try:
        for k in range(args.episodes):
            with record_world(world) as rec:
                run_episodes(
                    model, env, 1, seed=args.seed + k, obs_normalizer=normalizer, deterministic=True
                )
            start = np.array(
                [arg[0][:2] for kind, arg in rec.calls if kind == "ball"][-1], dtype=float
            )
            env_ball = world.ball_position()[:2] - start
            types = [r.model.robot_type.index for r in world.robots]
            replays = {}
            for name, make in (("mujoco", World), ("ode", OdeWorld)):
                try:
                    w = make(types)
                except OdeUnavailableError as e:
                    print(f"ode_transfer: {e}", file=sys.stderr)
                    raise SystemExit(2) from None
                torso = []
                replay_recording(rec, w, on_cycle=lambda w, t=torso: t.append(w.torso_position(0)))
                replays[name] = (w.ball_position()[:2] - start, np.array(torso), w.torso_up(0)[2])
            apart = np.linalg.norm(replays["mujoco"][1] - replays["ode"][1], axis=1)
            off = np.flatnonzero(apart > 0.01)
            rows.append(
                {
                    "episode": k,
                    "cycles": rec.cycles,
                    "env_ball_dx_m": round(float(env_ball[0]), 4),
                    "mujoco_replay_ball_dx_m": round(float(replays["mujoco"][0][0]), 4),
                    "ode_replay_ball_dx_m": round(float(replays["ode"][0][0]), 4),
                    "ode_replay_fell": bool(replays["ode"][2] < 0.5),
                    "torsos_1cm_apart_from_cycle": int(off[0]) + 1 if len(off) else None,
                }
            )
    finally:
        env.close()
    ode_env = make_env(cfg.env_id, backend="ode", env_kwargs=cfg.env_options())
    try:
        for k, row in enumerate(rows):
            (rec,) = run_episodes(
                model, ode_env, 1, seed=args.seed + k, obs_normalizer=normalizer, deterministic=True
            )
            row["ode_closed_loop_ball_dx_m"] = round(float(rec["ball_dx"]), 4)
            row["ode_closed_loop_fell"] = bool(rec.get("fell", 0.0))
    finally:
        ode_env.close()
    print(
        f"{'episode':>8}{'cycles':>8}{'env Δx m':>10}{'MuJoCo replay':>15}{'ODE replay':>12}"
        f"{'ODE fell':>10}{'>1cm at':>9}{'ODE closed loop':>17}{'fell':>6}"
    )
    for r in rows:
        fell = "yes" if r["ode_replay_fell"] else "no"
        apart = r["torsos_1cm_apart_from_cycle"] or "-"
        closed_fell = "yes" if r["ode_closed_loop_fell"] else "no"
        print(
            f"{r['episode']:>8}{r['cycles']:>8}{r['env_ball_dx_m']:>10.3f}"
            f"{r['mujoco_replay_ball_dx_m']:>15.3f}{r['ode_replay_ball_dx_m']:>12.3f}"
            f"{fell:>10}{apart:>9}{r['ode_closed_loop_ball_dx_m']:>17.3f}{closed_fell:>6}"
        )

    def mean(key: str) -> float:
        return round(float(np.mean([r[key] for r in rows])), 4)

    summary = {
        "run": str(info.path),
        "episodes": rows,
        "env_ball_dx_mean": mean("env_ball_dx_m"),
        "ode_replay_ball_dx_mean": mean("ode_replay_ball_dx_m"),
        "ode_closed_loop_ball_dx_mean": mean("ode_closed_loop_ball_dx_m"),
    }
    print(json.dumps(summary))
    return summary


if __name__ == "__main__":
    main()

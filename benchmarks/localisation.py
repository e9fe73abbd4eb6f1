"""How well does a player know where it is from its own perceptors? And does the game's walk
still walk on that estimate?

On the default engine with rcssserver3d's vision noise, the game's walk (``game-walk``) walks for
``--seconds`` at each command while :class:`robocup_gym.soccer.localisation.Estimator` follows it
from the robot's own perceptors (vision every third cycle, head joints, gyroscope,
accelerometer, foot pressure); each cycle its estimate is compared with ground truth. Then the
same episodes are walked with the estimate in the policy's observation instead of ground truth
(as ``robocup-gym team`` plays), against ground truth in the same run.

Prints one line per command and, last, one JSON object: ``position_error_m_median``,
``heading_error_deg_median``, ``velocity_error_mps_median``, ``ball_error_m_median``, and per
command the speed and falls on ground truth and on the estimate (``false_falls``: episodes the
walk ended because the estimate said the robot was down while it was not).

    python benchmarks/localisation.py --episodes 10
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from robocup_gym.backends import make_backend
from robocup_gym.envs.observations import heading_frame, up_z
from robocup_gym.soccer.localisation import Estimator
from robocup_gym.train.pretrained import pretrained_env, pretrained_policy

COMMANDS = ((0.5, 0.0, 0.0), (0.0, 0.0, 0.0), (0.3, 0.0, 20.0))
"""Walk commands (forward m/s, left m/s, turn deg/s)."""


def _heading_deg(quat: np.ndarray) -> float:
    c, s = heading_frame(quat)
    return math.degrees(math.atan2(s, c))


def walk(policy, command, seed: int, cycles: int, robot_type: int, on_estimate: bool) -> dict:
    """One episode; the errors of the estimate each cycle, the distance walked and a fall."""
    backend = make_backend("ode", vision=True, robot_type=robot_type)
    env = pretrained_env(
        policy, backend, {"command_change_steps": 0, "robot_type": robot_type}
    ).unwrapped
    obs, _ = env.reset(seed=seed, options={"velocity_command": command})
    start = env.ground_truth
    est = Estimator(env.robot_model)
    est.place(start.torso_pos[0], start.torso_pos[1], _heading_deg(start.torso_quat))
    inner = backend.step
    truth: dict = {}

    def step(cmd):  # the estimate replaces ground truth in what the policy observes
        p = inner(cmd)
        truth["gt"] = p.ground_truth
        e = est.update(p)
        truth["est"] = e
        if on_estimate and e is not None:
            p.ground_truth = e
        return p

    backend.step = step
    errors = []
    fallen = stopped = False
    for _ in range(cycles):
        obs, _, terminated, truncated, _ = env.step(policy(obs[None])[0])
        gt, e = truth["gt"], truth["est"]
        dh = (_heading_deg(e.torso_quat) - _heading_deg(gt.torso_quat) + 180.0) % 360.0 - 180.0
        errors.append(
            (
                float(np.hypot(*(e.torso_pos[:2] - gt.torso_pos[:2]))),
                abs(dh),
                float(np.hypot(*(e.torso_vel[:2] - gt.torso_vel[:2]))),
                float(np.hypot(*(e.ball_pos[:2] - gt.ball_pos[:2]))),
            )
        )
        if up_z(gt.torso_quat) < 0.5:
            fallen = True
            break
        if terminated:  # the walk thought it fell: the estimate said so
            stopped = True
        if terminated or truncated:
            break
    moved = gt.torso_pos[:2] - start.torso_pos[:2]
    env.close()
    return {
        "errors": errors,
        "speed": float(np.hypot(*moved)) / (len(errors) * 0.02),
        "fallen": fallen,
        "stopped": stopped,
    }


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=5, help="episodes per command and mode")
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--robot-type", type=int, default=0)
    args = ap.parse_args(argv)
    policy = pretrained_policy("game-walk")
    cycles = round(args.seconds / 0.02)
    all_errors = []
    per_command = []
    for command in COMMANDS:
        row = {"command": list(command)}
        for mode, on_estimate in (("ground_truth", False), ("estimate", True)):
            runs = [
                walk(policy, command, seed, cycles, args.robot_type, on_estimate)
                for seed in range(args.episodes)
            ]
            if not on_estimate:
                all_errors += [e for r in runs for e in r["errors"]]
            row[f"{mode}_speed_mps"] = round(float(np.mean([r["speed"] for r in runs])), 3)
            row[f"{mode}_falls"] = sum(r["fallen"] for r in runs)
            row[f"{mode}_false_falls"] = sum(r["stopped"] for r in runs)
        per_command.append(row)
        print(
            f"command {command}: on ground truth {row['ground_truth_speed_mps']:.3f} m/s, "
            f"{row['ground_truth_falls']} falls; on the estimate {row['estimate_speed_mps']:.3f}"
            f" m/s, {row['estimate_falls']} falls (of {args.episodes})",
            flush=True,
        )
    e = np.array(all_errors)
    out = {
        "episodes_per_command": args.episodes,
        "seconds": args.seconds,
        "robot_type": args.robot_type,
        "position_error_m_median": round(float(np.median(e[:, 0])), 4),
        "position_error_m_p90": round(float(np.percentile(e[:, 0], 90)), 4),
        "heading_error_deg_median": round(float(np.median(e[:, 1])), 3),
        "velocity_error_mps_median": round(float(np.median(e[:, 2])), 4),
        "ball_error_m_median": round(float(np.median(e[:, 3])), 4),
        "per_command": per_command,
    }
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

"""Speed of training on a real rcssserver3d: VelocityKick env steps per second with resets, and
the reset time.

Runs where a real rcssserver3d is installed (``RCSSSERVER3D`` or on ``PATH``; see
docs/rcssserver3d.md); elsewhere it says so and exits 0 with ``{"skipped": ...}``. One environment
on the ``rcssserver3d`` backend in launch mode (its own server, sync mode, real time off), random
actions, the episodes as the task defines them (40 steps, then the 20 wait cycles), every reset
and wait cycle counted in the wall time. Reference: the paper's code ran VelocityKick at ~208 env
steps/s with resets on a 2-core machine; the target is twice that, and resets within 30 ms.

    python benchmarks/real_server.py [--steps 2000] [--robot-type 0]

Prints one JSON object last: ``env_steps_per_s``, ``reset_ms_median``, ``reset_ms_p90``,
``reset_cycles_median``, ``episodes``, ``vs_paper`` (env_steps_per_s / 208), and the **start
residuals**: after a reset to the paper's crouch with the ball in front, what the real server's
first perception and monitor show against what the in-process ODE engine places for the same
start (``start_joint_deg_max``, ``start_torso_m``, ``start_tilt_deg``, ``start_ball_m``;
medians over ``--residual-resets`` resets, each after a few random steps).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

PAPER_STEPS_PER_S = 208.0


def start_residuals(binary: str, resets: int, robot_type: int) -> dict:
    """Medians over ``resets`` resets of the differences between a real-server reset and the
    in-process ODE engine's placement of the same start (see the module docstring)."""
    from robocup_gym.backends import RobotPose, make_backend
    from robocup_gym.envs.config import PAPER_STANDING_POSE_DEG, resolve_angles
    from robocup_gym.robot.nao import nao_model
    from robocup_gym.types import AgentCommand

    angles = resolve_angles(nao_model(robot_type), PAPER_STANDING_POSE_DEG, "pose")
    pose = RobotPose(-1.0, 0.0, heading_deg=0.0, joint_angles_deg=angles)
    ball = (-0.8, -0.055, 0.042)
    ode = make_backend("ode", robot_type=robot_type)
    real = make_backend("rcssserver3d", binary=binary, robot_type=robot_type)
    rows = []
    try:
        ref = ode.reset_episode(pose, ball_pos=ball)
        rng = np.random.default_rng(0)
        for _ in range(resets):
            for _ in range(10):
                real.step(AgentCommand(rng.uniform(-2.0, 2.0, len(angles))))
            p = real.reset_episode(pose, ball_pos=ball)
            g, r = p.ground_truth, ref.ground_truth
            up_real = _up(g.torso_quat)
            up_ref = _up(r.torso_quat)
            tilt = np.degrees(np.arccos(np.clip(up_real @ up_ref, -1.0, 1.0)))
            rows.append(
                (
                    float(np.abs(p.joint_angles_deg - ref.joint_angles_deg).max()),
                    float(np.linalg.norm(g.torso_pos - r.torso_pos)),
                    float(tilt),
                    float(np.linalg.norm(g.ball_pos - r.ball_pos)),
                )
            )
    finally:
        real.close()
        ode.close()
    med = np.median(np.array(rows), axis=0)
    return {
        "start_joint_deg_max": round(float(med[0]), 3),
        "start_torso_m": round(float(med[1]), 4),
        "start_tilt_deg": round(float(med[2]), 2),
        "start_ball_m": round(float(med[3]), 4),
        "residual_resets": resets,
    }


def _up(quat) -> np.ndarray:
    """The torso's up axis in world coordinates for orientation ``quat`` (w, x, y, z)."""
    w, x, y, z = (float(v) for v in quat)
    return np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--robot-type", type=int, default=0)
    parser.add_argument("--residual-resets", type=int, default=10)
    args = parser.parse_args()

    import gymnasium

    import robocup_gym.envs  # noqa: F401  (registers the environments)
    from robocup_gym.backends.process import RcssServerNotFoundError, find_binary

    try:
        binary = find_binary()
    except RcssServerNotFoundError as exc:
        print(json.dumps({"skipped": str(exc).split(". ")[0]}))
        return
    env = gymnasium.make(
        "RobocupGym/VelocityKick-v0",
        backend="rcssserver3d",
        backend_options={"binary": binary},
        robot_type=args.robot_type,
    )
    try:
        backend = env.unwrapped.backend
        env.action_space.seed(0)
        env.reset(seed=0)  # the server's start and the first reset are not timed
        reset_ms, reset_cycles, episodes = [], [], 0
        start = time.perf_counter()
        for _ in range(args.steps):
            _, _, terminated, truncated, _ = env.step(env.action_space.sample())
            if terminated or truncated:
                t0 = time.perf_counter()
                env.reset()
                reset_ms.append((time.perf_counter() - t0) * 1e3)
                reset_cycles.append(backend.last_reset.cycles)
                episodes += 1
        elapsed = time.perf_counter() - start
    finally:
        env.close()
    rate = args.steps / elapsed
    residuals = start_residuals(binary, args.residual_resets, args.robot_type)
    print(
        json.dumps(
            {
                "binary": binary,
                "env_steps_per_s": round(rate, 1),
                "vs_paper": round(rate / PAPER_STEPS_PER_S, 2),
                "reset_ms_median": round(float(np.median(reset_ms)), 1) if reset_ms else None,
                "reset_ms_p90": round(float(np.percentile(reset_ms, 90)), 1) if reset_ms else None,
                "reset_cycles_median": float(np.median(reset_cycles)) if reset_cycles else None,
                "episodes": episodes,
                **residuals,
            }
        )
    )


if __name__ == "__main__":
    main()

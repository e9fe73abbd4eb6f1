"""How well does a policy walk? Forward speed, falls, and sideways and turn tracking.

Runs a trained Walk or Run policy (``robocup-gym train walk`` or ``run`` folder)
deterministically on the default engine for ``--episodes`` episodes per command, each as long
as the run's episodes (10 s by default), with the command held fixed:

* forward ``--forward`` m/s (default 0.5 on Walk, 1.5 on Run; the reference team walks 0.81 m/s
  on rcssserver3d): mean forward speed over the episode (displacement along the start heading /
  time) and the falls;
* sideways 0.3 m/s to the left: mean error of the leftward speed;
* turning 30 deg/s: mean error of the turn rate.

A task that only ever runs straight ahead (``Run-v1``: no sideways or turn commands) is
measured forward alone.

``--tracking`` measures the omnidirectional walk's targets instead: forward 0.8 m/s,
sideways 0.4 m/s, turning 60 deg/s (each within 10 % of the command: the planar velocity's
error, drift included, over the commanded speed; the turn rate's over the commanded rate;
measured over the episode's last 6 s, once the gait is up to speed) and stopping when told
(0.5 m/s forward for 4 s, then told to stand: the speed over the last 4 s), with no fall; the
JSON gets ``tracking`` (each command's figures and ``error_fraction``), ``stop_speed_mps`` and
``meets_tracking_target``.

``pretrained:NAME`` runs a shipped policy; ``zero`` runs a policy that sends zero actions (a
baseline, and a smoke test without a trained run). ``--robot-type N`` runs another Nao type,
``--backend rcssserver3d`` a real server (``serve``: a ``robocup-gym serve`` of its own). Prints one
line per command and, as the last line, one JSON object (``forward_speed_mps``, ``falls``,
``sideways_error_mps``, ``turn_error_deg_s``, …).

    python benchmarks/walk.py runs/walk-ppo-<time> --episodes 20
    python benchmarks/walk.py pretrained:run --episodes 20     # forward 1.5 m/s

``meets_target`` in the JSON: at least the commanded forward speed, no falls.
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from robocup_gym.envs.observations import heading_frame

COMMANDS = {
    "forward": (0.5, 0.0, 0.0),
    "sideways": (0.0, 0.3, 0.0),
    "turn": (0.0, 0.0, 30.0),
}
TRACKING_COMMANDS = {
    "forward": (0.8, 0.0, 0.0),
    "sideways": (0.0, 0.4, 0.0),
    "turn": (0.0, 0.0, 60.0),
}
"""The omnidirectional walk's targets: each followed within :data:`TRACKING_TOLERANCE`."""
TRACKING_TOLERANCE = 0.1
"""Largest error of a tracked command, a fraction of the command."""
TRACKING_SETTLE_S = 4.0
"""With ``--tracking`` the speeds are measured after this much of an episode (the gait eases
in and speeds up first)."""
STOP_AFTER_S = 4.0
"""The stop test walks this long, then is told to stand …"""
STOP_SPEED_MPS = 0.05
"""… and must move slower than this over the rest of the episode (from 2 s after the order)."""


def run(
    env,
    act,
    command,
    episodes: int,
    seed: int,
    from_s: float = 0.0,
    stop_after_s: float | None = None,
) -> dict:
    """Episodes with ``command`` held (no other mid-episode changes): speeds (measured from
    ``from_s`` into the episode on) and falls. ``stop_after_s``: told to stand from then on."""
    u = env.unwrapped
    u.config = u.config.replace(command_change_steps=0)
    speeds, lefts, turns, falls = [], [], [], 0
    for k in range(episodes):
        obs, info = env.reset(seed=seed + k, options={"velocity_command": command})
        start = u.torso_pos.copy()
        start_heading = math.radians(u.config.robot_start_heading_deg)
        heading, turned = _heading(u.ground_truth.torso_quat), 0.0
        done, steps, measured = False, 0, 0
        while not done:
            if stop_after_s is not None and steps == round(stop_after_s / 0.02):
                u.velocity_command[:] = 0.0
            if steps == round(from_s / 0.02):  # the measured stretch starts here
                start, turned, measured = u.torso_pos.copy(), 0.0, 0
                start_heading = _heading(u.ground_truth.torso_quat) if from_s else start_heading
            obs, _, terminated, truncated, info = env.step(act(obs))
            steps += 1
            measured += 1
            done = terminated or truncated
            now = _heading(u.ground_truth.torso_quat)
            turned += _wrap(now - heading)  # summed per step: turns past 180° count whole
            heading = now
        t = max(measured, 1) * 0.02
        d = u.torso_pos - start
        fwd = d[0] * math.cos(start_heading) + d[1] * math.sin(start_heading)
        left = -d[0] * math.sin(start_heading) + d[1] * math.cos(start_heading)
        dyaw = math.degrees(turned)
        speeds.append(fwd / t)
        lefts.append(left / t)
        turns.append(dyaw / t)
        falls += int(bool(info.get("fallen")))
    return {
        "forward_speed_mps": float(np.mean(speeds)),
        "left_speed_mps": float(np.mean(lefts)),
        "turn_rate_deg_s": float(np.mean(turns)),
        "falls": falls,
        "episodes": episodes,
    }


def tracking(env, act, episodes: int, seed: int) -> dict:
    """The omnidirectional walk's targets (:data:`TRACKING_COMMANDS`, stopping when told)."""
    out: dict = {"tracking": {}}
    worst = 0.0
    falls = 0
    for name, command in TRACKING_COMMANDS.items():
        res = run(env, act, command, episodes, seed, from_s=TRACKING_SETTLE_S)
        if name == "turn":
            error = abs(res["turn_rate_deg_s"] - command[2]) / abs(command[2])
        else:  # the planar velocity's error, sideways drift included
            error = math.hypot(
                res["forward_speed_mps"] - command[0], res["left_speed_mps"] - command[1]
            ) / math.hypot(command[0], command[1])
        res["error_fraction"] = error
        worst = max(worst, res["error_fraction"])
        falls += res["falls"]
        out["tracking"][name] = res
        print(_line(name, command, res, f" (error {100 * error:.0f} %)"))
    stop = run(
        env,
        act,
        (0.5, 0.0, 0.0),
        episodes,
        seed,
        from_s=STOP_AFTER_S + 2.0,
        stop_after_s=STOP_AFTER_S,
    )
    speed = math.hypot(stop["forward_speed_mps"], stop["left_speed_mps"])
    falls += stop["falls"]
    out["tracking"]["stop"] = stop
    print(
        f"stop      after {STOP_AFTER_S:.0f} s at 0.5 m/s: {speed:.3f} m/s, falls {stop['falls']}"
    )
    out["tracking_error_fraction_max"] = worst
    out["stop_speed_mps"] = speed
    out["tracking_falls"] = falls
    out["meets_tracking_target"] = (
        worst <= TRACKING_TOLERANCE and speed < STOP_SPEED_MPS and falls == 0
    )
    return out


def _line(name: str, command, res: dict, extra: str = "") -> str:
    """One command's result as the benchmark prints it."""
    return (
        f"{name:9s} command {command}: forward {res['forward_speed_mps']:+.3f} m/s, left "
        f"{res['left_speed_mps']:+.3f} m/s, turn {res['turn_rate_deg_s']:+.1f} deg/s{extra}, "
        f"falls {res['falls']}/{res['episodes']}"
    )


def _heading(quat) -> float:
    """Heading of the torso (rad, counter-clockwise from world +x, as the turn command)."""
    cos, sin = heading_frame(quat)
    return math.atan2(sin, cos)


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def main(argv: list[str] | None = None) -> dict:
    from robocup_gym.envs import Run
    from robocup_gym.train.evaluate import add_benchmark_options, benchmark_policy_and_env

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_benchmark_options(parser, "Walk or Run", episodes=20)
    parser.add_argument(
        "--task",
        choices=("walk", "run"),
        default="walk",
        help="the task a 'zero' policy runs (a run folder or a shipped policy brings its own)",
    )
    parser.add_argument(
        "--forward",
        type=float,
        default=None,
        help="the forward command, m/s (default 0.5 on Walk, 1.5 on Run)",
    )
    parser.add_argument(
        "--tracking",
        action="store_true",
        help="measure the omnidirectional walk's targets (0.8 m/s forward, 0.4 m/s sideways, "
        "60 deg/s turning within 10 %%, and stopping when told) instead",
    )
    args = parser.parse_args(argv)
    forward = args.forward
    if forward is not None and not (math.isfinite(forward) and forward > 0.0):
        raise SystemExit(f"--forward must be a speed above 0 m/s, got {forward}")
    env_id = "RobocupGym/Run-v1" if args.task == "run" else "RobocupGym/Walk-v0"
    env, act = benchmark_policy_and_env(args, env_id)
    if forward is None:
        forward = 1.5 if isinstance(env.unwrapped, Run) else 0.5
    commands = dict(COMMANDS, forward=(forward, 0.0, 0.0))
    config = env.unwrapped.config
    sprint = not any(config.sideways_speed_range) and not any(config.turn_rate_range)
    if sprint:  # a task that only ever runs straight ahead (Run-v1): forward alone
        commands = {"forward": commands["forward"]}
    out: dict = {
        "policy": args.policy,
        "episodes_per_command": args.episodes,
        "robot_type": env.unwrapped.config.robot_type,
    }
    if args.tracking:
        try:
            out.update(tracking(env, act, args.episodes, args.seed))
        finally:
            env.close()
        print(json.dumps(out))
        return out
    try:
        for name, command in commands.items():
            res = run(env, act, command, args.episodes, args.seed)
            out[name] = res
            print(_line(name, command, res))
    finally:
        env.close()
    out["forward_speed_mps"] = out["forward"]["forward_speed_mps"]
    out["falls"] = out["forward"]["falls"]
    if not sprint:
        out["sideways_error_mps"] = abs(out["sideways"]["left_speed_mps"] - COMMANDS["sideways"][1])
        out["turn_error_deg_s"] = abs(out["turn"]["turn_rate_deg_s"] - COMMANDS["turn"][2])
    out["forward_command_mps"] = forward
    out["meets_target"] = out["forward_speed_mps"] >= forward and out["falls"] == 0
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

"""Is the in-process league world exactly RCSSServerMJ? And how much faster is it?

Starts a real ``rcssservermj`` (``python -m rcsssmj``, this interpreter's, sync mode, real time
off, no viewer, OS-chosen ports) with one agent (a T1 by default) and an in-process
:class:`~robocup_gym.sim.engines.rcsssmj.LeagueWorld` from the same state (the server's idle
cycles before the agent joined are read off its first perception). Both get the same command
sequence: every cycle random PD targets on every joint (``q`` uniform in ±30° inside the joint's
range, ``kp`` 20, ``kd`` 1). Every cycle the perception the agent receives is compared with the
in-process one, byte for byte, and the values in it (joint angles, torso position and
orientation; the ball is compared in-process against the server's monitor-free proxy: its
vision polar coordinates when both see it).

    python benchmarks/rcssservermj_match.py [--cycles 500] [--robot T1]

Prints one JSON object last: ``identical_perceptions`` (of ``cycles``),
``max_joint_deg_diff``, ``max_torso_m_diff``, ``max_ball_m_diff`` (from the perceptions' values:
0 means equal to the wire's precision, which is the server's only output), and the speed:
``server_cycles_per_s`` (the real server with this client), ``inprocess_cycles_per_s``
(:meth:`LeagueWorld.cycle`, same commands) and their ratio ``speedup``; the same without making
perceptions (``inprocess_no_perception_cycles_per_s``, ``speedup_no_perception``, and
``no_perception_same_state``: whether the state ends bit-equal).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import time

import numpy as np

_HJ = re.compile(rb"\(HJ \(n ([^)\s]+)\)\(ax ([-0-9.e]+)\)")
_POS = re.compile(rb"\(pos \(n torso_pos\) \(p ([-0-9.e]+) ([-0-9.e]+) ([-0-9.e]+)\)\)")
_BALL = re.compile(rb"\(B \(pol ([-0-9.e]+) ([-0-9.e]+) ([-0-9.e]+)\)\)")


def _values(p: bytes) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    joints = np.array([float(v) for _, v in _HJ.findall(p)])
    pos = _POS.search(p)
    torso = np.array([float(v) for v in pos.groups()]) if pos else np.full(3, np.nan)
    ball = _BALL.search(p)
    return joints, torso, None if ball is None else np.array([float(v) for v in ball.groups()])


def _polar_to_xyz(pol: np.ndarray) -> np.ndarray:
    d, az, el = pol[0], math.radians(pol[1]), math.radians(pol[2])
    return d * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])


def commands_for(robot, rng: np.random.Generator) -> dict:
    """One cycle of random PD commands for every joint of ``robot`` (a
    :class:`~robocup_gym.robot.league.LeagueRobot`; see the module docstring)."""
    from robocup_gym.sim.engines.rcsssmj import PDCommand

    out = {}
    for name, joint in zip(robot.effector_names, robot.joints, strict=True):
        lo, hi = joint.range_deg
        q = float(np.clip(rng.uniform(-30.0, 30.0), lo, hi))
        out[name] = PDCommand(q, 0.0, 20.0, 1.0, 0.0)
    return out


def run(cycles: int = 500, robot: str = "T1", seed: int = 0) -> dict:
    """The comparison of the module docstring; returns the summary."""
    from robocup_gym.backends.rcssservermj import (
        LeagueAgentLink,
        RcssServerMJProcess,
        format_pd_commands,
    )
    from robocup_gym.robot.league import league_robot
    from robocup_gym.sim.engines.rcsssmj import LeagueWorld

    rng = np.random.default_rng(seed)
    model = league_robot(robot)
    sequence = [commands_for(model, rng) for _ in range(cycles)]
    identical = 0
    max_j = max_t = max_b = 0.0
    ball_seen = 0
    first_difference = None
    # The server first (it drops an agent that does not answer within 5 s), then in-process.
    # Both join with zero-filled heap memory (robocup_gym.sim.engines.rcsssmj.join), so the
    # server's start is reproduced exactly, wherever this runs.
    with (
        RcssServerMJProcess(monitor=False) as server,  # no monitor work: its best speed
        LeagueAgentLink(server.agent_port, robot, "A", 1) as a,
    ):
        first = a.recv()
        pairs: list[tuple[bytes, bytes | None]] = [(first, None)]
        t0 = time.perf_counter()
        for cmds in sequence:
            a.send(format_pd_commands(cmds))
            pairs.append((a.recv(), None))
        server_s = time.perf_counter() - t0
    world = LeagueWorld.joining_as([(robot, "A", 1)], [first])
    pairs[0] = (first, first)  # (joining_as found the start that reproduces it exactly)
    t0 = time.perf_counter()
    for k, cmds in enumerate(sequence):
        world.command(0, cmds)
        pairs[k + 1] = (pairs[k + 1][0], world.cycle()[0])
    inprocess_s = time.perf_counter() - t0
    # the same commands again, without making perceptions (a learner that reads the state)
    lean = LeagueWorld.joining_as([(robot, "A", 1)], [first])
    t0 = time.perf_counter()
    for cmds in sequence:
        lean.command(0, cmds)
        lean.cycle(perceive=False)
    lean_s = time.perf_counter() - t0
    same_state = bool(
        np.array_equal(lean.joint_angles(0), world.joint_angles(0))
        and np.array_equal(lean.ball_position(), world.ball_position())
    )
    for k, (theirs, ours) in enumerate(pairs):
        if theirs == ours:
            identical += 1
        elif first_difference is None:
            first_difference = k
        (jt, tt, bt), (jo, to, bo) = _values(theirs), _values(ours)
        if jt.shape == jo.shape:
            max_j = max(max_j, float(np.abs(jt - jo).max(initial=0.0)))
        else:
            max_j = math.inf
        max_t = max(max_t, float(np.abs(tt - to).max()))
        if bt is not None and bo is not None:
            ball_seen += 1
            max_b = max(max_b, float(np.linalg.norm(_polar_to_xyz(bt) - _polar_to_xyz(bo))))
    return {
        "robot": robot,
        "cycles": cycles,
        "identical_perceptions": identical - 1,  # (the first one is not a commanded cycle)
        "first_perception_identical": pairs[0][0] == pairs[0][1],
        "first_difference_at_cycle": first_difference,
        "max_joint_deg_diff": max_j,
        "max_torso_m_diff": max_t,
        "max_ball_m_diff": max_b,
        "ball_seen_in": ball_seen,
        "server_cycles_per_s": round(cycles / server_s, 1),
        "inprocess_cycles_per_s": round(cycles / inprocess_s, 1),
        "speedup": round(server_s / inprocess_s, 2),
        "inprocess_no_perception_cycles_per_s": round(cycles / lean_s, 1),
        "speedup_no_perception": round(server_s / lean_s, 2),
        "no_perception_same_state": same_state,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles", type=int, default=500)
    parser.add_argument("--robot", default="T1")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(json.dumps(run(args.cycles, args.robot, args.seed)))


if __name__ == "__main__":
    main()

"""Replays of the real server's measured cases (``robocup_gym/data``) on the embedded world.

Used by ``benchmarks/fidelity.py`` and the tests. The figures measured on rcssserver3d 0.7.3 are
kept in ``robocup_gym/data/real_server_figures.json`` and the scripted kick in ``kick_D.json``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from importlib import resources

import numpy as np

from robocup_gym.robot.nao import nao_model
from robocup_gym.sim.engines.mujoco.world import World

BALL_MOVE_THRESHOLD_M = 0.005
"""Ball displacement that counts as "moved" (the monitor only re-sends a transform when it changes
by more than 0.005, which is how the real server's first-move cycle was measured)."""


def load_data(name: str) -> dict:
    """A JSON file from ``robocup_gym/data`` (real-server measurements)."""
    return json.loads(resources.files("robocup_gym.data").joinpath(name).read_text())


@dataclass
class StandResult:
    """Outcome of standing still with all joint velocities 0."""

    fell: bool
    torso_z_m: float
    """Mean torso-centre height over the last second, m."""
    head_z_m: float
    max_joint_drift_deg: float


def stand(seconds: float = 60.0, robot_type: int = 0, world: World | None = None) -> StandResult:
    """Stand with zero joint velocities for ``seconds`` and report the torso height (on the
    MuJoCo world by default, or on ``world``: either engine's)."""
    w = world or World([robot_type])
    w.place_robot(0, x=-1.0, y=0.0, heading_deg=0.0)
    w.place_ball((5.0, 5.0))
    cycles = round(seconds / 0.02)
    last = max(1, min(50, cycles))
    zs, hs = [], []
    zero = np.zeros(len(w.robots[0].model.joints))
    fell = False
    for c in range(cycles):
        w.step({0: zero})
        if w.torso_up(0)[2] < 0.5 or w.torso_position(0)[2] < 0.25:
            fell = True
        if c >= cycles - last:
            zs.append(w.torso_position(0)[2])
            hs.append(w._head_pose(0)[0][2])
    return StandResult(
        fell=fell,
        torso_z_m=float(np.mean(zs)),
        head_z_m=float(np.mean(hs)),
        max_joint_drift_deg=float(np.abs(w.joint_angles_deg(0)).max()),
    )


@dataclass
class KickResult:
    """Outcome of a scripted open-loop kick."""

    ball_displacement_m: float
    """Ball displacement on the ground plane after the sequence, m."""
    first_move_cycle: int | None
    """1-based cycle of the sequence in which the ball had first moved > 5 mm."""
    peak_speed_mps: float
    peak_speed_cycle: int
    robot_fell: bool
    ball_final: np.ndarray


def scripted_kick(spec: dict | None = None, world: World | None = None) -> KickResult:
    """Replay a scripted kick in the format of ``kick_D.json``: same placement, same commands
    (every cycle all joints are sent, unlisted joints 0 rad/s), one-cycle dead time as in sync
    mode.

    The robot is placed as the trainer's ``move`` put it: torso centre at ``torso_before_kick``
    (z = 0.385 m, all joints 0: the soles exactly at z = 0, ~2 mm above the resting height) and
    asleep. On the real server ODE's auto-disable keeps it hanging there through the zero-velocity
    cycles until the first non-zero joint velocity wakes it (fixture README); it then falls those
    2 mm while the kick starts."""
    spec = spec or load_data("kick_D.json")
    w = world or World([int(spec.get("robot_type", 0))])
    model = nao_model(int(spec.get("robot_type", 0)))
    torso = spec["torso_before_kick"]
    z = torso[2] if len(torso) > 2 else None
    w.place_robot(0, x=torso[0], y=torso[1], z=z, heading_deg=0.0, asleep=True)
    start = np.array(spec["ball_start"][:2], dtype=float)
    w.place_ball(start)
    names = model.effector_names
    first_move = None
    peak, peak_cycle = 0.0, 0
    fell = False
    cycle = 0
    for block in spec["command_sequence"]:
        vel = np.zeros(len(names))
        for name, v in block["velocities_rad_per_s"].items():
            vel[names.index(name)] = v
        for _ in range(int(block["cycles"])):
            cycle += 1
            w.step({0: vel})
            pos = w.ball_position()
            if first_move is None and np.linalg.norm(pos[:2] - start) > BALL_MOVE_THRESHOLD_M:
                first_move = cycle
            speed = float(np.linalg.norm(w.ball_velocity()[:2]))
            if speed > peak:
                peak, peak_cycle = speed, cycle
            if w.torso_up(0)[2] < 0.5:
                fell = True
    final = w.ball_position()
    return KickResult(
        ball_displacement_m=float(np.linalg.norm(final[:2] - start)),
        first_move_cycle=first_move,
        peak_speed_mps=peak,
        peak_speed_cycle=peak_cycle,
        robot_fell=fell,
        ball_final=final,
    )

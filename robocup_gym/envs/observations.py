"""Observation components: what each one contains, its units and its analytic range.

An observation is the concatenation of the components named in
:attr:`EnvConfig.observations` (then normalised, noised, clipped and frame-stacked). The analytic
range ``[lo, hi]`` of each value is what ``normalise="min_max"`` maps onto [-1, 1]; values outside
it are possible (e.g. a hard impact on the accelerometer) and are cut by ``obs_clip``.

Frames used below:

* **heading frame**: centred on the torso, x = the robot's forward direction projected on the
  ground, y = to the robot's left, z = world up (for a robot facing +x it is the world frame
  shifted to the torso);
* **torso frame** (SimSpark's, for the sensors): x = robot's right, y = forward, z = up.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from robocup_gym.robot.nao import NaoModel

__all__ = ["COMPONENTS", "Component", "ObservationContext", "component_names", "up_z"]


@dataclass(frozen=True)
class ObservationContext:
    """What the size and range of a component depend on."""

    model: NaoModel
    observed_joints: np.ndarray
    """Canonical indices of the joints in ``joint_pos``/``joint_vel``."""
    n_action: int
    max_episode_steps: int


@dataclass(frozen=True)
class Component:
    """One named observation component."""

    name: str
    description: str
    units: str
    range_doc: str
    bounds: Callable[[ObservationContext], tuple[np.ndarray, np.ndarray]]
    labels: Callable[[ObservationContext], list[str]]
    write: Callable[[Any, np.ndarray], None] | None = None
    """Fills the component's slice of an environment's raw frame: ``write(env, out)`` (raw
    units, before normalisation), reading the environment's latest perception and state."""
    needs_ground_truth: bool = False
    needs_vision: bool = False
    needs_toes: bool = False

    def size(self, ctx: ObservationContext) -> int:
        return len(self.labels(ctx))


def _const(lo: list[float], hi: list[float]):
    def f(ctx: ObservationContext) -> tuple[np.ndarray, np.ndarray]:
        return np.array(lo, float), np.array(hi, float)

    return f


def _labels(prefix: str, names: list[str]):
    return lambda ctx: [f"{prefix}/{n}" for n in names]


def _joint_pos_bounds(ctx):
    r = ctx.model.ranges_deg[ctx.observed_joints]
    return r[:, 0].astype(float), r[:, 1].astype(float)


def _joint_vel_bounds(ctx):
    v = ctx.model.max_speeds[ctx.observed_joints]
    return -v, v.copy()


def _joint_labels(prefix):
    return lambda ctx: [f"{prefix}/{ctx.model.perceptor_names[i]}" for i in ctx.observed_joints]


_FRP = ["cx", "cy", "cz", "fx", "fy", "fz"]
_FRP_LO = [-0.1, -0.1, -0.1, -100.0, -100.0, -100.0]
_FRP_HI = [0.1, 0.1, 0.1, 100.0, 100.0, 100.0]


# ---- writers: each fills its component's slice of the raw frame from the environment


def _write_joint_pos(env, out: np.ndarray) -> None:
    out[:] = env._q[env._obs_joints]


def _write_joint_vel(env, out: np.ndarray) -> None:
    out[:] = env._qdot[env._obs_joints]


def _write_ball_rel(env, out: np.ndarray) -> None:
    gt = env.ground_truth
    d = gt.ball_pos - gt.torso_pos
    out[0], out[1] = in_heading_frame(env._heading, d[0], d[1])
    out[2] = d[2]


def _write_ball_vel(env, out: np.ndarray) -> None:
    v = env.ground_truth.ball_vel
    out[0], out[1] = in_heading_frame(env._heading, v[0], v[1])
    out[2] = v[2]


def _write_ball_vision(env, out: np.ndarray) -> None:
    out[:] = env._vision_ball


def _write_force_pair(env, out: np.ndarray, left: str, right: str) -> None:
    """Point and force of two FRP sensors into ``out`` (12 values; zeros = no contact)."""
    fs = env.perception.force_sensors
    for k, name in ((0, left), (6, right)):
        fr = fs.get(name)
        if fr is None:
            out[k : k + 6] = 0.0
        else:
            out[k : k + 3] = fr.point
            out[k + 3 : k + 6] = fr.force


def _write_foot_force(env, out: np.ndarray) -> None:
    _write_force_pair(env, out, "lf", "rf")


def _write_toe_force(env, out: np.ndarray) -> None:
    _write_force_pair(env, out, "lf1", "rf1")


def _write_accel(env, out: np.ndarray) -> None:
    out[:] = env.perception.accel


def _write_gyro(env, out: np.ndarray) -> None:
    out[:] = env.perception.gyro


def _write_torso_orientation(env, out: np.ndarray) -> None:
    out[:] = torso_axes(env.ground_truth.torso_quat)


def _write_torso_height(env, out: np.ndarray) -> None:
    out[0] = env.ground_truth.torso_pos[2]


def _write_time(env, out: np.ndarray) -> None:
    out[0] = env.episode_step


def _write_kick_target(env, out: np.ndarray) -> None:
    out[:] = env.kick_target


def _write_target_rel(env, out: np.ndarray) -> None:
    d = env.target_pos - env.ground_truth.torso_pos[:2]
    out[0], out[1] = in_heading_frame(env._heading, d[0], d[1])


def _write_velocity_command(env, out: np.ndarray) -> None:
    out[:] = env.policy_command


def _write_gait_phase(env, out: np.ndarray) -> None:
    angle = 2.0 * math.pi * env.gait_phase
    out[0] = math.sin(angle)
    out[1] = math.cos(angle)


def _write_torso_velocity(env, out: np.ndarray) -> None:
    gt = env.ground_truth
    if gt.torso_vel is None or gt.torso_ang_vel is None:  # a backend without velocities
        out[:] = 0.0
        return
    v = gt.torso_vel
    out[0], out[1] = in_heading_frame(heading_frame(gt.torso_quat), v[0], v[1])
    out[2] = v[2]
    out[3] = math.degrees(gt.torso_ang_vel[2])


def _write_last_action(env, out: np.ndarray) -> None:
    out[:] = env._last_action


COMPONENTS: dict[str, Component] = {
    c.name: c
    for c in [
        Component(
            "joint_pos",
            "Joint angles (HJ) of the observed joints, in the order of `observed_joints`.",
            "deg",
            "each joint's range [min, max]",
            _joint_pos_bounds,
            _joint_labels("joint_pos"),
            write=_write_joint_pos,
        ),
        Component(
            "joint_vel",
            "Joint angular velocities of the observed joints: change of the perceived angle over "
            "the last cycle (0 on the first frame of an episode).",
            "rad/s",
            "± each joint's max speed (6.14 rad/s; type 2 ankles: 8.81 pitch, 3.47 roll)",
            _joint_vel_bounds,
            _joint_labels("joint_vel"),
            write=_write_joint_vel,
        ),
        Component(
            "ball_rel",
            "Ball centre minus torso centre in the heading frame (x forward, y left, z up). "
            "Exact (ground truth; the paper's ``ballpos`` extension).",
            "m",
            "[-2, 2] each",
            _const([-2.0] * 3, [2.0] * 3),
            _labels("ball_rel", ["x", "y", "z"]),
            needs_ground_truth=True,
            write=_write_ball_rel,
        ),
        Component(
            "ball_vel",
            "Ball linear velocity in the heading frame (x forward, y left, z up), ground truth.",
            "m/s",
            "[-10, 10] each",
            _const([-10.0] * 3, [10.0] * 3),
            _labels("ball_vel", ["x", "y", "z"]),
            needs_ground_truth=True,
            write=_write_ball_vel,
        ),
        Component(
            "ball_vision",
            "The ball as seen by the (noisy, restricted) See perceptor, relative to the head: "
            "distance, horizontal angle (left positive), vertical angle (up positive), and a "
            "flag that is 1 when the ball was in the most recent See (every 3rd cycle). Values "
            "are held between See messages and are 0 before the ball was first seen.",
            "m, deg, deg, 1",
            "[0, 20], [-180, 180], [-90, 90], [0, 1]",
            _const([0.0, -180.0, -90.0, 0.0], [20.0, 180.0, 90.0, 1.0]),
            _labels("ball_vision", ["distance", "horizontal", "vertical", "visible"]),
            needs_vision=True,
            write=_write_ball_vision,
        ),
        Component(
            "foot_force",
            "Foot pressure sensors (FRP) of the left then right foot: centre of pressure c "
            "(x, y, z) in the foot frame and total force f (x, y, z) in the foot frame; zeros "
            "when the foot touches nothing. Standing: f_z ≈ 22.6 N per foot.",
            "m, N",
            "c: [-0.1, 0.1]; f: [-100, 100]",
            _const(_FRP_LO * 2, _FRP_HI * 2),
            _labels("foot_force", [f"lf_{n}" for n in _FRP] + [f"rf_{n}" for n in _FRP]),
            write=_write_foot_force,
        ),
        Component(
            "toe_force",
            "Toe pressure sensors (lf1 then rf1) of robot type 4, as foot_force.",
            "m, N",
            "c: [-0.1, 0.1]; f: [-100, 100]",
            _const(_FRP_LO * 2, _FRP_HI * 2),
            _labels("toe_force", [f"lf1_{n}" for n in _FRP] + [f"rf1_{n}" for n in _FRP]),
            needs_toes=True,
            write=_write_toe_force,
        ),
        Component(
            "accel",
            "Accelerometer (ACC) in the torso frame (x right, y forward, z up); ≈ (0, 0, 9.81) "
            "standing still.",
            "m/s²",
            "[-50, 50] each",
            _const([-50.0] * 3, [50.0] * 3),
            _labels("accel", ["x", "y", "z"]),
            write=_write_accel,
        ),
        Component(
            "gyro",
            "Gyroscope (GYR): torso angular velocity in the torso frame.",
            "deg/s",
            "[-500, 500] each",
            _const([-500.0] * 3, [500.0] * 3),
            _labels("gyro", ["x", "y", "z"]),
            write=_write_gyro,
        ),
        Component(
            "torso_orientation",
            "Torso orientation as two unit vectors in the world frame: the robot's forward axis "
            "(x, y, z) then its up axis (x, y, z). Upright facing +x: (1, 0, 0, 0, 0, 1). "
            "Ground truth.",
            "1",
            "[-1, 1] each",
            _const([-1.0] * 6, [1.0] * 6),
            _labels("torso_orientation", ["fwd_x", "fwd_y", "fwd_z", "up_x", "up_y", "up_z"]),
            needs_ground_truth=True,
            write=_write_torso_orientation,
        ),
        Component(
            "torso_height",
            "Height of the torso centre above the ground (≈0.38 m standing upright). Ground truth.",
            "m",
            "[0, 0.6]",
            _const([0.0], [0.6]),
            _labels("torso_height", ["z"]),
            needs_ground_truth=True,
            write=_write_torso_height,
        ),
        Component(
            "time",
            "Steps taken in this episode (0 on the first observation).",
            "steps",
            "[0, max_episode_steps]",
            lambda ctx: (np.array([0.0]), np.array([float(ctx.max_episode_steps)])),
            _labels("time", ["step"]),
            write=_write_time,
        ),
        Component(
            "kick_target",
            "Desired kick distance and direction (relative to the robot's start heading, CCW "
            "positive): `kick_target`, or drawn per episode with `randomise_kick_target`.",
            "m, deg",
            "[0, 20], [-90, 90]",
            _const([0.0, -90.0], [20.0, 90.0]),
            _labels("kick_target", ["distance", "angle"]),
            write=_write_kick_target,
        ),
        Component(
            "target_rel",
            "The point a task asks for (Dribble: where the ball should go) relative to the "
            "torso, in its heading frame (forward, left). Ground truth.",
            "m",
            "[-20, 20]",
            _const([-20.0, -20.0], [20.0, 20.0]),
            _labels("target_rel", ["x", "y"]),
            needs_ground_truth=True,
            write=_write_target_rel,
        ),
        Component(
            "velocity_command",
            "The planar velocity the task commands (Walk; with its command loop, corrected by "
            "the measured motion): forward and leftward speed in the "
            "heading frame and turn rate (CCW positive); zeros in tasks without a command.",
            "m/s, m/s, deg/s",
            "[-1, 1], [-1, 1], [-90, 90]",
            _const([-1.0, -1.0, -90.0], [1.0, 1.0, 90.0]),
            _labels("velocity_command", ["forward", "left", "turn"]),
            write=_write_velocity_command,
        ),
        Component(
            "gait_phase",
            "The task's gait clock φ in [0, 1) as (sin 2πφ, cos 2πφ) (Walk: φ advances at "
            "`gait_frequency_hz` from a random start; the left foot is meant to swing first). "
            "(0, 1) in tasks without a gait clock.",
            "1",
            "[-1, 1] each",
            _const([-1.0, -1.0], [1.0, 1.0]),
            _labels("gait_phase", ["sin", "cos"]),
            write=_write_gait_phase,
        ),
        Component(
            "torso_velocity",
            "Velocity of the torso centre in the heading frame (forward, left, up) and its turn "
            "rate about the world's up axis (CCW positive). Ground truth.",
            "m/s, m/s, m/s, deg/s",
            "[-2, 2] each, [-360, 360]",
            _const([-2.0, -2.0, -2.0, -360.0], [2.0, 2.0, 2.0, 360.0]),
            _labels("torso_velocity", ["forward", "left", "up", "turn"]),
            needs_ground_truth=True,
            write=_write_torso_velocity,
        ),
        Component(
            "last_action",
            "The previous action as given to step() (after clipping to [-1, 1]); zeros on the "
            "first frame.",
            "1",
            "[-1, 1] each",
            lambda ctx: (-np.ones(ctx.n_action), np.ones(ctx.n_action)),
            lambda ctx: [f"last_action/{i}" for i in range(ctx.n_action)],
            write=_write_last_action,
        ),
    ]
}
"""Every observation component by name."""


def component_names() -> tuple[str, ...]:
    """Names of all observation components."""
    return tuple(COMPONENTS)


def heading_frame(quat: np.ndarray) -> tuple[float, float]:
    """(cos ψ, sin ψ) of the heading ψ of a torso with orientation ``quat`` (w, x, y, z): the
    direction of its forward (+y) axis projected on the ground (+x if it points straight up)."""
    w, x, y, z = quat
    fx = 2.0 * (x * y - w * z)
    fy = 1.0 - 2.0 * (x * x + z * z)
    n = math.hypot(fx, fy)
    if n < 1e-9:
        return 1.0, 0.0
    return fx / n, fy / n


def in_heading_frame(heading: tuple[float, float], x: float, y: float) -> tuple[float, float]:
    """A world-frame planar vector (``x``, ``y``) in the heading frame of a robot whose heading
    is ``heading`` (cos ψ, sin ψ, :func:`heading_frame`): (forward, left)."""
    c, s = heading
    return c * x + s * y, c * y - s * x


def turn_to_deg(heading: tuple[float, float], direction: float) -> float:
    """How far a robot with heading ``heading`` (cos ψ, sin ψ) must turn to face the world
    direction ``direction`` (rad), deg in [−180, 180), counter-clockwise positive."""
    c, s = heading
    return math.degrees((direction - math.atan2(s, c) + math.pi) % (2.0 * math.pi) - math.pi)


def up_z(quat: np.ndarray) -> float:
    """World z of the torso's up axis (+z) from its quaternion (w, x, y, z): 1 upright, 0 lying,
    the cosine of the torso's tilt."""
    _, x, y, _ = quat
    return float(1.0 - 2.0 * (x * x + y * y))


def torso_axes(quat: np.ndarray) -> tuple[float, float, float, float, float, float]:
    """Forward (+y) and up (+z) axes of the torso in world coordinates from its quaternion."""
    w, x, y, z = quat
    return (
        2.0 * (x * y - w * z),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z + w * x),
        2.0 * (x * z + w * y),
        2.0 * (y * z - w * x),
        up_z(quat),
    )

"""One Nao in the MuJoCo world: where its joints, bodies, geoms and sensors are in the MuJoCo
model, its motor state (targets, creep compensation, commands waiting out the dead time) and
its state as an agent."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from robocup_gym.robot.nao import NaoModel
from robocup_gym.sim import physics as phys
from robocup_gym.sim.senses import AgentState
from robocup_gym.types import ForceResistance


@dataclass(kw_only=True)
class RobotState(AgentState):
    """Book-keeping of one robot in the world: ids into the MuJoCo model, motor state, and (from
    :class:`~robocup_gym.sim.senses.AgentState`) its state as an agent."""

    index: int
    prefix: str
    model: NaoModel
    qpos_root: int = 0
    qvel_root: int = 0
    qpos_joints: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    qvel_joints: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    torso_body: int = 0
    head_body: int = 0
    part_bodies: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    frp_sensors: list[tuple[str, int, int]] = field(default_factory=list)
    """Per force resistance perceptor: name, address of its contact sensor's data
    (contact count, force, point; world frame), foot/toe body."""
    robot_bodies: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    robot_geoms: frozenset = frozenset()
    shapes: tuple = ()
    """Collision geoms by shape: (boxes, their half sizes, spheres, radii, capsules, radii,
    half lengths), for the lowest point of the robot."""
    range_rad: tuple = (np.zeros(0), np.zeros(0))
    """(lower, upper) joint limits in rad, canonical order."""
    max_speeds: np.ndarray = field(default_factory=lambda: np.zeros(0))
    min_speeds: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """``-max_speeds`` (the lower clip of commands), rad/s."""
    targets: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Active motor targets, rad/s, canonical order."""
    q_ref: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Integral of the commanded velocities (rad) used for creep compensation."""
    motor_lost: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    """Joints whose motor saturated or sat at a stop in the last step: their creep compensation
    restarts from where they are (motion lost there is never caught up, as in ODE)."""
    cmd: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Commands due this cycle for the compiled step (NaN: none), a view into the world's."""
    joint_slice: slice = field(default_factory=lambda: slice(0, 0))
    """This robot's joints in the world-level joint arrays."""
    pending: list = field(default_factory=list)
    """Commands waiting out the dead time: ``(due cycle, velocities in rad/s with NaN for "no
    command", whether every joint has a command)``."""
    accel: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, phys.GRAVITY]))
    prev_vel: np.ndarray = field(default_factory=lambda: np.zeros(3))
    last_frp: dict[str, ForceResistance] = field(default_factory=dict)
    asleep: bool = False
    """Held where it was placed (ODE auto-disable) until a non-zero motor target or a contact
    with a moving body wakes it (see :meth:`World.place_robot`)."""
    sleep_qpos: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Root pose (7) and joint angles at which a sleeping robot is held."""

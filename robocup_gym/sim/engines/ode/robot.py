"""The Nao on ODE: one robot's bodies, masses, geoms and hinge motors built from the robot model
(:func:`robocup_gym.robot.nao.nao_model`) as rcssserver3d builds them from its scene files, and
the robot's handles and state in an :class:`~robocup_gym.sim.engines.ode.world.OdeWorld`.

The hinges carry SimSpark's motor parameters (``docs/reference/simspark.md`` §7.2, §8.3): FMax
from the model, CFM 1e-8, stop ERP 0.8 / CFM 1e-8, fudge factor 1e-5 and stop bounce 1.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass, field

import numpy as np

from robocup_gym.robot.nao import NaoModel, nao_model
from robocup_gym.sim import physics as phys
from robocup_gym.sim.engines.mujoco.scene import FRP_GEOMS
from robocup_gym.sim.engines.ode import lib as ode
from robocup_gym.sim.senses import AgentState
from robocup_gym.types import ForceResistance

HINGE_CFM = 1e-8
HINGE_STOP_ERP, HINGE_STOP_CFM = phys.JOINT_STOP_ERP_CFM
HINGE_FUDGE_FACTOR = 1e-5
HINGE_STOP_BOUNCE = 1.0


@dataclass(kw_only=True)
class OdeRobot(AgentState):
    """One Nao in the ODE world: body and joint handles in the model's order, and (from
    :class:`~robocup_gym.sim.senses.AgentState`) its state as an agent."""

    model: NaoModel
    bodies: list[int]
    """ODE body handles, in ``model.bodies`` order (torso first)."""
    joints: list[int]
    """ODE hinge handles, canonical joint order."""
    geoms: list[int]
    child_body: list[int]
    """Handle of each joint's child body (woken by a non-zero command)."""
    limits: np.ndarray
    """(n, 2) stops in rad."""
    pending: list = field(default_factory=list)
    """Commands given but not yet realised (dead time)."""
    body_index: dict[str, int] = field(default_factory=dict)
    """Body name → index into :attr:`bodies`."""
    joint_slice: slice = field(default_factory=lambda: slice(0, 0))
    """This robot's joints in the world's joint state arrays."""
    frp_bodies: dict[str, int] = field(default_factory=dict)
    """Force resistance perceptor name (``lf``, ``rf``, ``lf1``, ``rf1``) → its body handle."""
    prev_vel: np.ndarray = field(default_factory=lambda: np.zeros(3))
    """Torso velocity at the last accelerometer sample, m/s, world."""
    accel: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, phys.GRAVITY]))
    """Accelerometer reading, m/s², torso frame."""
    frp: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    """The last step's foot contacts: name → (total force on the foot, force-weighted centre of
    the contacts), world frame."""
    last_frp: dict[str, ForceResistance] = field(default_factory=dict)


def build_robot(lib, world: int, type_index: int) -> OdeRobot:
    """One robot of type ``type_index`` in ODE world ``world`` (``lib``: the loaded library), in
    the zero pose at the origin (torso frame = world frame, so the reference's anchors and axes
    apply as they are); the world's ``place_robot`` moves it."""
    model = nao_model(type_index)
    names = [b.name for b in model.bodies]
    bodies, geoms = [], []
    for b in model.bodies:
        body = lib.dBodyCreate(world)
        lib.dBodySetPosition(body, *b.pos)
        mass = ode.Mass()
        if b.shape == "box":
            lib.dMassSetBoxTotal(ctypes.byref(mass), b.mass, *b.size)
        elif b.shape == "sphere":
            lib.dMassSetSphereTotal(ctypes.byref(mass), b.mass, b.size[0])
        else:  # capsule along local z (ODE direction 3)
            lib.dMassSetCapsuleTotal(ctypes.byref(mass), b.mass, 3, b.size[0], b.size[1])
        lib.dBodySetMass(body, ctypes.byref(mass))
        bodies.append(body)
        if b.collides:
            if b.shape == "box":
                g = lib.dCreateBox(None, *b.size)
            elif b.shape == "sphere":
                g = lib.dCreateSphere(None, b.size[0])
            else:
                g = lib.dCreateCapsule(None, b.size[0], b.size[1])
            lib.dGeomSetBody(g, body)
            geoms.append(g)
    joints, child = [], []
    for j in model.joints:
        h = lib.dJointCreateHinge(world, None)
        c, p = bodies[names.index(j.child)], bodies[names.index(j.parent)]
        lib.dJointAttach(h, c, p)  # body 1 = child, body 2 = parent (reference §1.5)
        lib.dJointSetHingeAnchor(h, *j.anchor)
        lib.dJointSetHingeAxis(h, *j.axis)  # the angle is 0 in this (zero) pose
        lo, hi = j.range_rad
        for param, value in (
            (ode.PARAM_LO_STOP, lo),
            (ode.PARAM_HI_STOP, hi),
            (ode.PARAM_FMAX, j.max_torque),
            (ode.PARAM_CFM, HINGE_CFM),
            (ode.PARAM_STOP_ERP, HINGE_STOP_ERP),
            (ode.PARAM_STOP_CFM, HINGE_STOP_CFM),
            (ode.PARAM_FUDGE_FACTOR, HINGE_FUDGE_FACTOR),
            (ode.PARAM_BOUNCE, HINGE_STOP_BOUNCE),
            (ode.PARAM_VEL, 0.0),
        ):
            lib.dJointSetHingeParam(h, param, value)
        joints.append(h)
        child.append(c)
    limits = np.array([j.range_rad for j in model.joints])
    frp = {f: bodies[names.index(FRP_GEOMS[f])] for f in FRP_GEOMS if FRP_GEOMS[f] in names}
    return OdeRobot(
        model=model,
        bodies=bodies,
        joints=joints,
        geoms=geoms,
        child_body=child,
        limits=limits,
        body_index={name: i for i, name in enumerate(names)},
        frp_bodies=frp,
    )


_KINEMATICS: dict[int, tuple] = {}
"""Per robot model (by ``id``, the model kept alive in the entry): what
:meth:`OdeWorld._forward_kinematics` needs of it, as arrays, computed once."""


def kinematics(model: NaoModel) -> tuple:
    """``(model, links)`` of ``model`` (cached): per body in order, ``(parent's index, joint
    index, unit joint axis, joint anchor, zero-pose centre)`` (-1, -1, None, None for the
    torso)."""
    entry = _KINEMATICS.get(id(model))
    if entry is None or entry[0] is not model:
        index = {b.name: i for i, b in enumerate(model.bodies)}
        joint_of = {j.child: j for j in model.joints}
        k_of = {j.child: k for k, j in enumerate(model.joints)}
        links = []
        for b in model.bodies:
            if b.parent is None:
                links.append((-1, -1, None, None, np.array(b.pos)))
                continue
            j = joint_of[b.name]
            axis = np.array(j.axis, float) / np.linalg.norm(j.axis)
            links.append((index[b.parent], k_of[b.name], axis, np.array(j.anchor), np.array(b.pos)))
        entry = _KINEMATICS[id(model)] = (model, links)
    return entry

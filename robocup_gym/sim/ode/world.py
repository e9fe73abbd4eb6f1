"""SimSpark's physics step re-created on ODE itself: the reference the MuJoCo world is checked
against.

rcssserver3d advances the Open Dynamics Engine once per 20 ms cycle (``dWorldStep``, ODE 0.16,
double precision). :class:`OdeWorld` builds the same robot (from the same tables,
:func:`robocup_gym.robot.nao.nao_model`), ball and ground on that engine, with the parameters of
``shared/spec/simspark-model.md``: world CFM 1e-5, surface layer 1 mm, auto-disable on; hinge
motors with FMax 10 N·m, CFM 1e-8, stop ERP 0.8 / CFM 1e-8, fudge factor 1e-5 and bounce 1;
contact surfaces mixed from each side's handler as SimSpark does (§7.3); drag before each step
(§7.5); the hinge effector's rules (clip to the joint's max speed, ignore commands while the
joint is not strictly inside its limits, wake the body on a non-zero command, §8.3).

It is a yardstick, not a second simulator: no referee, no vision, no walls or goals (the
motions it compares happen near the centre of the field). It has the body sensors a kick
policy reads (joint angles, gyro, accelerometer, foot force perceptors from ODE's contact
feedback, as SimSpark computes them), so that :class:`robocup_gym.backends.ode_backend.OdeBackend`
can run a trained policy closed-loop on SimSpark's physics. What it settles is how ODE's own
solver, contact generation, joint stops and motor-at-stop rules behave for a given motion,
which the MuJoCo translation (:mod:`robocup_gym.sim.world`) can then be compared with
(``benchmarks/ode_compare.py``). It needs the system library ``libode``
(:mod:`robocup_gym.sim.ode.lib`).

It offers the part of :class:`robocup_gym.sim.world.World`'s interface that scripted motions
use (``place_robot``, ``place_ball``, ``step``, ``ball_position``, ``torso_position``, …), so
:func:`robocup_gym.sim.fidelity.scripted_kick` runs on either.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np

from robocup_gym.robot.nao import NaoModel, nao_model
from robocup_gym.sim import compiled as compiled_step
from robocup_gym.sim import physics as phys
from robocup_gym.sim.ode import lib as ode
from robocup_gym.sim.ode.fast import FastLoops
from robocup_gym.sim.ode.fast import load as load_fast
from robocup_gym.sim.scene import FRP_GEOMS
from robocup_gym.sim.world import heading_to_quat, joint_angles_array, joint_index
from robocup_gym.types import ForceResistance

WORLD_CFM = 1e-5
"""SimSpark's world CFM (spec §7.1); the world ERP stays ODE's default 0.2."""
WORLD_ERP = 0.2
HINGE_CFM = 1e-8
HINGE_STOP_ERP, HINGE_STOP_CFM = phys.JOINT_STOP_ERP_CFM
HINGE_FUDGE_FACTOR = 1e-5
HINGE_STOP_BOUNCE = 1.0
MAX_CONTACTS = 4
"""Contact points per geom pair (spec §7.3)."""


@dataclass(frozen=True)
class Surface:
    """One contact handler's surface settings (spec §7.3); ``None`` = that mode is off."""

    bounce: tuple[float, float] | None
    """(restitution, minimum approach speed m/s)."""
    soft_erp: float | None
    soft_cfm: float | None
    slip: float | None
    """Force-dependent slip, m/s per N (both friction directions)."""


ROBOT_SURFACE = Surface(bounce=None, soft_erp=0.6, soft_cfm=1e-4, slip=0.005)
"""Every robot part and foot (contact-joint and touch-perceptor handlers)."""
BALL_SURFACE = Surface(bounce=(0.8, 0.8), soft_erp=0.5, soft_cfm=0.05, slip=0.6)
GROUND_SURFACE = Surface(bounce=None, soft_erp=0.2, soft_cfm=None, slip=0.005)
WALL_SURFACE = Surface(bounce=(0.8, 2.0), soft_erp=None, soft_cfm=None, slip=None)
"""The default handler of walls and goals (not built here; kept for the mixing table)."""


def _mix(a, b):
    if a is None:
        return b
    if b is None:
        return a
    if isinstance(a, tuple):
        return tuple((x + y) / 2 for x, y in zip(a, b, strict=True))
    return (a + b) / 2


def mix_surfaces(a: Surface, b: Surface) -> Surface:
    """The contact parameters SimSpark gives a pair: a mode enabled on both sides averages the
    two values, on one side takes that side's value, on neither stays off (spec §7.3)."""
    return Surface(
        bounce=_mix(a.bounce, b.bounce),
        soft_erp=_mix(a.soft_erp, b.soft_erp),
        soft_cfm=_mix(a.soft_cfm, b.soft_cfm),
        slip=_mix(a.slip, b.slip),
    )


def _surface_parameters(s: Surface) -> ode.SurfaceParameters:
    p = ode.SurfaceParameters()
    p.mu = ode.INFINITY
    mode = 0
    if s.bounce is not None:
        mode |= ode.CONTACT_BOUNCE
        p.bounce, p.bounce_vel = s.bounce
    if s.soft_erp is not None:
        mode |= ode.CONTACT_SOFT_ERP
        p.soft_erp = s.soft_erp
    if s.soft_cfm is not None:
        mode |= ode.CONTACT_SOFT_CFM
        p.soft_cfm = s.soft_cfm
    if s.slip is not None:
        mode |= ode.CONTACT_SLIP1 | ode.CONTACT_SLIP2
        p.slip1 = p.slip2 = s.slip
    p.mode = mode
    return p


def _rotation(quat: np.ndarray) -> np.ndarray:
    """The 3×3 matrix of a unit quaternion ``(w, x, y, z)`` (MuJoCo's ``mju_quat2Mat``)."""
    m = np.zeros(9)
    mujoco.mju_quat2Mat(m, quat)
    return m.reshape(3, 3)


def _axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix by ``angle`` (rad) about ``axis`` (MuJoCo's ``mju_axisAngle2Quat``)."""
    q = np.zeros(4)
    mujoco.mju_axisAngle2Quat(q, axis, angle)
    return _rotation(q)


def _mat3(r: np.ndarray) -> ode.Mat3:
    m = ode.Mat3()
    for i in range(3):
        for j in range(3):
            m[4 * i + j] = float(r[i, j])
    return m


@dataclass
class OdeRobot:
    """One Nao in the ODE world: body and joint handles in the model's order."""

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


class OdeWorld:
    """The SimSpark Nao world stepped by ODE 0.16 exactly as rcssserver3d steps it.

    Args:
        robot_types: One entry per robot (types 0–4).
        dead_time_cycles: Cycles between a command given to :meth:`step` and the step it first
            acts in, as :class:`robocup_gym.sim.world.World` (1 = SimSpark's sync-mode latency).
        compiled: Run the per-cycle loops in C (:mod:`robocup_gym.sim.ode.fast`, bit-equal,
            twice as fast), as :class:`~robocup_gym.sim.world.World`'s argument of that name:
            ``None`` = ``ROBOCUP_GYM_COMPILED``, else whenever it can be built.

    Raises:
        robocup_gym.sim.ode.lib.OdeUnavailableError: when ``libode`` is missing.
    """

    def __init__(
        self,
        robot_types: Sequence[int] = (0,),
        *,
        dead_time_cycles: int = 1,
        compiled: bool | None = None,
    ) -> None:
        self._lib = lib = ode.load()
        self.dead_time_cycles = int(dead_time_cycles)
        self.time = 0.0
        self._world = lib.dWorldCreate()
        lib.dWorldSetGravity(self._world, 0.0, 0.0, -phys.GRAVITY)
        lib.dWorldSetERP(self._world, WORLD_ERP)
        lib.dWorldSetCFM(self._world, WORLD_CFM)
        lib.dWorldSetContactSurfaceLayer(self._world, phys.SURFACE_LAYER)
        lib.dWorldSetAutoDisableFlag(self._world, 1)  # before bodies: they copy the setting
        self._contacts = lib.dJointGroupCreate(0)
        self._ground = lib.dCreatePlane(None, 0.0, 0.0, 1.0, 0.0)
        self._ball = lib.dBodyCreate(self._world)
        mass = ode.Mass()
        lib.dMassSetSphereTotal(ctypes.byref(mass), phys.BALL_MASS, phys.BALL_RADIUS)
        lib.dBodySetMass(self._ball, ctypes.byref(mass))
        self._ball_geom = lib.dCreateSphere(None, phys.BALL_RADIUS)
        lib.dGeomSetBody(self._ball_geom, self._ball)
        self.robots = [self._build_robot(int(t)) for t in robot_types]
        self._contact_buf = (ode.ContactGeom * MAX_CONTACTS)()
        self._contact = ode.Contact()
        self._pairs = self._collision_pairs()
        n_sensed = sum(1 for p in self._pairs if p[5] or p[6])
        self._feedback = (ode.JointFeedback * (MAX_CONTACTS * max(n_sensed, 1)))()
        """Contact feedback slots for the contacts of foot/toe geoms (SimSpark's ``FRP``)."""
        self._fast = self._init_fast(compiled_step.wanted() if compiled is None else compiled)
        self.place_ball((0.0, 0.0))
        for i in range(len(self.robots)):
            self.place_robot(i, -1.0 - 1.0 * i, 0.0)

    # ------------------------------------------------------------------ construction
    def _build_robot(self, type_index: int) -> OdeRobot:
        """One robot of type ``type_index`` in the zero pose at the origin (torso frame = world
        frame, so the spec's anchors and axes apply as they are); :meth:`place_robot` moves it."""
        lib = self._lib
        model = nao_model(type_index)
        names = [b.name for b in model.bodies]
        bodies, geoms = [], []
        for b in model.bodies:
            body = lib.dBodyCreate(self._world)
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
            h = lib.dJointCreateHinge(self._world, None)
            c, p = bodies[names.index(j.child)], bodies[names.index(j.parent)]
            lib.dJointAttach(h, c, p)  # body 1 = child, body 2 = parent (spec §1.5)
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
        return OdeRobot(model, bodies, joints, geoms, child, limits, frp_bodies=frp)

    def _collision_pairs(self) -> list[tuple]:
        """Every geom pair that can touch, as ``(geom1, geom2, body1, body2, surface)`` (body
        ``None`` for the static ground) with its mixed surface: robot parts with the ground,
        the ball and other robots' parts (never with their own robot: inner collision is
        disabled, spec §1.1); the ball with the ground."""
        robot_ground = _surface_parameters(mix_surfaces(ROBOT_SURFACE, GROUND_SURFACE))
        robot_ball = _surface_parameters(mix_surfaces(ROBOT_SURFACE, BALL_SURFACE))
        robot_robot = _surface_parameters(mix_surfaces(ROBOT_SURFACE, ROBOT_SURFACE))
        ball_ground = _surface_parameters(mix_surfaces(BALL_SURFACE, GROUND_SURFACE))
        pairs = [(self._ball_geom, self._ground, ball_ground)]
        for i, r in enumerate(self.robots):
            for g in r.geoms:
                pairs.append((g, self._ground, robot_ground))
                pairs.append((g, self._ball_geom, robot_ball))
                for other in self.robots[i + 1 :]:
                    pairs.extend((g, g2, robot_robot) for g2 in other.geoms)
        body = self._lib.dGeomGetBody
        sensor = {}  # body handle -> (robot, FRP name)
        for i, r in enumerate(self.robots):
            for name, b in r.frp_bodies.items():
                sensor[b] = (i, name)
        return [
            (g1, g2, body(g1), body(g2), s, sensor.get(body(g1)), sensor.get(body(g2)))
            for g1, g2, s in pairs
        ]

    def _init_fast(self, mode: bool | None) -> FastLoops | None:
        """The compiled loops when ``mode`` is ``True`` (must work) or ``None`` (if they can
        be built); :attr:`stepper` says which run, :attr:`compiled_unavailable` why not."""
        self.compiled_unavailable: str | None = None
        if mode is False:
            return None
        try:
            load_fast()
        except compiled_step.CompiledStepUnavailableError as exc:
            if mode:
                raise
            self.compiled_unavailable = str(exc)
            return None
        lin, ang = phys.BODY_LINEAR_DRAG, phys.BODY_ANGULAR_DRAG
        bodies = [(b, (lin, ang)) for r in self.robots for b in r.bodies]
        bodies.append((self._ball, (phys.BALL_LINEAR_DRAG, phys.BALL_ANGULAR_DRAG)))
        robots = [(r.joints, r.child_body, r.limits, r.model.max_speeds) for r in self.robots]
        return FastLoops(
            self._lib,
            bodies,
            robots,
            self._world,
            self._contacts,
            self._pairs,
            self._feedback,
            MAX_CONTACTS,
        )

    @property
    def stepper(self) -> str:
        """Which implementation runs the per-cycle loops: ``"compiled"`` or ``"python"``."""
        return "compiled" if self._fast is not None else "python"

    # ------------------------------------------------------------------ placement
    def place_robot(
        self,
        index: int,
        x: float,
        y: float,
        *,
        heading_deg: float = 0.0,
        z: float | None = None,
        joint_angles_deg: Mapping[str, float] | np.ndarray | None = None,
        asleep: bool = False,
    ) -> None:
        """Teleport robot ``index`` with zero velocities and motor targets, as the trainer's
        ``move`` does; ``z`` = torso centre height (``None``: lowest point 1 mm deep, ODE's
        resting depth, as :meth:`robocup_gym.sim.world.World.place_robot` puts it),
        ``joint_angles_deg`` in canonical order or by name (others 0). ``asleep`` leaves every
        body disabled, as ODE's auto-disable leaves a robot that was resting when moved."""
        lib = self._lib
        r = self.robots[index]
        model = r.model
        for name, v in (("x", x), ("y", y), ("z", z), ("heading_deg", heading_deg)):
            if v is not None and not math.isfinite(v):
                raise ValueError(f"robot placement {name} must be finite, got {v}")
        angles = (
            np.zeros(len(model.joints))
            if joint_angles_deg is None
            else joint_angles_array(model, joint_angles_deg)
        )
        rot, trans = self._forward_kinematics(model, np.radians(angles), heading_deg)
        centres = [rot[i] @ np.array(b.pos) + trans[i] for i, b in enumerate(model.bodies)]
        if z is None:
            shift = -phys.SURFACE_LAYER - min(
                c[2] - np.abs(rot[i][2]) @ (np.array(b.size) / 2)
                for i, (b, c) in enumerate(zip(model.bodies, centres, strict=True))
                if b.collides and b.shape == "box"
            )
        else:
            shift = z - centres[0][2]
        for i, body in enumerate(r.bodies):
            c = centres[i]
            lib.dBodySetPosition(body, x + c[0], y + c[1], c[2] + shift)
            lib.dBodySetRotation(body, _mat3(rot[i]))
            lib.dBodySetLinearVel(body, 0.0, 0.0, 0.0)
            lib.dBodySetAngularVel(body, 0.0, 0.0, 0.0)
            (lib.dBodyDisable if asleep else lib.dBodyEnable)(body)
        for h in r.joints:
            lib.dJointSetHingeParam(h, ode.PARAM_VEL, 0.0)
        r.pending.clear()
        r.prev_vel[:] = 0.0
        r.accel[:] = (0.0, 0.0, phys.GRAVITY)
        r.frp = {}
        r.last_frp = {}

    @staticmethod
    def _forward_kinematics(
        model: NaoModel, angles: np.ndarray, heading_deg: float
    ) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Per body, the rotation and translation that take zero-pose torso-frame points to
        world points (relative to the torso's x, y; torso centre at height 0)."""
        root = _rotation(heading_to_quat(heading_deg))
        index = {b.name: i for i, b in enumerate(model.bodies)}
        joint_of = {j.child: (k, j) for k, j in enumerate(model.joints)}
        rot: list = [None] * len(model.bodies)
        trans: list = [None] * len(model.bodies)
        for i, b in enumerate(model.bodies):  # parents come before their children
            if b.parent is None:
                rot[i], trans[i] = root, np.zeros(3)
                continue
            p = index[b.parent]
            k, j = joint_of[b.name]
            turn = _axis_rotation(np.array(j.axis, float) / np.linalg.norm(j.axis), angles[k])
            a = np.array(j.anchor)
            rot[i] = rot[p] @ turn
            trans[i] = rot[p] @ (a - turn @ a) + trans[p]
        return rot, trans

    def place_ball(
        self,
        pos: Sequence[float],
        vel: Sequence[float] = (0.0, 0.0, 0.0),
        angular_vel: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> None:
        """Put the ball at ``pos`` (x, y[, z]; z defaults to 1 mm into the ground, as the MuJoCo
        world's default) with velocity ``vel`` (m/s) and ``angular_vel`` (rad/s)."""
        lib = self._lib
        p, v, w = (np.asarray(a, float) for a in (pos, vel, angular_vel))
        if p.shape not in ((2,), (3,)) or not np.isfinite(p).all():
            raise ValueError(f"ball position must be 2 or 3 finite numbers, got {pos!r}")
        if (
            v.shape != (3,)
            or w.shape != (3,)
            or not (np.isfinite(v).all() and np.isfinite(w).all())
        ):
            raise ValueError("ball velocities must be 3 finite numbers each")
        z = p[2] if len(p) > 2 else phys.BALL_RADIUS - phys.SURFACE_LAYER
        lib.dBodySetPosition(self._ball, float(p[0]), float(p[1]), float(z))
        lib.dBodySetRotation(self._ball, _mat3(np.eye(3)))
        lib.dBodySetLinearVel(self._ball, *map(float, v))
        lib.dBodySetAngularVel(self._ball, *map(float, w))
        lib.dBodyEnable(self._ball)

    # ------------------------------------------------------------------ stepping
    def step(self, commands: Mapping[int, Mapping[str, float] | np.ndarray] | None = None) -> None:
        """Advance one 20 ms cycle: realise due commands (target rad/s, clipped to the joint's
        max speed, ignored for a joint not strictly inside its limits, a non-zero one wakes the
        joint's child body), drag on every body, collisions, one ``dWorldStep(0.02)``."""
        commands = commands or {}
        arrays = [  # all validated before any is queued
            None if commands.get(i) is None else self._command_array(r, commands[i])
            for i, r in enumerate(self.robots)
        ]
        for i, (r, cmd) in enumerate(zip(self.robots, arrays, strict=True)):
            r.pending.append(cmd)
            if len(r.pending) > self.dead_time_cycles:
                due = r.pending.pop(0)
                if due is not None and self._fast is not None:
                    self._fast.realise(i, due)
                elif due is not None:
                    self._realise(r, due)
        self._sense_accelerometers()
        if self._fast is not None:
            self._fast.drag()
        else:
            self._apply_drag()
        self._collide_and_step()
        self.time += phys.CYCLE_S

    def sense_contacts(self) -> None:
        """Fill the force perceptors for the current state without advancing it: with the
        contact forces ODE's next step would apply (what MuJoCo's ``mj_forward`` gives the
        world at a placement), so that the perception of a freshly placed robot shows its feet
        loaded, as every later one does. The state is put back exactly; nothing else changes
        (ODE's big-matrix step keeps no warm start, and placing re-arms auto-disable)."""
        lib = self._lib
        bodies = [self._ball, *(b for r in self.robots for b in r.bodies)]
        saved = [
            (
                self._vec(lib.dBodyGetPosition(b)),
                ode.Vec4(*lib.dBodyGetQuaternion(b)[:4]),
                self._vec(lib.dBodyGetLinearVel(b)),
                self._vec(lib.dBodyGetAngularVel(b)),
                lib.dBodyIsEnabled(b),
            )
            for b in bodies
        ]
        self._collide_and_step()
        for b, (pos, quat, vel, ang, enabled) in zip(bodies, saved, strict=True):
            lib.dBodySetPosition(b, *pos)
            lib.dBodySetQuaternion(b, quat)
            lib.dBodySetLinearVel(b, *vel)
            lib.dBodySetAngularVel(b, *ang)
            (lib.dBodyEnable if enabled else lib.dBodyDisable)(b)

    def _collide_and_step(self) -> None:
        """Contacts for the current poses, one ``dWorldStep(0.02)``, the force perceptors."""
        lib = self._lib
        sensed = self._fast.collide() if self._fast is not None else self._collide()
        lib.dWorldStep(self._world, phys.CYCLE_S)
        self._read_feedback(sensed)
        lib.dJointGroupEmpty(self._contacts)

    def _collide(self) -> list:
        """Contact joints for the current poses; returns the contacts of foot/toe geoms as
        ``(feedback slot, contact position, FRP of body 1, FRP of body 2)``."""
        lib = self._lib
        buf, contact = self._contact_buf, self._contact
        size = ctypes.sizeof(ode.ContactGeom)
        sensed = []
        for g1, g2, b1, b2, surface, frp1, frp2 in self._pairs:
            n = lib.dCollide(g1, g2, MAX_CONTACTS, buf, size)
            if n:
                contact.surface = surface
                for k in range(n):
                    contact.geom = buf[k]
                    joint = lib.dJointCreateContact(self._world, self._contacts, contact)
                    lib.dJointAttach(joint, b1, b2)
                    if frp1 or frp2:
                        slot = self._feedback[len(sensed)]
                        lib.dJointSetFeedback(joint, slot)
                        sensed.append((slot, np.array(buf[k].pos[:3]), frp1, frp2))
        return sensed

    def _sense_accelerometers(self) -> None:
        """Each torso's accelerometer, sampled as :class:`robocup_gym.sim.world.World` samples
        it (spec §4.5): the change of the torso's velocity since the last sample over one cycle
        plus gravity, in the torso frame, m/s²; taken just before the physics step."""
        lib = self._lib
        for r in self.robots:
            v = self._vec(lib.dBodyGetLinearVel(r.bodies[0]))
            a = (v - r.prev_vel) / phys.CYCLE_S
            a[2] += phys.GRAVITY
            r.prev_vel[:] = v
            r.accel[:] = a @ self._rotation(r.bodies[0])

    def _read_feedback(self, sensed: list) -> None:
        """SimSpark's force resistance perceptors from the step's contact feedback (spec §4.6):
        per foot/toe the total contact force on it and the contacts' centre weighted by the
        magnitude of each contact's force, world frame."""
        sums: dict[tuple[int, str], list] = {}
        for slot, pos, frp1, frp2 in sensed:
            for frp, f in ((frp1, slot.f1), (frp2, slot.f2)):
                if frp is None:
                    continue
                force = np.array(f[:3])
                acc = sums.setdefault(frp, [np.zeros(3), np.zeros(3), 0.0])
                magnitude = float(np.linalg.norm(force))
                acc[0] += force
                acc[1] += magnitude * pos
                acc[2] += magnitude
        for r in self.robots:
            r.frp = {}
        for (i, name), (force, moment, total) in sums.items():
            centre = moment / total if total > 0.0 else None
            self.robots[i].frp[name] = (force, centre)

    def _command_array(self, r: OdeRobot, cmd: Mapping[str, float] | np.ndarray) -> np.ndarray:
        """Targets in canonical order, rad/s; NaN marks a joint the command leaves alone.

        Raises:
            KeyError: an unknown joint name (listing the valid ones).
            ValueError: a NaN/inf velocity (naming the joint) or an array of the wrong shape.
        """
        names = r.model.effector_names
        out = np.full(len(names), np.nan)
        if isinstance(cmd, Mapping):
            given = np.zeros(len(names), dtype=bool)
            for name, v in cmd.items():
                k = joint_index(r.model, name)
                out[k] = float(v)
                given[k] = True
        else:
            arr = np.asarray(cmd, dtype=float)
            if arr.shape != out.shape:
                raise ValueError(f"command array must have shape {out.shape}, got {arr.shape}")
            out[:] = arr
            given = np.ones(len(names), dtype=bool)
        bad = given & ~np.isfinite(out)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise ValueError(f"velocity command for joint {names[k]} is {out[k]}")
        return out

    def _realise(self, r: OdeRobot, targets: np.ndarray) -> None:
        lib = self._lib
        vmax = r.model.max_speeds
        for k, h in enumerate(r.joints):
            v = targets[k]
            if math.isnan(v):
                continue
            angle = lib.dJointGetHingeAngle(h)
            lo, hi = r.limits[k]
            if not lo < angle < hi:
                continue  # SimSpark's hinge effector: the previous target stays
            v = min(max(float(v), -vmax[k]), vmax[k])
            lib.dJointSetHingeParam(h, ode.PARAM_VEL, v)
            if v != 0.0:
                lib.dBodyEnable(r.child_body[k])

    def _apply_drag(self) -> None:
        lib = self._lib
        lin, ang = phys.BODY_LINEAR_DRAG, phys.BODY_ANGULAR_DRAG
        for r in self.robots:
            for b in r.bodies:
                v = lib.dBodyGetLinearVel(b)
                w = lib.dBodyGetAngularVel(b)
                lib.dBodyAddForce(b, -lin * v[0], -lin * v[1], -lin * v[2])
                lib.dBodyAddTorque(b, -ang * w[0], -ang * w[1], -ang * w[2])
        v = lib.dBodyGetLinearVel(self._ball)
        w = lib.dBodyGetAngularVel(self._ball)
        c, a = phys.BALL_LINEAR_DRAG, phys.BALL_ANGULAR_DRAG
        lib.dBodyAddForce(self._ball, -c * v[0], -c * v[1], -c * v[2])
        lib.dBodyAddTorque(self._ball, -a * w[0], -a * w[1], -a * w[2])

    # ------------------------------------------------------------------ state
    def _vec(self, ptr) -> np.ndarray:
        return np.array([ptr[0], ptr[1], ptr[2]])

    def ball_position(self) -> np.ndarray:
        """Ball centre, world, m."""
        return self._vec(self._lib.dBodyGetPosition(self._ball))

    def ball_velocity(self) -> np.ndarray:
        """Ball linear velocity, world, m/s."""
        return self._vec(self._lib.dBodyGetLinearVel(self._ball))

    def body_position(self, index: int, name: str) -> np.ndarray:
        """Centre of robot ``index``'s body ``name`` (e.g. ``rfoot``), world, m."""
        r = self.robots[index]
        k = [b.name for b in r.model.bodies].index(name)
        return self._vec(self._lib.dBodyGetPosition(r.bodies[k]))

    def body_rotation(self, index: int, name: str) -> np.ndarray:
        """Orientation of robot ``index``'s body ``name`` as a 3×3 matrix (torso-frame axes in
        world coordinates)."""
        r = self.robots[index]
        k = [b.name for b in r.model.bodies].index(name)
        return self._rotation(r.bodies[k])

    def _rotation(self, body: int) -> np.ndarray:
        m = self._lib.dBodyGetRotation(body)
        return np.array([[m[4 * i + j] for j in range(3)] for i in range(3)])

    def ball_angular_velocity(self) -> np.ndarray:
        """Ball angular velocity, world, rad/s."""
        return self._vec(self._lib.dBodyGetAngularVel(self._ball))

    def torso_quat(self, index: int = 0) -> np.ndarray:
        """Torso orientation of robot ``index`` as a unit quaternion ``(w, x, y, z)``."""
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, self._rotation(self.robots[index].bodies[0]).ravel())
        return quat

    def torso_velocity(self, index: int = 0) -> np.ndarray:
        """Torso centre velocity of robot ``index``, world, m/s."""
        return self._vec(self._lib.dBodyGetLinearVel(self.robots[index].bodies[0]))

    def torso_angular_velocity(self, index: int = 0) -> np.ndarray:
        """Torso angular velocity of robot ``index``, world, rad/s."""
        return self._vec(self._lib.dBodyGetAngularVel(self.robots[index].bodies[0]))

    def gyro(self, index: int = 0) -> np.ndarray:
        """Torso angular velocity in the torso frame, deg/s (``GYR``, as the world's)."""
        torso = self.robots[index].bodies[0]
        return np.degrees(self.torso_angular_velocity(index) @ self._rotation(torso))

    def accelerometer(self, index: int = 0) -> np.ndarray:
        """The accelerometer (``ACC``) of robot ``index``, m/s², torso frame."""
        return self.robots[index].accel.copy()

    def force_sensors(self, index: int = 0) -> dict[str, ForceResistance]:
        """``FRP`` readings of robot ``index`` from the last step's contact feedback: force (N)
        and centre of pressure (m) in the foot's own frame, as
        :meth:`robocup_gym.sim.world.World.force_sensors` gives them (a foot without contact
        is omitted; one whose contacts carry no force repeats its last reading)."""
        r = self.robots[index]
        out: dict[str, ForceResistance] = {}
        for name, (force, centre) in r.frp.items():
            if centre is None:
                if name in r.last_frp:
                    out[name] = r.last_frp[name]
                continue
            body = r.frp_bodies[name]
            rot = self._rotation(body)
            origin = self._vec(self._lib.dBodyGetPosition(body))
            out[name] = ForceResistance(point=(centre - origin) @ rot, force=force @ rot)
        r.last_frp = out
        return out

    def torso_position(self, index: int = 0) -> np.ndarray:
        """Torso centre of robot ``index``, world, m."""
        return self._vec(self._lib.dBodyGetPosition(self.robots[index].bodies[0]))

    def torso_up(self, index: int = 0) -> np.ndarray:
        """The torso's up axis (+z of the torso frame) in world coordinates."""
        m = self._lib.dBodyGetRotation(self.robots[index].bodies[0])
        return np.array([m[2], m[6], m[10]])

    def joint_angles_deg(self, index: int = 0) -> np.ndarray:
        """Joint angles of robot ``index`` in degrees, canonical order."""
        lib = self._lib
        return np.degrees([lib.dJointGetHingeAngle(h) for h in self.robots[index].joints])

    def joint_velocities(self, index: int = 0) -> np.ndarray:
        """Joint angular velocities of robot ``index`` in rad/s, canonical order."""
        lib = self._lib
        return np.array([lib.dJointGetHingeAngleRate(h) for h in self.robots[index].joints])

    def asleep(self, index: int = 0) -> bool:
        """Whether every body of robot ``index`` is disabled by ODE's auto-disable."""
        lib = self._lib
        return not any(lib.dBodyIsEnabled(b) for b in self.robots[index].bodies)

    def close(self) -> None:
        """Free the ODE world (bodies, joints) and geoms."""
        if self._world is None:
            return
        lib = self._lib
        lib.dJointGroupEmpty(self._contacts)
        for g in [self._ground, self._ball_geom, *(g for r in self.robots for g in r.geoms)]:
            lib.dGeomDestroy(g)
        lib.dWorldDestroy(self._world)
        self._world = None

    def __del__(self) -> None:
        with contextlib.suppress(Exception):  # at interpreter shutdown ctypes may be gone
            self.close()

"""SimSpark's physics step re-created on ODE itself: the reference the MuJoCo world is checked
against.

rcssserver3d advances the Open Dynamics Engine once per 20 ms cycle (``dWorldStep``, ODE 0.16,
double precision). :class:`OdeWorld` builds the same robot (from the same tables,
:func:`robocup_gym.robot.nao.nao_model`), ball and ground on that engine, with the parameters of
``docs/reference/simspark.md``: world CFM 1e-5, surface layer 1 mm, auto-disable on; hinge
motors with FMax 10 N·m, CFM 1e-8, stop ERP 0.8 / CFM 1e-8, fudge factor 1e-5 and bounce 1;
contact surfaces mixed from each side's handler as SimSpark does (§7.3); drag before each step
(§7.5); the hinge effector's rules (clip to the joint's max speed, ignore commands while the
joint is not strictly inside its limits, wake the body on a non-zero command, §8.3).

It is the default engine of the environments and of ``robocup-gym serve``. It has every body
perceptor (joint angles, gyro, accelerometer, the foot force perceptors from ODE's contact
feedback, as SimSpark computes them), and the game state, hearing, vision and perception of
:mod:`robocup_gym.sim.senses`, the same code as the MuJoCo world's, and the field's walls and
goals (:mod:`robocup_gym.sim.field`). It needs the system
library ``libode`` (:mod:`robocup_gym.sim.engines.ode.lib`).

It has the MuJoCo world's interface (:class:`robocup_gym.sim.engines.mujoco.world.World`):
placing robots and the ball, commanding joints (``step`` or ``command``), ``beam``, readings,
and what the server's referee and monitor use (``body_frames``, ``ball_frame``,
``ball_touchers``, ``motor_targets``, ``export_robot_state``/``import_robot_state`` for its
rebuilds). ``benchmarks/ode_compare.py`` compares the two engines motion by motion.
"""

from __future__ import annotations

import contextlib
import copy
import ctypes
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields

import numpy as np

from robocup_gym.robot.nao import NaoModel, nao_model
from robocup_gym.sim import SimulationDivergedError
from robocup_gym.sim import compiled as compiled_step
from robocup_gym.sim import physics as phys
from robocup_gym.sim.engines.mujoco.scene import FRP_GEOMS
from robocup_gym.sim.engines.ode import lib as ode
from robocup_gym.sim.engines.ode.fast import SANE_SPEED, FastLoops
from robocup_gym.sim.engines.ode.fast import load as load_fast
from robocup_gym.sim.engines.ode.readings import OdeReadings
from robocup_gym.sim.engines.ode.surfaces import (
    BALL_SURFACE,
    GROUND_SURFACE,
    ROBOT_SURFACE,
    WALL_SURFACE,
    mix_surfaces,
    surface_parameters,
)
from robocup_gym.sim.field import GOAL_BOXES, WALLS
from robocup_gym.sim.pose import joint_angles_array, joint_index, placement_quat, rigid_move
from robocup_gym.sim.rotations import axis_angle_quat, quat_to_matrix
from robocup_gym.sim.senses import AgentState, Senses
from robocup_gym.sim.vision import VisionConfig
from robocup_gym.types import AgentCommand, ForceResistance, GameState

WORLD_CFM = 1e-5
"""SimSpark's world CFM (reference §7.1); the world ERP stays ODE's default 0.2."""
WORLD_ERP = 0.2
HINGE_CFM = 1e-8
HINGE_STOP_ERP, HINGE_STOP_CFM = phys.JOINT_STOP_ERP_CFM
HINGE_FUDGE_FACTOR = 1e-5
HINGE_STOP_BOUNCE = 1.0
MAX_CONTACTS = 4
"""Contact points per geom pair (reference §7.3)."""
SANE_POSITION = 1e3
"""A body this far (m) from the origin in a coordinate, or at NaN, means the world diverged."""


def _lowest(body, rot: np.ndarray, centre: np.ndarray) -> float:
    """Height of the lowest point of a collision shape (box, sphere, or capsule along its local
    z) with rotation ``rot`` and centre ``centre``, m."""
    size = np.asarray(body.size, dtype=float)
    if body.shape == "box":
        return float(centre[2] - np.abs(rot[2]) @ (size / 2))
    if body.shape == "sphere":
        return float(centre[2] - size[0])
    return float(centre[2] - abs(rot[2][2]) * size[1] / 2 - size[0])


def _apart(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two axis-aligned boxes ``(minx, maxx, miny, maxy, minz, maxz)`` are apart (then
    their geoms cannot touch); ``ode_step.c``'s ``apart`` is the same test."""
    return a[1] < b[0] or b[1] < a[0] or a[3] < b[2] or b[3] < a[2] or a[5] < b[4] or b[5] < a[4]


def _mat3(r: np.ndarray) -> ode.Mat3:
    """ODE's 3×4 rotation layout of a 3×3 matrix (the padding column 0)."""
    (a, b, c), (d, e, f), (g, h, i) = r.tolist()
    return ode.Mat3(a, b, c, 0.0, d, e, f, 0.0, g, h, i, 0.0)


_KINEMATICS: dict[int, tuple] = {}
"""Per robot model (by ``id``, the model kept alive in the entry): what
:meth:`OdeWorld._forward_kinematics` needs of it, as arrays, computed once."""


def _kinematics(model: NaoModel) -> tuple:
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


class OdeWorld(OdeReadings, Senses):
    """The SimSpark Nao world stepped by ODE 0.16 exactly as rcssserver3d steps it.

    Args:
        robot_types: One entry per robot (types 0–4).
        dead_time_cycles: Cycles between a command given to :meth:`step` and the step it first
            acts in, as :class:`robocup_gym.sim.engines.mujoco.world.World` (1 = SimSpark's
            sync-mode latency).
        compiled: Run the per-cycle loops in C (:mod:`robocup_gym.sim.engines.ode.fast`, bit-equal,
            twice as fast), as :class:`~robocup_gym.sim.engines.mujoco.world.World`'s argument of
            that name:
            ``None`` = ``ROBOCUP_GYM_COMPILED``, else whenever it can be built.
        vision: ``See`` settings (noise, field of view, interval, ground-truth extensions), as
            the MuJoCo world's; vision, hearing and the game state are the same code on both
            engines (:mod:`robocup_gym.sim.senses`).
        seed: Seed of the vision noise and calibration offsets.

    Raises:
        robocup_gym.sim.engines.ode.lib.OdeUnavailableError: when ``libode`` is missing.
    """

    def __init__(
        self,
        robot_types: Sequence[int] = (0,),
        *,
        dead_time_cycles: int = 1,
        compiled: bool | None = None,
        vision: VisionConfig | None = None,
        seed: int | None = None,
    ) -> None:
        self._lib = lib = ode.load()
        self.dead_time_cycles = int(dead_time_cycles)
        self.time = 0.0
        self.cycle = 0
        self.game = GameState()
        self.vision_config = vision or VisionConfig()
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.engine_seconds: float | None = None
        """Set to 0.0 to accumulate the wall time of ODE's own work (contact generation and
        ``dWorldStep``) in each step; ``benchmarks/throughput.py`` compares it with the whole
        step. ``None``: not measured."""
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
        self._statics = []
        """The walls and the goals' solid parts (reference §6.2, §6.3): static boxes, no body."""
        for _name, centre, size in (*WALLS, *GOAL_BOXES):
            g = lib.dCreateBox(None, *size)
            lib.dGeomSetPosition(g, *centre)
            self._statics.append(g)
        self.robots = [self._build_robot(int(t)) for t in robot_types]
        self._contact_buf = (ode.ContactGeom * MAX_CONTACTS)()
        self._contact = ode.Contact()
        self._pairs = self._collision_pairs()
        # the AABB pre-test: every geom but the ground plane has a slot; a pair whose boxes are
        # apart cannot touch, so dCollide (which would return no contact) is skipped for it
        self._slot_geoms = [
            self._ball_geom,
            *self._statics,
            *(g for r in self.robots for g in r.geoms),
        ]
        slot = {g: k for k, g in enumerate(self._slot_geoms)}
        self._pair_slots = np.array(
            [(slot.get(p[0], -1), slot.get(p[1], -1)) for p in self._pairs], dtype=np.int32
        ).reshape(-1, 2)
        self._aabb = np.zeros((len(self._slot_geoms), 6))
        n_sensed = sum(1 for p in self._pairs if p[5] or p[6])
        self._feedback = (ode.JointFeedback * (MAX_CONTACTS * max(n_sensed, 1)))()
        """Contact feedback slots for the contacts of foot/toe geoms (SimSpark's ``FRP``)."""
        self._feedback_view = np.frombuffer(self._feedback, dtype=np.float64).reshape(-1, 16)
        """The slots as numbers: force on body 1 in columns 0–2, on body 2 in 8–10."""
        self._hit = np.full(len(self._pairs), -1, dtype=np.int32)
        """Per pair, the stamp of the last collision pass in which it made a contact."""
        self._stamp = 0
        """Number of collision passes so far (the stamp of the latest)."""
        robot_of = {g: i for i, r in enumerate(self.robots) for g in r.geoms}
        ball_pairs = [
            (p, robot_of[pair[0]])
            for p, pair in enumerate(self._pairs)
            if pair[1] == self._ball_geom and pair[0] in robot_of
        ]
        self._ball_pairs = np.array([p for p, _ in ball_pairs], dtype=np.int64)
        self._ball_pair_robot = np.array([i for _, i in ball_pairs], dtype=np.int64)
        # pairs of two robots' geoms whose contacts rcssserver3d's agent-collision handler sees
        # (every part but the feet and toes carries one; a contact fires each handler it has)
        robot_pairs = [
            (p, robot_of[pair[0]], robot_of[pair[1]], (pair[5] is None) + (pair[6] is None))
            for p, pair in enumerate(self._pairs)
            if pair[0] in robot_of and pair[1] in robot_of
        ]
        robot_pairs = [rp for rp in robot_pairs if rp[3]]
        self._robot_pairs = np.array([rp[0] for rp in robot_pairs], dtype=np.int64)
        self._robot_pair_info = [rp[1:] for rp in robot_pairs]
        self._robot_pair_of = np.full(len(self._pairs), -1, dtype=np.int64)
        """Each pair's index in ``_robot_pairs`` (-1: not two robots' parts)."""
        self._robot_pair_of[self._robot_pairs] = np.arange(len(self._robot_pairs))
        self._robot_contacts: dict[tuple[int, int], tuple[np.ndarray, int]] = {}
        self._robot_contacts_stamp = -1
        self._queued: dict[int, np.ndarray] = {}
        """Commands given with :meth:`command` for the next :meth:`step`."""
        self._pushes: dict[int, tuple[float, float, float]] = {}
        """Robot index → the external force on its torso (:meth:`set_torso_force`)."""
        self._out_pair = np.zeros(len(self._feedback), dtype=np.int32)
        self._out_pos = np.zeros((len(self._feedback), 3))
        pair_frp = [(p[5], p[6]) for p in self._pairs]  # each body's (robot, name) or None
        self._frp_slots = list(dict.fromkeys(f for pair in pair_frp for f in pair if f))
        """Every force perceptor ``(robot, name)`` that a pair can touch: the rows of
        ``_frp_sums``."""
        slot_of = {f: k for k, f in enumerate(self._frp_slots)}
        self._pair_frp_slot = np.array(
            [[-1 if f is None else slot_of[f] for f in pair] for pair in pair_frp],
            dtype=np.int32,
        ).reshape(-1, 2)
        """Per pair, the ``_frp_slots`` row of its two bodies' force perceptors (-1: none)."""
        self._frp_sums = np.zeros((max(len(self._frp_slots), 1), 8))
        """Per force perceptor, the last step's sums (:meth:`_read_feedback`)."""
        self._frp_pending = False
        """Whether the robots' ``frp`` are still to be made from the sums (:meth:`_sync_frp`)."""
        # the state snapshot every reading comes from (one C call per step, see _read_state)
        self._state_bodies = self._drag_bodies()
        self._row = {b: k for k, b in enumerate(self._state_bodies)}
        self._state = np.zeros((len(self._state_bodies), 18))
        self._all_joints = [h for r in self.robots for h in r.joints]
        self._angles = np.zeros(len(self._all_joints))
        self._rates = np.zeros(len(self._all_joints))
        start = 0
        for r in self.robots:
            r.joint_slice = slice(start, start + len(r.joints))
            start += len(r.joints)
        self._fresh = False
        self._fast = self._init_fast(compiled_step.wanted() if compiled is None else compiled)
        self._reset_senses()
        self.place_ball((0.0, 0.0))
        for i in range(len(self.robots)):
            self.place_robot(i, -1.0 - 1.0 * i, 0.0)

    def reseed(self, seed: int | None) -> None:
        """Restart the vision noise from ``seed`` and draw new calibration offsets (as the MuJoCo
        world's ``reset(seed=...)`` does); the physical state is left as it is."""
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self._reset_senses()

    # ------------------------------------------------------------------ construction
    def _build_robot(self, type_index: int) -> OdeRobot:
        """One robot of type ``type_index`` in the zero pose at the origin (torso frame = world
        frame, so the reference's anchors and axes apply as they are); :meth:`place_robot` moves
        it."""
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

    def _collision_pairs(self) -> list[tuple]:
        """Every geom pair that can touch, as ``(geom1, geom2, body1, body2, surface)`` (body
        ``None`` for the static ground) with its mixed surface: robot parts with the ground,
        the ball and other robots' parts (never with their own robot: inner collision is
        disabled, reference §1.1); the ball with the ground."""
        robot_ground = surface_parameters(mix_surfaces(ROBOT_SURFACE, GROUND_SURFACE))
        robot_ball = surface_parameters(mix_surfaces(ROBOT_SURFACE, BALL_SURFACE))
        robot_robot = surface_parameters(mix_surfaces(ROBOT_SURFACE, ROBOT_SURFACE))
        ball_ground = surface_parameters(mix_surfaces(BALL_SURFACE, GROUND_SURFACE))
        robot_wall = surface_parameters(mix_surfaces(ROBOT_SURFACE, WALL_SURFACE))
        ball_wall = surface_parameters(mix_surfaces(BALL_SURFACE, WALL_SURFACE))
        pairs = [(self._ball_geom, self._ground, ball_ground)]
        for i, r in enumerate(self.robots):
            for g in r.geoms:
                pairs.append((g, self._ground, robot_ground))
                pairs.append((g, self._ball_geom, robot_ball))
                for other in self.robots[i + 1 :]:
                    pairs.extend((g, g2, robot_robot) for g2 in other.geoms)
        # walls and goals last: they touch nothing near the centre of the field, so the order of
        # the contacts (and so every result) there is that of a world without them
        for w in self._statics:
            pairs.append((self._ball_geom, w, ball_wall))
            pairs.extend((g, w, robot_wall) for r in self.robots for g in r.geoms)
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
        ball = (phys.BALL_LINEAR_DRAG, phys.BALL_ANGULAR_DRAG)
        bodies = [(b, ball if b == self._ball else (lin, ang)) for b in self._drag_bodies()]
        robots = [
            (r.bodies, r.joints, r.child_body, r.limits, r.model.max_speeds) for r in self.robots
        ]
        return FastLoops(
            self._lib,
            bodies,
            robots,
            self._world,
            self._contacts,
            self._pairs,
            self._feedback,
            MAX_CONTACTS,
            self._slot_geoms,
            self._pair_slots,
            (self._state_bodies, self._state, self._all_joints, self._angles, self._rates),
            (self._out_pair, self._out_pos),
            self._hit,
            (self._pair_frp_slot, self._frp_sums),
            SANE_POSITION,
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
        quat: Sequence[float] | None = None,
        forward: bool = True,
    ) -> None:
        """Teleport robot ``index`` with zero velocities and motor targets, as the trainer's
        ``move`` does; ``z`` = torso centre height (``None``: lowest point 1 mm deep, ODE's
        resting depth, as :meth:`robocup_gym.sim.engines.mujoco.world.World.place_robot` puts it),
        ``joint_angles_deg`` in canonical order or by name (others 0; ``None`` keeps the current
        angles, as the MuJoCo world does: a rigid move), ``quat`` a full torso
        orientation ``(w, x, y, z)`` instead of upright facing ``heading_deg``. ``asleep``
        leaves every body disabled, as ODE's auto-disable leaves a robot that was resting when
        moved. ``forward`` is accepted for the MuJoCo world's interface (nothing to recompute
        here)."""
        lib = self._lib
        r = self.robots[index]
        model = r.model
        q = placement_quat(x, y, z, heading_deg, quat)
        angles = (
            self.joint_angles_deg(index)
            if joint_angles_deg is None
            else joint_angles_array(model, joint_angles_deg)
        )
        rot, trans = self._forward_kinematics(model, np.radians(angles), q)
        links = _kinematics(model)[1]
        centres = [rot[i] @ link[4] + trans[i] for i, link in enumerate(links)]
        if z is None:
            shift = -phys.SURFACE_LAYER - min(
                _lowest(b, rot[i], c)
                for i, (b, c) in enumerate(zip(model.bodies, centres, strict=True))
                if b.collides
            )
        else:
            shift = z - centres[0][2]
        if self._fast is not None:
            pos = np.array(centres)
            pos[:, 0] += x
            pos[:, 1] += y
            pos[:, 2] += shift
            self._fast.place(index, pos, np.array(rot), asleep)
        else:  # the same ODE calls in Python
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
        self._queued.pop(index, None)
        r.prev_vel[:] = 0.0
        r.accel[:] = (0.0, 0.0, phys.GRAVITY)
        self._sync_frp()  # the sums of the last step must not overwrite this later
        r.frp = {}
        r.last_frp = {}
        self._fresh = False

    def move_robot(
        self,
        index: int,
        pos: Sequence[float] | None = None,
        *,
        heading_deg: float | None = None,
        rot_deg: Sequence[float] | None = None,
    ) -> None:
        """Move robot ``index`` rigidly as rcssserver3d moves an agent (the trainer's ``move``,
        ``pos`` and ``rot``, ``beam``, the referee): every body keeps its place relative to the
        torso as the physics left it (:func:`robocup_gym.sim.pose.rigid_move`, in SimSpark's
        single precision), all velocities become zero, and nothing else changes: joint motor
        targets, pending commands, the sensors' memory, and whether ODE's auto-disable has the
        bodies asleep (a robot that was resting hangs where it was put until a motor or a
        moving body wakes it, as on the real server).

        Raises:
            ValueError: a position or angle that is not finite.
        """
        for name, value in (("pos", pos), ("rot_deg", rot_deg)):
            if value is not None and not np.all(np.isfinite(np.asarray(value, float))):
                raise ValueError(f"robot move {name} must be finite, got {value!r}")
        if heading_deg is not None and not math.isfinite(heading_deg):
            raise ValueError(f"robot move heading_deg must be finite, got {heading_deg}")
        lib = self._lib
        bodies = self.robots[index].bodies
        positions, rotations = self.body_frames(index)
        new_pos, new_rot = rigid_move(
            positions, rotations, pos, heading_deg=heading_deg, rot_deg=rot_deg
        )
        turned = heading_deg is not None or rot_deg is not None
        for k, body in enumerate(bodies):
            lib.dBodySetPosition(body, *new_pos[k].tolist())
            if turned:
                lib.dBodySetRotation(body, _mat3(new_rot[k]))
            lib.dBodySetLinearVel(body, 0.0, 0.0, 0.0)
            lib.dBodySetAngularVel(body, 0.0, 0.0, 0.0)
        self._fresh = False

    @staticmethod
    def _forward_kinematics(
        model: NaoModel, angles: np.ndarray, quat: np.ndarray
    ) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Per body, the rotation and translation that take zero-pose torso-frame points to
        world points (relative to the torso's x, y; torso centre at height 0) for a torso with
        orientation ``quat``."""
        root = quat_to_matrix(quat)
        links = _kinematics(model)[1]
        rot: list = [None] * len(links)
        trans: list = [None] * len(links)
        for i, (p, k, axis, a, _) in enumerate(links):  # parents come before their children
            if p < 0:
                rot[i], trans[i] = root, np.zeros(3)
                continue
            turn = quat_to_matrix(axis_angle_quat(axis, angles[k]))
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
        self._fresh = False

    # ------------------------------------------------------------------ stepping
    def command(self, index: int, command: AgentCommand | Mapping[str, float] | np.ndarray) -> None:
        """Give robot ``index`` its command for the next :meth:`step` (as the MuJoCo world's
        ``command``): joint velocities in rad/s (by name, or an array in canonical order), or an
        :class:`~robocup_gym.types.AgentCommand` whose ``beam`` and ``say`` act at once. A
        second command before the step overrides the first joint by joint.

        Raises:
            KeyError: an unknown joint name (listing the valid ones).
            ValueError: a NaN/inf velocity (naming the joint) or an array of the wrong shape.
        """
        r = self.robot(index)
        if isinstance(command, AgentCommand):
            arr = self._command_array(r, command.joint_velocities)
            if command.beam is not None:
                self.beam(index, *command.beam)
            if command.say is not None:
                self.say(index, command.say)
        else:
            arr = self._command_array(r, command)
        old = self._queued.get(index)
        if old is not None:
            arr = np.where(np.isnan(arr), old, arr)
        self._queued[index] = arr

    def step(self, commands: Mapping[int, Mapping[str, float] | np.ndarray] | None = None) -> None:
        """Advance one 20 ms cycle: realise due commands (target rad/s, clipped to the joint's
        max speed, ignored for a joint not strictly inside its limits, a non-zero one wakes the
        joint's child body), drag on every body, collisions, one ``dWorldStep(0.02)``.
        ``commands`` (robot index → velocities) come on top of those given with
        :meth:`command` since the last step."""
        commands = commands or {}
        arrays = [  # all validated before any is queued
            None if commands.get(i) is None else self._command_array(r, commands[i])
            for i, r in enumerate(self.robots)
        ]
        if self._queued:
            for i, queued in self._queued.items():
                a = arrays[i]
                arrays[i] = queued if a is None else np.where(np.isnan(a), queued, a)
            self._queued = {}
        for i, (r, cmd) in enumerate(zip(self.robots, arrays, strict=True)):
            r.pending.append(cmd)
            if len(r.pending) > self.dead_time_cycles:
                due = r.pending.pop(0)
                if due is not None:
                    due = self._frozen_to_zero(i, due)
                if due is not None and self._fast is not None:
                    self._fast.realise(i, due)
                elif due is not None:
                    self._realise(r, due)
        self._sense_accelerometers()
        bad = self._fast.drag() if self._fast is not None else self._apply_drag()
        if bad >= 0:
            raise SimulationDivergedError(
                f"the ODE world diverged before cycle {self.cycle + 1} (t = {self.time:.2f} s): "
                f"{self._body_name(bad)} has a velocity that is not finite or beyond "
                f"{SANE_SPEED:g}; place the ball and robots again"
            )
        for i, force in self._pushes.items():
            torso = self.robots[i].bodies[0]
            self._lib.dBodyEnable(torso)  # a push wakes a robot that ODE put to sleep
            self._lib.dBodyAddForce(torso, *force)
        self._collide_and_step()
        self._fresh = False
        self.cycle += 1
        self._advance_clocks(phys.CYCLE_S)
        self._check_sane()

    def set_torso_force(self, index: int, force: Sequence[float]) -> None:
        """Push robot ``index``'s torso with ``force`` (N, world frame, at its centre of mass)
        in every cycle until it is changed; ``(0, 0, 0)`` ends it. SimSpark has no such force:
        it is a training aid (``TrainConfig.assist_force``, which lifts a robot that learns to
        get up), never part of an evaluation.

        Raises:
            ValueError: ``force`` is not three finite numbers.
        """
        f = phys.finite_force(force)
        self.robots[index]  # IndexError for an unknown robot
        if any(f):
            self._pushes[index] = f
        else:
            self._pushes.pop(index, None)

    def _check_sane(self) -> None:
        """Raise :class:`~robocup_gym.sim.SimulationDivergedError` (as the MuJoCo world does)
        when a body left the finite, plausible range (NaN/inf, or ``SANE_POSITION`` = 1 km
        away): ODE blew up. Re-placing the ball and every robot recovers. Reads the state
        snapshot that the next perception reads anyway."""
        if self._fast is not None:
            k = self._fast.read()
            self._fresh = True
        else:
            positions = self._read_state()[:, 0:3]
            ok = (np.abs(positions) < SANE_POSITION).all(axis=1)  # NaN fails too
            k = -1 if ok.all() else int(np.argmin(ok))
        if k >= 0:
            positions = self._state[:, 0:3]
            raise SimulationDivergedError(
                f"the ODE world diverged at cycle {self.cycle} (t = {self.time:.2f} s): "
                f"{self._body_name(k)} is at ({', '.join(f'{v:.3f}' for v in positions[k])}) m; "
                "place the ball and robots again"
            )

    def sense_contacts(self) -> None:
        """Fill the force perceptors for the current state without advancing it: with the
        contact forces ODE's next step would apply (what MuJoCo's ``mj_forward`` gives the
        world at a placement), so that the perception of a freshly placed robot shows its feet
        loaded, as every later one does. The state is put back exactly; nothing else changes
        (ODE's big-matrix step keeps no warm start, and placing re-arms auto-disable)."""
        if self._fast is not None:
            state = self._fast.save_bodies()
            self._collide_and_step()
            self._fast.restore_bodies(state)
            self._fresh = False
            return
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
        self._fresh = False

    def _collide_and_step(self) -> None:
        """Contacts for the current poses, one ``dWorldStep(0.02)``, the force perceptors."""
        lib = self._lib
        self._stamp += 1
        stamp = self._stamp
        if self.engine_seconds is None:
            sensed = self._fast.collide(stamp) if self._fast is not None else self._collide(stamp)
            if len(self._robot_pairs):
                self._note_robot_contacts(stamp)
            lib.dWorldStep(self._world, phys.CYCLE_S)
        else:  # measuring: the engine's own share (collision and dWorldStep)
            t0 = time.perf_counter()
            sensed = self._fast.collide(stamp) if self._fast is not None else self._collide(stamp)
            if len(self._robot_pairs):
                self._note_robot_contacts(stamp)
            lib.dWorldStep(self._world, phys.CYCLE_S)
            self.engine_seconds += time.perf_counter() - t0
        self._read_feedback(sensed)  # the number of sensed contacts
        lib.dJointGroupEmpty(self._contacts)

    def _note_robot_contacts(self, stamp: int) -> None:
        """The contacts between robots made by this collision pass, by robot pair, as
        rcssserver3d's agent-collision handlers see them (:meth:`robot_contacts`). The contact
        points of the pairs that touched are computed again (``dCollide`` of the same poses
        gives the same points), before the step moves the bodies."""
        hit = self._robot_pair_of[np.flatnonzero(self._hit == stamp)]
        hit = hit[hit >= 0]
        self._robot_contacts_stamp = stamp
        if not hit.size:
            self._robot_contacts = {}
            return
        lib, buf = self._lib, self._contact_buf
        size = ctypes.sizeof(ode.ContactGeom)
        sums: dict[tuple[int, int], list] = {}
        for k in hit.tolist():
            g1, g2 = self._pairs[int(self._robot_pairs[k])][:2]
            i, j, weight = self._robot_pair_info[k]
            n = lib.dCollide(g1, g2, MAX_CONTACTS, buf, size)
            acc = sums.setdefault((i, j), [np.zeros(3), 0])
            for c in range(n):
                acc[0] += weight * np.array(buf[c].pos[:3])
                acc[1] += weight
        self._robot_contacts = {ij: (total / n, n) for ij, (total, n) in sums.items() if n}

    def _collide(self, stamp: int) -> int:
        """Contact joints for the current poses (the Python loop; ``ode_step.c``'s
        ``ode_collide`` does the same): the contacts of foot/toe geoms get feedback slots in
        order, their pairs and positions go to ``_out_pair``/``_out_pos``; returns how many.
        Every pair that touches gets ``stamp`` in ``_hit``."""
        lib = self._lib
        buf, contact = self._contact_buf, self._contact
        size = ctypes.sizeof(ode.ContactGeom)
        m = 0
        aabb = self._aabb
        box = (ode.dReal * 6)()
        for k, g in enumerate(self._slot_geoms):
            lib.dGeomGetAABB(g, box)
            aabb[k] = box[:]
        for p, ((g1, g2, b1, b2, surface, frp1, frp2), (s1, s2)) in enumerate(
            zip(self._pairs, self._pair_slots, strict=True)
        ):
            if s1 >= 0 and s2 >= 0 and _apart(aabb[s1], aabb[s2]):
                continue
            n = lib.dCollide(g1, g2, MAX_CONTACTS, buf, size)
            if n:
                self._hit[p] = stamp
                contact.surface = surface
                for k in range(n):
                    contact.geom = buf[k]
                    joint = lib.dJointCreateContact(self._world, self._contacts, contact)
                    lib.dJointAttach(joint, b1, b2)
                    if frp1 or frp2:
                        lib.dJointSetFeedback(joint, self._feedback[m])
                        self._out_pair[m] = p
                        self._out_pos[m] = buf[k].pos[:3]
                        m += 1
        return m

    def _sense_accelerometers(self) -> None:
        """Each torso's accelerometer, sampled as
        :class:`robocup_gym.sim.engines.mujoco.world.World` samples
        it (reference §4.5): the change of the torso's velocity since the last sample over one cycle
        plus gravity, in the torso frame, m/s²; taken just before the physics step."""
        st = self._read_state()
        for r in self.robots:
            row = st[self._row[r.bodies[0]]]
            v = row[12:15].copy()
            a = (v - r.prev_vel) / phys.CYCLE_S
            a[2] += phys.GRAVITY
            r.prev_vel[:] = v
            r.accel[:] = a @ row[3:12].reshape(3, 3)

    def _read_feedback(self, m: int) -> None:
        """SimSpark's force resistance perceptors from the step's contact feedback (reference §4.6):
        per foot/toe the total contact force on it and the contacts' centre weighted by the
        magnitude of each contact's force, world frame. ``m`` sensed contacts: contact ``k``
        has feedback slot ``k``, pair ``self._out_pair[k]`` and position ``self._out_pos[k]``
        (written alike by the compiled and the Python contact loops). Both sum into
        ``_frp_sums`` (the compiled ``ode_frp``, or this Python loop: the same additions in
        the same order); :meth:`_sync_frp` makes the readings when they are read."""
        self._frp_pending = True
        if self._fast is not None:
            self._fast.frp(m)
            return
        sums: dict[int, list[float]] = {}
        fb = self._feedback_view
        for k in range(m):
            p = int(self._out_pair[k])
            pos = self._out_pos[k]
            for slot, f in (
                (self._pair_frp_slot[p, 0], fb[k, 0:3]),
                (self._pair_frp_slot[p, 1], fb[k, 8:11]),
            ):
                if slot < 0:
                    continue
                fx, fy, fz = float(f[0]), float(f[1]), float(f[2])
                acc = sums.setdefault(int(slot), [0.0] * 8)
                magnitude = math.sqrt(fx * fx + fy * fy + fz * fz)
                acc[0] += fx
                acc[1] += fy
                acc[2] += fz
                acc[3] += magnitude * float(pos[0])
                acc[4] += magnitude * float(pos[1])
                acc[5] += magnitude * float(pos[2])
                acc[6] += magnitude
                acc[7] += 1.0
        self._frp_sums[:] = 0.0
        for slot, acc in sums.items():
            self._frp_sums[slot] = acc

    def _sync_frp(self) -> None:
        """Make every robot's ``frp`` from the last step's sums (:meth:`_read_feedback`), if not
        done yet: the arrays are only built for a step whose perception is read."""
        if not self._frp_pending:
            return
        self._frp_pending = False
        for r in self.robots:
            r.frp = {}
        sums = self._frp_sums
        for k in np.flatnonzero(sums[:, 7]).tolist():  # in _frp_slots order
            i, name = self._frp_slots[k]
            a = sums[k]
            total = a[6]
            centre = a[3:6] / total if total > 0.0 else None
            self.robots[i].frp[name] = (a[0:3].copy(), centre)

    def _command_array(self, r: OdeRobot, cmd: Mapping[str, float] | np.ndarray) -> np.ndarray:
        """Targets in canonical order, rad/s; NaN marks a joint the command leaves alone.

        Raises:
            KeyError: an unknown joint name (listing the valid ones).
            ValueError: a NaN/inf velocity (naming the joint) or an array of the wrong shape.
        """
        names = r.model.effector_names
        if isinstance(cmd, np.ndarray) and cmd.shape == (len(names),):  # the common case
            out = cmd.astype(float)  # a copy: the queue keeps it
            if not np.isfinite(out).all():
                k = int(np.argmin(np.isfinite(out)))
                raise ValueError(f"velocity command for joint {names[k]} is {out[k]}")
            return out
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

    def _drag_bodies(self) -> list[int]:
        """Every body that feels drag, in the compiled loop's order: robots' parts, the ball."""
        return [*(b for r in self.robots for b in r.bodies), self._ball]

    def _body_name(self, k: int) -> str:
        """A readable name of body ``k`` of :meth:`_drag_bodies`."""
        for i, r in enumerate(self.robots):
            if k < len(r.bodies):
                return f"robot {i}'s {r.model.bodies[k].name}"
            k -= len(r.bodies)
        return "the ball"

    def _apply_drag(self) -> int:
        """Drag on every body, after checking every body's velocity as ``ode_drag`` does;
        returns the index of an insane body (nothing applied then), else -1."""
        lib = self._lib
        bodies = self._drag_bodies()
        for k, b in enumerate(bodies):
            v, w = lib.dBodyGetLinearVel(b), lib.dBodyGetAngularVel(b)
            if not all(abs(v[j]) < SANE_SPEED and abs(w[j]) < SANE_SPEED for j in range(3)):
                return k
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
        return -1

    # ------------------------------------------------------------------ state
    def forward(self) -> None:
        """Nothing to do: ODE keeps no derived quantities (kept for the MuJoCo world's
        interface, whose ``forward`` recomputes body poses after a change of state)."""

    def export_robot_state(self, index: int) -> dict:
        """Everything of robot ``index`` a rebuilt world needs to go on with it: every body's
        pose, velocities and whether ODE has it disabled, motor targets, pending commands,
        accelerometer history, foot contacts, and the agent's state (team, hearing, vision
        phase and calibration). With :meth:`import_robot_state` it moves a robot into a new
        world (the ``serve`` server rebuilds its world when robots join or leave)."""
        lib = self._lib
        r = self.robot(index)
        self._sync_frp()
        bodies = [
            (
                self._vec(lib.dBodyGetPosition(b)),
                np.array(lib.dBodyGetQuaternion(b)[:4]),
                self._vec(lib.dBodyGetLinearVel(b)),
                self._vec(lib.dBodyGetAngularVel(b)),
                bool(lib.dBodyIsEnabled(b)),
            )
            for b in r.bodies
        ]
        agent = {f.name: copy.deepcopy(getattr(r, f.name)) for f in fields(AgentState)}
        return {
            "robot_type": r.model.robot_type.index,
            "bodies": bodies,
            "targets": self.motor_targets(index),
            "pending": [None if c is None else c.copy() for c in r.pending],
            "queued": None if index not in self._queued else self._queued[index].copy(),
            "prev_vel": r.prev_vel.copy(),
            "accel": r.accel.copy(),
            "frp": copy.deepcopy(r.frp),
            "last_frp": copy.deepcopy(r.last_frp),
            "agent": agent,
        }

    def import_robot_state(self, index: int, state: Mapping) -> None:
        """Restore what :meth:`export_robot_state` returned (from a robot of the same type, in
        any ODE world) into robot ``index``.

        Raises:
            ValueError: the state is of a robot of another type.
        """
        lib = self._lib
        r = self.robot(index)
        if state["robot_type"] != r.model.robot_type.index:
            raise ValueError(
                f"robot state of type {state['robot_type']} cannot go into robot {index} of "
                f"type {r.model.robot_type.index}"
            )
        for b, (pos, quat, vel, ang, enabled) in zip(r.bodies, state["bodies"], strict=True):
            lib.dBodySetPosition(b, *map(float, pos))
            lib.dBodySetQuaternion(b, ode.Vec4(*map(float, quat)))
            lib.dBodySetLinearVel(b, *map(float, vel))
            lib.dBodySetAngularVel(b, *map(float, ang))
            (lib.dBodyEnable if enabled else lib.dBodyDisable)(b)
        self.set_motor_targets(index, state["targets"])
        r.pending = [None if c is None else c.copy() for c in state["pending"]]
        if state["queued"] is None:
            self._queued.pop(index, None)
        else:
            self._queued[index] = state["queued"].copy()
        r.prev_vel[:] = state["prev_vel"]
        r.accel[:] = state["accel"]
        self._sync_frp()  # the sums of the last step must not overwrite this later
        r.frp = copy.deepcopy(state["frp"])
        r.last_frp = copy.deepcopy(state["last_frp"])
        for name, value in state["agent"].items():
            setattr(r, name, copy.deepcopy(value))
        self._fresh = False

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
        geoms = [self._ground, self._ball_geom, *self._statics]
        for g in geoms + [g for r in self.robots for g in r.geoms]:
            lib.dGeomDestroy(g)
        lib.dWorldDestroy(self._world)
        self._world = None

    def __del__(self) -> None:
        with contextlib.suppress(Exception):  # at interpreter shutdown ctypes may be gone
            self.close()

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
from collections.abc import Mapping, Sequence
from dataclasses import fields

import numpy as np

from robocup_gym.robot.nao import NaoModel
from robocup_gym.sim import SimulationDivergedError
from robocup_gym.sim import compiled as compiled_step
from robocup_gym.sim import physics as phys
from robocup_gym.sim.engines.ode import lib as ode
from robocup_gym.sim.engines.ode.contacts import MAX_CONTACTS, OdeContacts
from robocup_gym.sim.engines.ode.fast import SANE_SPEED, FastLoops
from robocup_gym.sim.engines.ode.fast import load as load_fast
from robocup_gym.sim.engines.ode.motors import OdeMotors
from robocup_gym.sim.engines.ode.readings import OdeReadings
from robocup_gym.sim.engines.ode.robot import build_robot, kinematics
from robocup_gym.sim.field import GOAL_BOXES, WALLS
from robocup_gym.sim.pose import (
    ball_placement,
    joint_angles_array,
    placement_quat,
    rigid_move,
)
from robocup_gym.sim.rotations import axis_angle_quat, quat_to_matrix
from robocup_gym.sim.senses import AgentState, Senses
from robocup_gym.sim.vision import VisionConfig
from robocup_gym.types import GameState

WORLD_CFM = 1e-5
"""SimSpark's world CFM (reference §7.1); the world ERP stays ODE's default 0.2."""
WORLD_ERP = 0.2
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


def _mat3(r: np.ndarray) -> ode.Mat3:
    """ODE's 3×4 rotation layout of a 3×3 matrix (the padding column 0)."""
    (a, b, c), (d, e, f), (g, h, i) = r.tolist()
    return ode.Mat3(a, b, c, 0.0, d, e, f, 0.0, g, h, i, 0.0)


class OdeWorld(OdeMotors, OdeContacts, OdeReadings, Senses):
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
        # Its own step scheduler: without one every world shares ODE's global self-threaded
        # implementation, whose job lists are not locked, and worlds stepped at the same time in
        # different threads (ctypes releases the GIL inside dWorldStep) corrupt them and abort
        # the process. The scheduler runs the same jobs in the same order: results are unchanged.
        self._threading = lib.dThreadingAllocateSelfThreadedImplementation()
        if not self._threading:
            raise MemoryError("ODE could not allocate a step scheduler for a new world")
        lib.dWorldSetStepThreadingImplementation(
            self._world, lib.dThreadingImplementationGetFunctions(self._threading), self._threading
        )
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
        self.robots = [build_robot(lib, self._world, int(t)) for t in robot_types]
        self._queued: dict[int, np.ndarray] = {}
        """Commands given with :meth:`command` for the next :meth:`step`."""
        self._pushes: dict[int, tuple[float, float, float]] = {}
        """Robot index → the external force on its torso (:meth:`set_torso_force`)."""
        self._init_contacts()
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
        links = kinematics(model)[1]
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
        links = kinematics(model)[1]
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
        p, v, w = ball_placement(pos, vel, angular_vel)
        z = p[2] if len(p) > 2 else phys.BALL_RADIUS - phys.SURFACE_LAYER
        lib.dBodySetPosition(self._ball, float(p[0]), float(p[1]), float(z))
        lib.dBodySetRotation(self._ball, _mat3(np.eye(3)))
        lib.dBodySetLinearVel(self._ball, *map(float, v))
        lib.dBodySetAngularVel(self._ball, *map(float, w))
        lib.dBodyEnable(self._ball)
        self._fresh = False

    # ------------------------------------------------------------------ stepping
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
        if self._threading:
            lib.dThreadingFreeImplementation(self._threading)
        self._world = None

    def __del__(self) -> None:
        with contextlib.suppress(Exception):  # at interpreter shutdown ctypes may be gone
            self.close()

"""The embedded SimSpark world on MuJoCo: robots, ball, field, 20 ms cycles, perception.

:class:`World` is the fast approximation of the ODE world (the default engine,
:class:`~robocup_gym.sim.engines.ode.OdeWorld`), with the same interface. One
:meth:`World.step` is one SimSpark agent cycle (0.02 s). Joints are velocity-controlled exactly as
on rcssserver3d (target angular velocity in rad/s, clipped to the joint's max speed, driven by a
10 N·m motor; commands are ignored while a joint is at or beyond a stop), with a configurable dead
time between a command and its effect (one cycle by default, as SimSpark). Perception is built on
demand in SimSpark's units and frames (:class:`robocup_gym.types.Perception`).

Example::

    world = World(robot_types=[0])
    world.place_robot(0, x=-1.0, y=0.0, heading_deg=0.0)
    world.place_ball((-0.8, -0.055))
    for _ in range(50):
        world.step({0: AgentCommand({"rle3": -6.14})})
    p = world.perceive(0)
    print(p.joint("rlj3"), p.ground_truth.ball_pos)
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping, Sequence

import mujoco
import numpy as np

from robocup_gym.sim import SimulationDivergedError
from robocup_gym.sim import compiled as compiled_step
from robocup_gym.sim import physics as phys
from robocup_gym.sim.engines.mujoco.commands import WorldCommands
from robocup_gym.sim.engines.mujoco.layout import WorldLayout
from robocup_gym.sim.engines.mujoco.motors import OdeRowsNumpy
from robocup_gym.sim.engines.mujoco.readings import WorldReadings
from robocup_gym.sim.engines.mujoco.robot import RobotState
from robocup_gym.sim.engines.mujoco.scene import (
    RobotSlot,
    apply_ode_softness,
    scene_xml,
)
from robocup_gym.sim.engines.mujoco.sleep import AUTO_DISABLE_SPEED, AutoDisable
from robocup_gym.sim.memory import release_free_memory
from robocup_gym.sim.physics import CYCLE_S, PhysicsConfig
from robocup_gym.sim.pose import (
    ball_placement,
    joint_angles_array,
    placement_quat,
    rigid_move,
)
from robocup_gym.sim.senses import Senses
from robocup_gym.sim.vision import VisionConfig
from robocup_gym.types import (
    AgentCommand,
    GameState,
)

_DIVERGENCE_WARNINGS = (
    int(mujoco.mjtWarning.mjWARN_BADQACC),
    int(mujoco.mjtWarning.mjWARN_BADQVEL),
    int(mujoco.mjtWarning.mjWARN_BADQPOS),
)
_XYZ = (0, 1, 2)
_RELAXED = compiled_step.FLAGS.index("relaxed")
_BOUNCY = compiled_step.FLAGS.index("bouncy")


class World(WorldLayout, WorldCommands, AutoDisable, OdeRowsNumpy, WorldReadings, Senses):
    """The SimSpark Nao world on MuJoCo.

    Args:
        robot_types: One entry per robot (types 0–4). Robot ``i`` is addressed by index ``i``.
        teams: ``"left"``/``"right"`` per robot (default: all left). Decides the colour, the mirror
            of team-frame coordinates, and hearing.
        physics: MuJoCo settings (see :mod:`robocup_gym.sim.physics`).
        dead_time_cycles: Cycles between a command and the physics step it first acts in, counted
            like SimSpark: with 1 (the default, as rcssserver3d) a command given to
            :meth:`step` ``k`` acts from step ``k + 1`` on; with 0 it acts in step ``k``.
        vision: ``See`` settings (noise, field of view, interval, ground-truth extensions).
        seed: Seed for the vision noise and calibration offsets (deterministic when given).
        compiled: Run the per-cycle work in C (:mod:`robocup_gym.sim.compiled`, bit-equal to
            the NumPy path and several times cheaper). ``None`` (default): the environment
            variable ``ROBOCUP_GYM_COMPILED``, else whenever it can be built here; ``True``:
            raise :class:`~robocup_gym.sim.compiled.CompiledStepUnavailableError` if it cannot;
            ``False``: the NumPy path. :attr:`stepper` says which one runs.
    """

    def __init__(
        self,
        robot_types: Sequence[int] = (0,),
        *,
        teams: Sequence[str | None] | None = None,
        physics: PhysicsConfig | None = None,
        dead_time_cycles: int = 1,
        vision: VisionConfig | None = None,
        seed: int | None = None,
        compiled: bool | None = None,
    ) -> None:
        if dead_time_cycles < 0:
            raise ValueError(f"dead_time_cycles must be >= 0, got {dead_time_cycles}")
        robot_types = list(robot_types)
        if teams is None:
            teams = ["left"] * len(robot_types)
        if len(teams) != len(robot_types):
            raise ValueError("teams must have one entry per robot")
        for side in ("left", "right"):
            if sum(t == side for t in teams) > 11:
                raise ValueError(f"at most 11 robots per team, got more on the {side} team")
        self.physics = physics or PhysicsConfig()
        self.dead_time_cycles = int(dead_time_cycles)
        self.vision_config = vision or VisionConfig()
        self._substeps = self.physics.substeps
        slots = [RobotSlot(f"r{i}_", int(t), teams[i]) for i, t in enumerate(robot_types)]
        release_free_memory()  # what earlier worlds freed, before this one allocates
        self.xml = scene_xml(slots, self.physics)
        self.model = mujoco.MjModel.from_xml_string(self.xml)
        apply_ode_softness(self.model, self.physics)
        self._data = mujoco.MjData(self.model)
        self._poses_stale = False
        """Body poses (``xpos``, ``xmat``, geom poses) lag ``qpos`` by the last step."""
        self._com_stale = False
        """Centre-of-mass quantities (``subtree_com``, ``cvel``) lag the last step."""
        m = self.model
        self._ball_body = m.body("ball").id
        self._ball_geom = m.geom("ball").id
        self._geom_robot: list[int] | None = None
        """Robot index of every geom (-1: not a robot's), built on first use."""
        self._ball_qpos = int(m.jnt_qposadr[m.joint("ball").id])
        self._ball_qvel = int(m.jnt_dofadr[m.joint("ball").id])
        # Ball drag (reference §5) as damping of its free joint: translational dofs are world-frame
        # velocities, so this is exactly F = -0.01 v; rotational damping is isotropic.
        m.dof_damping[self._ball_qvel : self._ball_qvel + 3] = phys.BALL_LINEAR_DRAG
        m.dof_damping[self._ball_qvel + 3 : self._ball_qvel + 6] = phys.BALL_ANGULAR_DRAG
        # ball-ground contact pair: ODE bounces only above 0.8 m/s approach (switched per cycle)
        self._ball_ground_pair = 0
        self._ball_ground_solref = {
            b: self.physics.ode_row(
                *phys.BALL_GROUND_ERP_CFM,
                1.0 / phys.BALL_MASS,
                phys.BALL_RESTITUTION if b else 0.0,
            )[0]
            for b in (False, True)
        }
        self._flags = np.zeros(len(compiled_step.FLAGS), dtype=np.int32)
        """Per-cycle switches shared with the compiled step (see ``compiled_step.FLAGS``)."""
        self.robots: list[RobotState] = []
        drag_bodies = []
        for i, slot in enumerate(slots):
            r = self._index_robot(i, slot)
            r.team = slot.team
            self.robots.append(r)
            drag_bodies.extend(r.robot_bodies.tolist())
        self._init_motor_arrays()
        self._inv_timestep = 1.0 / m.opt.timestep
        self._init_drag(drag_bodies)
        self._init_views()
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.cycle = 0
        self.time = 0.0
        self.game = GameState()
        self._qpos0 = self.data.qpos.copy()
        self._dof_frictionloss0 = self.model.dof_frictionloss.copy()
        self._warning_counts = [0] * len(_DIVERGENCE_WARNINGS)
        self._sleepers: list[RobotState] = []
        """Robots that are asleep (held in place), see :meth:`place_robot`."""
        self._static_geoms = frozenset(np.flatnonzero(m.geom_bodyid == 0).tolist())
        self.reset(seed=seed)
        self._check_motor_rows()
        self._check_contact_rows()
        self._compiled: compiled_step.CompiledStep | None = None
        self.compiled_unavailable: str | None = None
        """Why the compiled step is not used (``None`` when it is, or was not wanted)."""
        self._init_compiled(compiled_step.wanted() if compiled is None else compiled)
        self._physics_step = self._step_numpy if self._compiled is None else self._step_compiled
        """One cycle's physics, compiled or NumPy; returns whether the state diverged."""

    @property
    def _motors_relaxed(self) -> bool:
        """Some motor rows are removed (joints at a stop pulled away) and fudge torques set."""
        return bool(self._flags[_RELAXED])

    @_motors_relaxed.setter
    def _motors_relaxed(self, value: bool) -> None:
        self._flags[_RELAXED] = value

    @property
    def _ball_bouncy(self) -> bool:
        """The ball-ground contact pair has its bouncy parameters this cycle."""
        return bool(self._flags[_BOUNCY])

    @_ball_bouncy.setter
    def _ball_bouncy(self, value: bool) -> None:
        self._flags[_BOUNCY] = value

    @property
    def stepper(self) -> str:
        """Which implementation runs the per-cycle work: ``"compiled"`` or ``"numpy"``."""
        return "compiled" if self._compiled is not None else "numpy"

    # ------------------------------------------------------------------ construction helpers
    # ------------------------------------------------------------------ robot state transfer
    _AGENT_STATE = (
        "team",
        "team_name",
        "unum",
        "announce_team",
        "perception_counter",
        "calibration",
        "heard",
        "hear_capacity",
        "last_frp",
        "asleep",
        "sleep_qpos",
    )
    _ARRAY_STATE = ("targets", "q_ref", "motor_lost", "accel", "prev_vel")

    def export_robot_state(self, index: int) -> dict:
        """Everything of robot ``index`` a rebuilt world needs to go on with it: its pose and
        velocities (root and joints), motor targets, creep reference and which motors lost
        motion, accelerometer history, pending commands, team/uniform, hearing, FRP memory. With
        :meth:`import_robot_state` it moves a robot into a new world (the ``serve`` server
        rebuilds its world when robots join or leave)."""
        r = self.robot(index)
        d = self._data
        out = {name: copy.deepcopy(getattr(r, name)) for name in self._AGENT_STATE}
        out.update({name: getattr(r, name).copy() for name in self._ARRAY_STATE})
        out["pending"] = [(due - self.cycle, vel.copy()) for due, vel, _ in r.pending]
        out["robot_type"] = r.model.robot_type.index
        a, b = r.qpos_root, r.qvel_root
        out["root_qpos"] = d.qpos[a : a + 7].copy()
        out["root_qvel"] = d.qvel[b : b + 6].copy()
        out["joint_qpos"] = d.qpos[r.qpos_joints].copy()
        out["joint_qvel"] = d.qvel[r.qvel_joints].copy()
        return out

    def import_robot_state(self, index: int, state: Mapping) -> None:
        """Restore what :meth:`export_robot_state` returned into robot ``index`` (of the same
        type; also from a world of another size). Arrays are copied in place: a robot's arrays
        are views into the world's.

        Raises:
            ValueError: the state is of a robot of another type.
        """
        r = self.robot(index)
        kind = state.get("robot_type", r.model.robot_type.index)
        if kind != r.model.robot_type.index:
            raise ValueError(
                f"robot state of type {kind} cannot go into robot {index} of "
                f"type {r.model.robot_type.index}"
            )
        if "root_qpos" in state:
            d = self._data
            a, b = r.qpos_root, r.qvel_root
            d.qpos[a : a + 7] = state["root_qpos"]
            d.qvel[b : b + 6] = state["root_qvel"]
            d.qpos[r.qpos_joints] = state["joint_qpos"]
            d.qvel[r.qvel_joints] = state["joint_qvel"]
            self._poses_stale = self._com_stale = True
        for name in self._AGENT_STATE:
            if name in state:
                setattr(r, name, copy.deepcopy(state[name]))
        for name in self._ARRAY_STATE:
            if name in state:
                getattr(r, name)[:] = state[name]
        if "pending" in state:
            r.pending = []
            for wait, vel in state["pending"]:  # cycles still to wait, velocities
                vel = np.array(vel, float)
                r.pending.append((self.cycle + wait, vel, not np.isnan(vel).any()))
        self._update_sleepers()

    # ------------------------------------------------------------------ properties
    @property
    def data(self) -> mujoco.MjData:
        """The MuJoCo data, with every derived quantity (body poses, centres of mass, body
        velocities) up to date with the state.

        :meth:`step` leaves them one step behind (MuJoCo derives them at the start of a step,
        SimSpark senses after it) and they are brought up to date here, on first use, so that
        cycles nobody looks at cost no kinematics.
        """
        if self._com_stale:
            self._sync()
        return self._data

    def _sync(self) -> None:
        """Bring body poses, centres of mass and body velocities up to the current state."""
        d = self._posed()
        mujoco.mj_comPos(self.model, d)
        mujoco.mj_comVel(self.model, d)
        self._com_stale = False

    def _posed(self) -> mujoco.MjData:
        """The MuJoCo data with body and geom poses up to date (all perception needs)."""
        if self._poses_stale:
            mujoco.mj_kinematics(self.model, self._data)
            self._poses_stale = False
        return self._data

    @property
    def substeps(self) -> int:
        """MuJoCo steps per 20 ms cycle."""
        return self._substeps

    # ------------------------------------------------------------------ reset / placement
    def reset(self, seed: int | None = None) -> None:
        """Restore the initial state: robots lined up on their side lines (as after ``init``),
        joints at 0, ball at the centre spot, time 0, BeforeKickOff. Also recovers from a
        diverged simulation."""
        if seed is not None:
            self.seed = seed
            self.rng = np.random.default_rng(seed)
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:] = self._qpos0
        self._restore_run_time_parameters()
        self.cycle = 0
        self.time = 0.0
        self.game = GameState()
        self._warning_counts = [0] * len(_DIVERGENCE_WARNINGS)
        for r in self.robots:
            r.targets[:] = 0.0
            r.pending.clear()
            r.last_frp = {}
            r.asleep = False
        self._reset_senses()
        counts = {"left": 0, "right": 0, None: 0}
        for r in self.robots:
            n = counts[r.team]
            counts[r.team] += 1
            col, row = divmod(n, 17)
            x = -14.2 + 0.8 * col
            y = 9.2 - 1.2 * row
            if r.team == "right":
                self.place_robot(r.index, x=-x, y=y, heading_deg=180.0, forward=False)
            else:
                self.place_robot(r.index, x=x, y=y, heading_deg=0.0, forward=False)
        self.place_ball((0.0, 0.0), forward=False)
        self.forward()

    def _restore_run_time_parameters(self) -> None:
        """Undo the per-cycle parameter switches (motor relaxation at stops, ball bounce mode) and
        the solver's warm start, so that a reset or placement never depends on the past."""
        self.model.dof_frictionloss[:] = self._dof_frictionloss0
        self._motors_relaxed = False
        self.model.pair_solref[self._ball_ground_pair] = self._ball_ground_solref[False]
        self._ball_bouncy = False
        self.data.qacc_warmstart[:] = 0.0

    def place_robot(
        self,
        index: int,
        x: float,
        y: float,
        *,
        heading_deg: float = 0.0,
        z: float | None = None,
        joint_angles_deg: Mapping[str, float] | np.ndarray | None = None,
        quat: Sequence[float] | None = None,
        forward: bool = True,
        asleep: bool = False,
    ) -> None:
        """Teleport a robot instantly: no warm-up cycles, no controller loop.

        Args:
            index: Robot index.
            x, y: Torso centre in world coordinates, m.
            heading_deg: Direction the robot faces (0 = world +x, CCW positive); see ``quat``.
            z: Torso centre height, m. ``None`` puts the robot's lowest point on the ground
                (resting 1 mm deep, as ODE's surface layer does).
            joint_angles_deg: Joint angles in degrees, by effector/perceptor name (others 0) or as
                an array in canonical order. ``None`` keeps the current angles.
            quat: Full torso orientation ``(w, x, y, z)`` instead of ``heading_deg``.
            forward: Recompute the derived quantities (contacts, sensors) now. Pass ``False``
                when placing several robots in a row and call :meth:`forward` once at the
                end (robots still overlapping half-way would create thousands of contacts).
            asleep: Leave the robot asleep, as ODE's auto-disable leaves a resting robot that a
                trainer ``move`` teleports (reference §7.1, §8.3: the real robot then
                hangs where it was put, e.g. 2 mm above its resting height, until the first
                non-zero joint velocity): it is held exactly in the placed pose, feeling no
                gravity, until a non-zero motor target is realised for it or one of its parts
                touches a moving body (ball, another robot); then it wakes in that very step.

        All velocities and joint targets are zeroed.
        """
        r = self.robot(index)
        q = placement_quat(x, y, z, heading_deg, quat)
        d = self.data
        if joint_angles_deg is not None:
            angles = joint_angles_array(r.model, joint_angles_deg)
            d.qpos[r.qpos_joints] = np.radians(angles)
        a = r.qpos_root
        d.qpos[a : a + 3] = (x, y, 1.0 if z is None else z)
        d.qpos[a + 3 : a + 7] = q
        d.qvel[r.qvel_root : r.qvel_root + 6] = 0.0
        d.qvel[r.qvel_joints] = 0.0
        r.targets[:] = 0.0
        r.pending.clear()
        r.last_frp = {}
        self.model.dof_frictionloss[r.qvel_joints] = phys.MOTOR_MAX_TORQUE
        d.qacc_warmstart[:] = 0.0
        r.q_ref[:] = d.qpos[r.qpos_joints]
        r.motor_lost[:] = False
        r.prev_vel[:] = 0.0
        r.accel[:] = (0.0, 0.0, phys.GRAVITY)
        if z is None:
            mujoco.mj_kinematics(self.model, d)
            lowest = self._lowest_point(r)
            d.qpos[a + 2] += -phys.SURFACE_LAYER - lowest
        r.asleep = bool(asleep)
        if r.asleep:
            r.sleep_qpos = np.concatenate((d.qpos[a : a + 7], d.qpos[r.qpos_joints]))
        self._update_sleepers()
        if forward:
            self.forward()

    def move_robot(
        self,
        index: int,
        pos: Sequence[float] | None = None,
        *,
        heading_deg: float | None = None,
        rot_deg: Sequence[float] | None = None,
    ) -> None:
        """Move robot ``index`` rigidly as rcssserver3d moves an agent (the trainer's ``move``,
        ``pos`` and ``rot``, ``beam``, the referee; see
        :meth:`robocup_gym.sim.engines.ode.world.OdeWorld.move_robot`): the torso to its new
        pose (:func:`robocup_gym.sim.pose.rigid_move`), joint angles, motor targets, pending
        commands and sensor memory kept, every velocity zero. This world has no auto-disable:
        a robot that is still (no motor target, every velocity under ODE's auto-disable
        thresholds, 0.01 m/s and 0.01 rad/s) is taken to be resting and left asleep, as ODE's
        auto-disable leaves a resting robot; one that moves falls from where it is put."""
        for name, value in (("pos", pos), ("rot_deg", rot_deg)):
            if value is not None and not np.all(np.isfinite(np.asarray(value, float))):
                raise ValueError(f"robot move {name} must be finite, got {value!r}")
        if heading_deg is not None and not math.isfinite(heading_deg):
            raise ValueError(f"robot move heading_deg must be finite, got {heading_deg}")
        r = self.robot(index)
        d = self.data
        still = not np.any(r.targets) and (
            np.abs(d.qvel[r.qvel_root : r.qvel_root + 6]).max() < AUTO_DISABLE_SPEED
            and np.abs(d.qvel[r.qvel_joints]).max(initial=0.0) < AUTO_DISABLE_SPEED
        )
        positions, rotations = self.body_frames(index)
        new_pos, new_rot = rigid_move(
            positions[:1], rotations[:1], pos, heading_deg=heading_deg, rot_deg=rot_deg
        )
        a = r.qpos_root
        d.qpos[a : a + 3] = new_pos[0]
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, new_rot[0].ravel())
        d.qpos[a + 3 : a + 7] = quat
        d.qvel[r.qvel_root : r.qvel_root + 6] = 0.0
        d.qvel[r.qvel_joints] = 0.0
        d.qacc_warmstart[:] = 0.0
        r.asleep = r.asleep or still
        if r.asleep:
            r.sleep_qpos = np.concatenate((d.qpos[a : a + 7], d.qpos[r.qpos_joints]))
        self._update_sleepers()
        self.forward()

    def _lowest_point(self, r: RobotState) -> float:
        """Height of robot ``r``'s lowest collision point (m), from the current geom poses."""
        box, half, sphere, radius, capsule, cap_radius, cap_half = r.shapes
        pos_z, mat = self.data.geom_xpos[:, 2], self.data.geom_xmat
        # a box reaches |R[2, :]| · half below its centre; a capsule |R[2, 2]| · half-length + r
        low = min(
            (pos_z[box] - (np.abs(mat[box, 6:9]) * half).sum(axis=1)).min(initial=np.inf),
            (pos_z[sphere] - radius).min(initial=np.inf),
            (pos_z[capsule] - np.abs(mat[capsule, 8]) * cap_half - cap_radius).min(initial=np.inf),
        )
        return float(low)

    def place_ball(
        self,
        pos: Sequence[float],
        vel: Sequence[float] = (0.0, 0.0, 0.0),
        angular_vel: Sequence[float] = (0.0, 0.0, 0.0),
        *,
        forward: bool = True,
    ) -> None:
        """Put the ball at ``pos`` (x, y[, z]; z defaults to resting on the ground) with linear
        velocity ``vel`` (m/s) and angular velocity ``angular_vel`` (rad/s, world frame).
        ``forward``: as in :meth:`place_robot`."""
        p, v, w = ball_placement(pos, vel, angular_vel)
        z = p[2] if p.shape == (3,) else phys.BALL_RADIUS - phys.SURFACE_LAYER
        a = self._ball_qpos
        self.data.qpos[a : a + 3] = (p[0], p[1], z)
        self.data.qpos[a + 3 : a + 7] = (1.0, 0.0, 0.0, 0.0)
        b = self._ball_qvel
        self.model.pair_solref[self._ball_ground_pair] = self._ball_ground_solref[False]
        self._ball_bouncy = False
        self.data.qacc_warmstart[:] = 0.0
        self.data.qvel[b : b + 3] = v
        # free-joint angular velocity is in the body frame; the ball's frame is the world's here
        self.data.qvel[b + 3 : b + 6] = w
        if forward:
            self.forward()

    def forward(self) -> None:
        """Bring every derived quantity (body poses, contacts and their forces, sensors) up to
        the current state without advancing it, with the contacts solved as a step solves them
        (ODE's surface layer, :meth:`_surface_layer`): a robot just placed 1 mm deep reads its
        weight on its feet (22.5 N each standing), as in every later cycle, where plain
        ``mj_forward`` would push it out of the layer (24.8 N). Motors at rest need no shift."""
        m, d = self.model, self._data
        mujoco.mj_step1(m, d)
        if d.ncon:
            self._surface_layer()
        mujoco.mj_fwdActuation(m, d)
        mujoco.mj_fwdAcceleration(m, d)
        mujoco.mj_fwdConstraint(m, d)
        mujoco.mj_sensorAcc(m, d)
        self._poses_stale = self._com_stale = False

    # ------------------------------------------------------------------ commands
    # ------------------------------------------------------------------ stepping
    def step(
        self,
        commands: Mapping[int, AgentCommand | Mapping[str, float] | np.ndarray]
        | AgentCommand
        | None = None,
    ) -> None:
        """Advance the world by one 20 ms cycle.

        Args:
            commands: ``{robot index: command}`` (an :class:`AgentCommand`, a ``{effector: rad/s}``
                mapping or a canonical-order array), or one :class:`AgentCommand` for robot 0.
                Joints without a command keep their previous target.

        Raises:
            SimulationDivergedError: the physics blew up (state is left as is; call reset()).
        """
        if commands is not None:
            if isinstance(commands, AgentCommand):
                self.command(0, commands)
            else:
                for i, c in commands.items():
                    self.command(i, c)
        diverged = self._physics_step()
        # MuJoCo computes positions at the start of a step; SimSpark senses after it. Body poses
        # and velocities are brought up to the new state when first used (see ``data``).
        self._poses_stale = self._com_stale = True
        self.cycle += 1
        self._advance_clocks(CYCLE_S)
        if diverged:
            self._raise_diverged()

    def _step_compiled(self) -> bool:
        """One cycle's physics with the per-cycle work in C (``cstep.c`` does what
        :meth:`_step_numpy` does, bit for bit). Returns whether the state diverged."""
        due = self.cycle
        for r in self.robots:
            pending = r.pending
            if pending and pending[0][0] <= due:
                r.cmd[:] = pending.pop(0)[1]
                while pending and pending[0][0] <= due:  # later commands win where they command
                    vel = pending.pop(0)[1]
                    np.copyto(r.cmd, vel, where=vel == vel)
                r.cmd[:] = self._frozen_to_zero(r.index, r.cmd)
        fast = self._compiled
        fast.pre()
        if self._sleepers:
            self._wake_commanded()
        m, d = self.model, self._data
        for sub in range(self._substeps):
            mujoco.mj_step1(m, d)
            fast.mid(sub == 0)
            if self._sleepers:
                self._wake_touched()
            mujoco.mj_step2(m, d)
            if self._sleepers:
                self._hold_sleepers()
        return fast.post()

    def _raise_diverged(self) -> None:
        """Raise :class:`SimulationDivergedError`: the last step blew up (a NaN/inf or absurd
        velocity, |qvel| > 1e5; MuJoCo's automatic reset is disabled so that the blow-up stays
        visible). The MuJoCo warnings of the step name the cause."""
        d = self._data
        counts = [d.warning[i].number for i in _DIVERGENCE_WARNINGS]
        names = [
            mujoco.mjtWarning(i).name
            for i, n, old in zip(_DIVERGENCE_WARNINGS, counts, self._warning_counts, strict=True)
            if n > old
        ]
        self._warning_counts = counts
        raise SimulationDivergedError(
            f"simulation diverged at cycle {self.cycle} (t = {self.time:.2f} s)"
            + (f"; MuJoCo warnings: {', '.join(names)}" if names else "; NaN/inf state")
            + ". Call World.reset() to continue."
        )

    def close(self) -> None:
        """Nothing to free by hand (MuJoCo's model and data go with the object); kept for the
        ODE world's interface, whose ``close`` frees the engine's bodies."""

    # ------------------------------------------------------------------ misc
    def state(self) -> np.ndarray:
        """Full physics state (qpos, qvel, act, time) for save/restore."""
        spec = mujoco.mjtState.mjSTATE_PHYSICS
        out = np.empty(mujoco.mj_stateSize(self.model, spec))
        mujoco.mj_getState(self.model, self.data, out, spec)
        return out

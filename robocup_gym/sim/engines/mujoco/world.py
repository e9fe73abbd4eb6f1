"""The embedded SimSpark world on MuJoCo: robots, ball, field, 20 ms cycles, perception.

:class:`World` is the in-process simulator every environment drives by default. One
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
from dataclasses import dataclass, field

import mujoco
import numpy as np

from robocup_gym.robot.nao import NaoModel, nao_model
from robocup_gym.sim import SimulationDivergedError
from robocup_gym.sim import compiled as compiled_step
from robocup_gym.sim import physics as phys
from robocup_gym.sim.engines.mujoco.motors import (
    _SATURATED,
    CREEP_WINDOW_RAD,
    DIVERGED_QVEL_SQ,
    OdeRowsNumpy,
    _any,
    _clip,
)
from robocup_gym.sim.engines.mujoco.readings import WorldReadings
from robocup_gym.sim.engines.mujoco.scene import (
    FRP_GEOMS,
    RobotSlot,
    apply_ode_softness,
    frp_sensor_name,
    scene_xml,
)
from robocup_gym.sim.memory import release_free_memory
from robocup_gym.sim.physics import CYCLE_S, PhysicsConfig
from robocup_gym.sim.pose import joint_angles_array, joint_index, placement_quat, rigid_move
from robocup_gym.sim.senses import AgentState, Senses
from robocup_gym.sim.vision import PLAYER_PARTS, VisionConfig
from robocup_gym.types import (
    AgentCommand,
    ForceResistance,
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


def _contiguous(ids: np.ndarray) -> slice | None:
    """``ids`` as a slice when they are consecutive ascending indices (views instead of
    gathers on the hot path), else ``None`` (also when empty)."""
    n = len(ids)
    if n and np.array_equal(ids, np.arange(ids[0], ids[0] + n)):
        return slice(int(ids[0]), int(ids[0]) + n)
    return None


_AUTO_DISABLE_SPEED = 0.01
"""ODE's default auto-disable thresholds (linear m/s, angular rad/s) that SimSpark keeps: a body
slower than both is resting (reference §7.1)."""


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


class World(OdeRowsNumpy, WorldReadings, Senses):
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
    def _init_compiled(self, mode: bool | None) -> None:
        """Bind the compiled step (:mod:`robocup_gym.sim.compiled`) to this world's arrays when
        ``mode`` is ``True`` (must work) or ``None`` (if it can be built)."""
        if mode is False:
            return
        try:
            compiled_step.load()
        except compiled_step.CompiledStepUnavailableError as exc:
            if mode:
                raise
            self.compiled_unavailable = str(exc)
            return
        m = self.model
        n = len(self._qvel_j)
        i32 = lambda a: np.ascontiguousarray(a, dtype=np.int32)  # noqa: E731
        sort = self._motor_sort if self._motor_sort is not None else np.arange(n)
        drag_bodies = m.sensor_objid[0 : 2 * len(self._drag_vel) : 2]
        keep = {
            "qpos_j": i32(self._qpos_j),
            "qvel_j": i32(self._qvel_j),
            "lo": np.ascontiguousarray(self._lo, dtype=float),
            "hi": np.ascontiguousarray(self._hi, dtype=float),
            "vmax": np.concatenate([r.max_speeds for r in self.robots]).astype(float)
            if self.robots
            else np.zeros(0),
            "targets": self._targets,
            "q_ref": self._q_ref,
            "motor_lost": self._motor_lost,
            "cmd": self._cmd,
            "at_lo": np.zeros(n, dtype=bool),
            "at_hi": np.zeros(n, dtype=bool),
            "limited": np.zeros(n, dtype=bool),
            "away": np.zeros(n, dtype=bool),
            "q": np.zeros(n),
            "mt": np.zeros(n),
            "sort": i32(sort),
            "dofs": i32(self._motor_dofs_sorted),
            "motor_b": np.ascontiguousarray(self._motor_b, dtype=float),
            "shift": np.zeros(n),
            "rows": np.zeros(n, dtype=bool),
            "qvel_root": i32([r.qvel_root for r in self.robots]),
            "torso_body": i32([r.torso_body for r in self.robots]),
            "prev_vel": self._prev_vel,
            "accel": self._accel,
            "drag_body": i32(drag_bodies),
            "flags": self._flags,
        }
        st = compiled_step.WorldStruct()
        for name, array in keep.items():
            setattr(st, name, compiled_step.address(array))
        st.n, st.nrobots, st.ndrag = n, len(self.robots), len(drag_bodies)
        st.ball_qpos, st.ball_qvel = self._ball_qpos, self._ball_qvel
        st.ball_pair = self._ball_ground_pair
        st.ball_solref[:] = [*self._ball_ground_solref[False], *self._ball_ground_solref[True]]
        st.cycle, st.inv_cycle, st.inv_timestep = CYCLE_S, 1.0 / CYCLE_S, self._inv_timestep
        st.creep_window = CREEP_WINDOW_RAD
        st.stop_erp, st.stop_bounce = phys.JOINT_STOP_ERP_CFM[0], phys.JOINT_STOP_BOUNCE
        st.fudge_torque = phys.MOTOR_FUDGE_FACTOR * phys.MOTOR_MAX_TORQUE
        st.max_torque, st.saturated = phys.MOTOR_MAX_TORQUE, _SATURATED
        st.surface_layer, st.gravity = phys.SURFACE_LAYER, phys.GRAVITY
        st.drag_lin, st.drag_ang = phys.BODY_LINEAR_DRAG, phys.BODY_ANGULAR_DRAG
        st.ball_radius, st.ground_z = phys.BALL_RADIUS, phys.GROUND_PLANE_Z
        st.bounce_min_speed, st.diverged_qvel_sq = phys.BALL_BOUNCE_MIN_SPEED, DIVERGED_QVEL_SQ
        self._compiled = compiled_step.CompiledStep(st, m, self._data, list(keep.values()))

    def _init_drag(self, drag_bodies: list[int]) -> None:
        """Map the scene's drag sensors
        (:func:`robocup_gym.sim.engines.mujoco.scene._drag_sensors`: per robot
        body its centre-of-mass linear and angular velocity) onto ``xfrc_applied``."""
        m, d = self.model, self._data
        n = 2 * len(drag_bodies)  # the drag sensors come first; the FRP contact sensors follow
        kinds = m.sensor_type[:n]
        lin, ang = mujoco.mjtSensor.mjSENS_FRAMELINVEL, mujoco.mjtSensor.mjSENS_FRAMEANGVEL
        bodies = m.sensor_objid[0:n:2]
        if (
            m.nsensor < n
            or not np.array_equal(bodies, drag_bodies)
            or not np.array_equal(m.sensor_objid[1:n:2], bodies)
            or not (np.all(kinds[0::2] == lin) and np.all(kinds[1::2] == ang))
            or not np.array_equal(m.sensor_adr[:n], 3 * np.arange(n))
        ):
            raise RuntimeError("the scene's drag sensors do not match the robot bodies")
        self._drag_vel = d.sensordata[: 3 * n].reshape(-1, 6)
        """Per robot body: centre-of-mass velocity (m/s) and angular velocity (rad/s), world."""
        rows = _contiguous(bodies)
        self._drag_index = None if rows is not None or len(bodies) == 0 else bodies
        self._drag_force = d.xfrc_applied[rows] if rows is not None else None
        """The robot bodies' rows of ``xfrc_applied`` (a view) when they are contiguous (always,
        in our scenes); otherwise ``_drag_index`` lists them."""

    def _init_views(self) -> None:
        """Views into MjData's fixed buffers (they never move) for the per-cycle work."""
        d = self._data
        self._qpos = d.qpos
        self._qvel = d.qvel
        self._sensordata = d.sensordata
        self._accel_io = [
            (
                r,
                d.qvel[r.qvel_root : r.qvel_root + 3],
                d.xmat[r.torso_body].reshape(3, 3),
                np.zeros(3),
            )
            for r in self.robots
        ]
        """Per robot: state, torso velocity (world), torso rotation, scratch (accelerometer)."""
        ms = self._motor_slice = _contiguous(self._motor_dofs_sorted)
        """The motor dofs as one slice when they are contiguous (one robot), else ``None``."""
        if ms is not None:
            self._motor_views = (
                self.model.dof_frictionloss[ms],
                d.qacc_warmstart[ms],
                d.qvel[ms],
            )
            """The motor dofs' friction loss (the motor rows' force bound), warm start and
            velocity: views, so that the per-cycle work needs no MjModel/MjData lookups."""

    def _init_motor_arrays(self) -> None:
        """World-level arrays over every robot's joints (robot after robot, canonical order);
        each robot's ``targets`` and ``q_ref`` are views into them (created here), so one cycle's
        motor work is a few vector operations whatever the number of robots.

        Motor rows are the dof friction-loss rows, which MuJoCo puts first in the constraint
        list, in dof order (checked at construction, :meth:`_check_motor_rows`); ``_motor_sort``
        maps canonical order to dof order.
        """
        m = self.model
        robots = self.robots
        cat = (lambda xs: np.concatenate(xs)) if robots else (lambda xs: np.zeros(0))
        self._qpos_j = cat([r.qpos_joints for r in robots]).astype(int)
        self._qvel_j = cat([r.qvel_joints for r in robots]).astype(int)
        self._lo = cat([r.range_rad[0] for r in robots])
        self._hi = cat([r.range_rad[1] for r in robots])
        n = len(self._qvel_j)
        self._targets = np.zeros(n)
        self._q_ref = np.zeros(n)
        self._motor_lost = np.zeros(n, dtype=bool)
        self._cmd = np.full(n, np.nan)
        """Due commands for the compiled step (NaN: none), see :meth:`_step_compiled`."""
        self._accel = np.zeros((len(robots), 3))
        self._prev_vel = np.zeros((len(robots), 3))
        off = 0
        for i, r in enumerate(robots):
            k = len(r.qvel_joints)
            r.targets = self._targets[off : off + k]
            r.q_ref = self._q_ref[off : off + k]
            r.motor_lost = self._motor_lost[off : off + k]
            r.cmd = self._cmd[off : off + k]
            self._accel[i] = r.accel
            r.accel = self._accel[i]
            r.prev_vel = self._prev_vel[i]
            r.joint_slice = slice(off, off + k)
            off += k
        sort = np.argsort(self._qvel_j, kind="stable")
        self._motor_sort = None if np.array_equal(sort, np.arange(n)) else sort
        dofs = self._qvel_j if self._motor_sort is None else self._qvel_j[sort]
        self._motor_dofs_sorted = dofs
        tc = np.maximum(m.dof_solref[dofs, 0], 2 * m.opt.timestep)
        self._motor_b = 2.0 / (m.dof_solimp[dofs, 1] * tc)
        """Damping B of each motor row, dof order (MuJoCo's aref = −B·v for friction rows)."""

    def _check_motor_rows(self) -> None:
        """Check, once per world, what the joint motors rely on in MuJoCo's constraint rows, so
        that a MuJoCo version that lays them out differently fails here with a clear error
        instead of silently driving the wrong rows (tested with MuJoCo 3.4 and 4.0, see
        docs/reference/engines.md §2.7):

        * the dof friction-loss rows (the motors) are the first ``nrows`` constraint rows, one per
          motor dof with non-zero ``dof_frictionloss``, in dof order, and no other row is one;
        * their reference acceleration is ``efc_aref = −B·v`` with ``B`` from ``_motor_b``
          (MuJoCo's damping of a row of impedance ``solimp[1]`` and time constant
          ``max(solref[0], 2·timestep)``), which :meth:`step` shifts by ``B·v_cmd``.

        Probes the freshly reset state with non-zero joint velocities and restores it.

        Raises:
            RuntimeError: naming the MuJoCo version and the assumption that does not hold.
        """
        dofs = self._motor_dofs_sorted
        n = len(dofs)
        if n == 0:
            return
        m, d = self.model, self.data
        probe = np.where(np.arange(n) % 2 == 0, 1.0, -1.0) * (1.0 + np.arange(n) % 5)
        d.qvel[dofs] = probe
        mujoco.mj_forward(m, d)
        friction = mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF
        problem = None
        rows = (d.efc_type == friction).nonzero()[0]
        if len(rows) != n or not np.array_equal(rows, np.arange(n)):
            problem = (
                f"the {n} joint motor (dof friction-loss) rows are not the first constraint rows "
                f"(friction-loss rows at {rows[:5].tolist()}…, {d.nefc} rows in all)"
            )
        elif not np.array_equal(d.efc_id[:n], dofs):
            problem = "the joint motor (dof friction-loss) rows are not in dof order"
        elif not np.allclose(d.efc_aref[:n], -self._motor_b * probe, rtol=1e-9, atol=0.0):
            problem = (
                "the motor rows' reference acceleration is not −B·v with MuJoCo's documented B "
                f"(largest error {np.abs(d.efc_aref[:n] + self._motor_b * probe).max():.3g})"
            )
        d.qvel[dofs] = 0.0
        d.qacc_warmstart[:] = 0.0
        mujoco.mj_forward(m, d)
        if problem is not None:
            raise RuntimeError(
                f"MuJoCo {mujoco.__version__}: {problem}. The World's joint motors "
                "(robocup_gym/sim/engines/mujoco/world.py, robocup_gym/robot/mjcf.py) rely on it; "
                "use a tested MuJoCo version (docs/reference/engines.md §2.7)."
            )

    def _check_contact_rows(self) -> None:
        """Check the row layout that :meth:`_surface_layer` and :meth:`_bounce_stops` rely on
        to find their rows without a per-row lookup: every contact has three constraint rows
        (condim 3, elliptic cones), and the only limit rows are the joints' stops (no limited
        tendon).

        Raises:
            RuntimeError: naming the geom or pair that would make contacts of another shape.
        """
        m = self.model
        if m.ntendon and np.any(m.tendon_limited):
            raise RuntimeError("the world's joint stops assume no limited tendons")
        if m.opt.cone != mujoco.mjtCone.mjCONE_ELLIPTIC:
            raise RuntimeError("the world's contact model needs elliptic friction cones")
        colliding = (m.geom_contype != 0) | (m.geom_conaffinity != 0)
        odd = np.flatnonzero(colliding & (m.geom_condim != 3))
        if len(odd) or np.any(m.pair_dim != 3):
            name = m.geom(int(odd[0])).name if len(odd) else "a contact pair"
            raise RuntimeError(
                f"{name} has condim ≠ 3: every contact must have three rows (see "
                "World._surface_layer)"
            )

    def _index_robot(self, i: int, slot: RobotSlot) -> RobotState:
        m = self.model
        model = nao_model(slot.type_index)
        p = slot.prefix
        root = m.joint(f"{p}root").id
        r = RobotState(index=i, prefix=p, model=model)
        r.qpos_root = int(m.jnt_qposadr[root])
        r.qvel_root = int(m.jnt_dofadr[root])
        r.qpos_joints = np.array([m.jnt_qposadr[m.joint(p + e).id] for e in model.effector_names])
        r.qvel_joints = np.array([m.jnt_dofadr[m.joint(p + e).id] for e in model.effector_names])
        r.torso_body = m.body(f"{p}torso").id
        r.head_body = m.body(f"{p}head").id
        r.part_bodies = np.array([m.body(p + part).id for part in PLAYER_PARTS])
        r.robot_bodies = np.array([m.body(p + b.name).id for b in model.bodies])
        r.robot_geoms = frozenset(m.geom(p + b.name).id for b in model.bodies if b.collides)
        feet = ["rf", "lf"] + (["rf1", "lf1"] if model.robot_type.has_toes else [])
        r.frp_sensors = [
            (f, int(m.sensor_adr[m.sensor(frp_sensor_name(p, f)).id]), m.body(p + FRP_GEOMS[f]).id)
            for f in feet
        ]
        r.range_rad = tuple(np.radians(model.ranges_deg).T.copy())
        r.max_speeds = model.max_speeds
        r.min_speeds = -model.max_speeds
        geoms = np.array(sorted(r.robot_geoms), dtype=int)
        kind = m.geom_type[geoms]
        box = geoms[kind == mujoco.mjtGeom.mjGEOM_BOX]
        sphere = geoms[kind == mujoco.mjtGeom.mjGEOM_SPHERE]
        capsule = geoms[kind == mujoco.mjtGeom.mjGEOM_CAPSULE]  # along local z
        if len(box) + len(sphere) + len(capsule) != len(geoms):
            raise ValueError("robot geoms must be boxes, spheres or capsules")
        r.shapes = (
            box,
            m.geom_size[box].copy(),
            sphere,
            m.geom_size[sphere, 0].copy(),
            capsule,
            m.geom_size[capsule, 0].copy(),
            m.geom_size[capsule, 1].copy(),
        )
        return r

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
            np.abs(d.qvel[r.qvel_root : r.qvel_root + 6]).max() < _AUTO_DISABLE_SPEED
            and np.abs(d.qvel[r.qvel_joints]).max(initial=0.0) < _AUTO_DISABLE_SPEED
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

    def _update_sleepers(self) -> None:
        self._sleepers = [r for r in self.robots if r.asleep]

    def _wake_touched(self) -> None:
        """Wake every sleeping robot one of whose parts touches a moving body (the ball or
        another robot) in this step's contacts: in ODE the contact joint joins it to that body's
        island, which is enabled as a whole."""
        d = self._data  # inside step(): the contacts are this step's
        if d.ncon == 0:
            return
        pairs = d.contact.geom[: d.ncon].tolist()
        static = self._static_geoms
        woke = False
        for r in self._sleepers:
            own = r.robot_geoms
            for g1, g2 in pairs:
                if (g1 in own and g2 not in own and g2 not in static) or (
                    g2 in own and g1 not in own and g1 not in static
                ):
                    r.asleep = False
                    woke = True
                    break
        if woke:
            self._update_sleepers()

    def _hold_sleepers(self) -> None:
        """Put every sleeping robot back into its held pose with zero velocity (a disabled ODE
        body is not integrated)."""
        d = self._data  # inside step(): only the state is written
        for r in self._sleepers:
            a = r.qpos_root
            d.qpos[a : a + 7] = r.sleep_qpos[:7]
            d.qpos[r.qpos_joints] = r.sleep_qpos[7:]
            d.qvel[r.qvel_root : r.qvel_root + 6] = 0.0
            d.qvel[r.qvel_joints] = 0.0

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
        p = np.asarray(pos, float)
        if p.shape not in ((2,), (3,)) or not np.all(np.isfinite(p)):
            raise ValueError(f"ball position must be 2 or 3 finite numbers, got {pos!r}")
        v = np.asarray(vel, float)
        w = np.asarray(angular_vel, float)
        if (
            v.shape != (3,)
            or w.shape != (3,)
            or not (np.isfinite(v).all() and np.isfinite(w).all())
        ):
            raise ValueError("ball velocities must be 3 finite numbers each")
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
    def command_array(self, index: int, velocities: Mapping[str, float] | np.ndarray) -> np.ndarray:
        """Validate a joint-velocity command (rad/s) and return it as a canonical-order array in
        which NaN marks "no command for this joint" (targets are sticky).

        Raises:
            KeyError: unknown effector name (lists the valid ones).
            ValueError: NaN/inf value (names the joint) or wrong array shape.
        """
        r = self.robot(index)
        n = len(r.max_speeds)
        if type(velocities) is np.ndarray and velocities.shape == (n,):  # the hot path
            out = velocities.astype(float)  # a copy: the caller may reuse its array
            if not math.isfinite(out.dot(out)):  # one check for any NaN/inf (or a huge value)
                self._raise_not_finite(r, out)
            return out
        if isinstance(velocities, Mapping):
            out = np.full(n, np.nan)
            for name, v in velocities.items():
                i = joint_index(r.model, name)
                v = float(v)
                if not math.isfinite(v):
                    raise ValueError(f"velocity command for joint {r.effector_names[i]} is {v}")
                out[i] = v
            return out
        out = np.array(velocities, dtype=float)  # a copy: the caller may reuse its array
        if out.shape != (n,):
            raise ValueError(
                f"velocity array must have shape ({n},) in effector order "
                f"{', '.join(r.effector_names)}; got {out.shape}"
            )
        if not math.isfinite(out.dot(out)):
            self._raise_not_finite(r, out)
        return out

    @staticmethod
    def _raise_not_finite(r: RobotState, velocities: np.ndarray) -> None:
        """Raise ``ValueError`` naming the first joint whose command is NaN/inf (if any: a
        finite command whose squares overflow is left alone)."""
        bad = ~np.isfinite(velocities)
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(f"velocity command for joint {r.effector_names[i]} is {velocities[i]}")

    def command(self, index: int, command: AgentCommand | Mapping[str, float] | np.ndarray) -> None:
        """Queue one cycle's command for robot ``index`` (it acts after the dead time)."""
        r = self.robot(index)
        if isinstance(command, AgentCommand):
            velocities = command.joint_velocities
            vel = self.command_array(index, velocities)
            if command.beam is not None:
                self.beam(index, *command.beam)
            if command.say is not None:
                self.say(index, command.say)
        else:
            velocities = command
            vel = self.command_array(index, velocities)
        # only a mapping can leave joints without a command (NaN): an array names them all
        full = type(velocities) is np.ndarray or not np.isnan(vel).any()
        r.pending.append((self.cycle + self.dead_time_cycles, vel, full))

    def _realise_commands(self, r: RobotState, inside: np.ndarray | None) -> None:
        """Write robot ``r``'s due commands into its motors (SimSpark's hinge effector, spec
        §8.3): a command is taken only by joints strictly inside their limits (``inside``, this
        robot's slice, ``None`` when all are); the others keep their previous target. Commands
        are clipped to each joint's maximum speed."""
        while r.pending and r.pending[0][0] <= self.cycle:
            _, vel, full = r.pending.pop(0)
            vel = self._frozen_to_zero(r.index, vel)
            if inside is None and full:
                _clip(vel, r.min_speeds, r.max_speeds, out=r.targets)  # every joint takes it
                continue
            clipped = _clip(vel, r.min_speeds, r.max_speeds)
            if full:
                take = inside
            else:
                # NaN (no command for that joint) compares False: the old target stays
                take = vel == vel
                if inside is not None:
                    take &= inside
            np.copyto(r.targets, clipped, where=take)

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

    def _wake_commanded(self) -> None:
        """A non-zero motor target wakes a sleeping robot for this very step (reference §8.3)."""
        for r in self._sleepers:
            if _any(r.targets != 0.0):
                r.asleep = False
        self._update_sleepers()

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

    def set_torso_force(self, index: int, force: Sequence[float]) -> None:
        """Push robot ``index``'s torso with ``force`` (N, world frame, at the torso's origin,
        through its free joint) in every step until it is changed or :meth:`reset`;
        ``(0, 0, 0)`` ends it. SimSpark has no such force: it is a training aid
        (``TrainConfig.assist_force``), never part of an evaluation.

        Raises:
            ValueError: ``force`` is not three finite numbers.
        """
        f = phys.finite_force(force)
        a = self.robot(index).qvel_root
        self._data.qfrc_applied[a : a + 3] = f

    def set_motor_targets(self, index: int, targets: np.ndarray) -> None:
        """Set robot ``index``'s motor targets (rad/s, canonical order) as they are, without the
        hinge effector's rules: to restore what :meth:`motor_targets` returned after a placement
        (which zeroes them)."""
        self.robot(index).targets[:] = targets

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

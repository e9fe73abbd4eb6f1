"""How the MuJoCo world finds its way in the compiled model: each robot's ids (joints, bodies,
geoms, force sensors), the arrays of the motor rows and the compiled step, the bodies that feel
drag, and the checks that the model's rows are the ones SimSpark's ODE step has
(docs/reference/engines.md §2).

:class:`WorldLayout` is a part of :class:`~robocup_gym.sim.engines.mujoco.world.World`."""

from __future__ import annotations

import mujoco
import numpy as np

from robocup_gym.robot.nao import nao_model
from robocup_gym.sim import compiled as compiled_step
from robocup_gym.sim import physics as phys
from robocup_gym.sim.engines.mujoco.motors import _SATURATED, CREEP_WINDOW_RAD, DIVERGED_QVEL_SQ
from robocup_gym.sim.engines.mujoco.robot import RobotState
from robocup_gym.sim.engines.mujoco.scene import FRP_GEOMS, RobotSlot, frp_sensor_name
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.sim.vision import PLAYER_PARTS


def _contiguous(ids: np.ndarray) -> slice | None:
    """``ids`` as a slice when they are consecutive ascending indices (views instead of
    gathers on the hot path), else ``None`` (also when empty)."""
    n = len(ids)
    if n and np.array_equal(ids, np.arange(ids[0], ids[0] + n)):
        return slice(int(ids[0]), int(ids[0]) + n)
    return None


class WorldLayout:
    """The model indexing of :class:`~robocup_gym.sim.engines.mujoco.world.World`."""

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

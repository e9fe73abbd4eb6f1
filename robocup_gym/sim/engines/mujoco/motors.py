"""SimSpark's hinge motors, joint stops and contacts as rows of MuJoCo's solver, in NumPy: the
reference path of the MuJoCo world's step (``cstep.c`` does the same arithmetic in the same
order, bit-equal; :mod:`robocup_gym.sim.compiled`). A mixin of :class:`~.world.World`; how each
ODE row is translated: docs/reference/engines.md §2."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from robocup_gym.sim import physics as phys
from robocup_gym.sim.physics import CYCLE_S

try:  # the clip ufunc itself: np.clip's Python wrapper costs more than the clipping here
    from numpy._core.umath import clip as _clip
except ImportError:  # numpy < 2
    from numpy.core.umath import clip as _clip

CREEP_WINDOW_RAD = math.radians(0.5)
"""Largest position error the motor creep compensation corrects (anti-windup), rad."""
DIVERGED_QVEL_SQ = 1e10
"""Squared norm of the velocity vector above which the world counts as diverged (no Nao or
ball gets near 1e5 rad/s or m/s)."""
_DRAG = np.array([-phys.BODY_LINEAR_DRAG] * 3 + [-phys.BODY_ANGULAR_DRAG] * 3)
"""Drag coefficients per xfrc_applied component (force, torque)."""
_INV_CYCLE = 1.0 / CYCLE_S
_SATURATED = phys.MOTOR_MAX_TORQUE * (1.0 - 1e-9)
"""Force (N·m) from which a motor row counts as saturated: it could not reach its target."""
_any = np.count_nonzero
"""``a.any()`` for a 1-d bool array (hot path: counting is several times cheaper than the
method's or ``np.logical_or.reduce``'s reduction machinery on a few values)."""


class OdeRowsNumpy:
    """The NumPy step of :class:`~robocup_gym.sim.engines.mujoco.world.World`."""

    def _step_numpy(self) -> bool:
        """One cycle's physics with the per-cycle work in NumPy (the reference implementation).
        Returns whether the state diverged."""
        d = self._data
        m = self.model
        q = self._qpos[self._qpos_j]
        at_lo = q <= self._lo
        at_hi = q >= self._hi
        limited = at_lo | at_hi
        any_limited = _any(limited) > 0
        due = self.cycle
        for r in self.robots:
            if r.pending and r.pending[0][0] <= due:
                self._realise_commands(r, ~limited[r.joint_slice] if any_limited else None)
        if self._sleepers:
            self._wake_commanded()
        targets = self._targets
        # ODE at a stop (reference §2.4, ODE's addLimot): the motor row gives way to the stop row
        # (fully elastic, ``_bounce_stops``) and a constant torque, FMax into the stop when the
        # target pushes into it or is 0, fudge·FMax away from it when the target pulls away.
        # FMax into a stop that the stop row holds only caps how fast the joint may leave it:
        # the joint's velocity becomes max(stop row's target, free velocity − FMax·h/I). The
        # motor row, kept with the stop row's target as its own, does exactly that without an
        # explicit 10 N·m on light joints. Pulling away, the row goes (``_fudge_torques``).
        at_stop = None
        if any_limited:
            away = (at_lo & (targets > 0.0)) | (at_hi & (targets < 0.0))
            at_stop = away if _any(away) else None
        # Creep compensation: MuJoCo regularises the motor rows, so a held joint creeps slowly
        # under load where ODE's rigid motor row does not. Each motor follows the integral of its
        # commanded velocity; the small difference is corrected within a cycle. A motor that
        # saturated or sat at a stop restarts from where its joint is: motion lost there is
        # never caught up, as in ODE.
        q_ref = self._q_ref
        np.copyto(q_ref, q, where=self._motor_lost)
        _clip(q_ref, q - CREEP_WINDOW_RAD, q + CREEP_WINDOW_RAD, out=q_ref)
        motor_target = q_ref - q
        motor_target *= 1.0 / CYCLE_S
        motor_target += targets
        q_ref += targets * CYCLE_S
        if any_limited:
            np.copyto(motor_target, self._stop_speeds(q, at_lo, at_hi), where=limited)
        sort = self._motor_sort
        if sort is not None:
            motor_target = motor_target[sort]
        shift = self._motor_b * motor_target
        dofs = self._motor_dofs_sorted
        ms = self._motor_slice
        if at_stop is not None:
            rows = ~(at_stop if sort is None else at_stop[sort])
            if ms is not None:
                np.multiply(rows, phys.MOTOR_MAX_TORQUE, out=self._motor_views[0])
            else:
                m.dof_frictionloss[dofs] = np.where(rows, phys.MOTOR_MAX_TORQUE, 0.0)
            shift = shift[rows]
            self._fudge_torques(at_stop, at_lo)
            self._motors_relaxed = True
        elif self._motors_relaxed:
            m.dof_frictionloss[dofs] = phys.MOTOR_MAX_TORQUE
            d.qfrc_applied[self._qvel_j] = 0.0
            self._motors_relaxed = False
        nrows = len(shift)
        # Warm start: every motor reaches its target (the solver corrects saturated ones).
        if ms is not None:
            _, warm, qvel_motors = self._motor_views
            np.subtract(motor_target, qvel_motors, out=warm)
            warm *= self._inv_timestep
        else:
            d.qacc_warmstart[dofs] = (motor_target - self._qvel[dofs]) * self._inv_timestep
        self._ball_ground_contact_mode()
        for sub in range(self._substeps):
            mujoco.mj_step1(m, d)
            if sub == 0:
                # mj_step1 brought poses and velocities up to the state before this cycle's
                # physics: sample the accelerometer (reference §4.5) and set the cycle's drag
                self._sense_accelerometers()
                self._apply_drag()
            # The motor rows' reference acceleration −B·v becomes −B·(v − target): MuJoCo's
            # friction-loss row turned into ODE's velocity motor (see robocup_gym/robot/mjcf.py).
            if nrows:
                d.efc_aref[:nrows] += shift
            if d.ncon:
                self._surface_layer()
            if d.nl:
                self._bounce_stops()
            if self._sleepers:
                self._wake_touched()
            mujoco.mj_step2(m, d)
            if self._sleepers:
                self._hold_sleepers()
        # which motors could not hold their target this step: saturated at ±FMax (read from the
        # forces: with islands, MuJoCo 4 leaves ``efc_state`` at the solver's first guess), or
        # absent at a stop
        moving = np.abs(d.efc_force[:nrows]) < _SATURATED
        if at_stop is not None:
            held = np.zeros(len(dofs), dtype=bool)
            held[rows] = moving
            moving = held
        if sort is None:
            np.logical_not(moving, out=self._motor_lost)
        else:
            self._motor_lost[sort] = ~moving
        if any_limited:
            self._motor_lost |= limited
        qvel = self._qvel
        return not qvel.dot(qvel) < DIVERGED_QVEL_SQ  # also True for NaN

    def _stop_speeds(self, q: np.ndarray, at_lo: np.ndarray, at_hi: np.ndarray) -> np.ndarray:
        """Per joint, the velocity (rad/s) the stop row of a joint at a stop asks for: its ERP
        correction back into the range or, for a joint running into the stop, the reflected
        speed if larger (ODE: ``c = max(−erp·err/h, −bounce·v)``); meaningful where
        ``at_lo``/``at_hi``."""
        v = self._qvel[self._qvel_j]
        erp_speed = phys.JOINT_STOP_ERP_CFM[0] * self._inv_timestep
        into = np.maximum(v, 0.0)
        into *= phys.JOINT_STOP_BOUNCE
        speed_hi = np.maximum((q - self._hi) * erp_speed, into)
        into = np.maximum(-v, 0.0)
        into *= phys.JOINT_STOP_BOUNCE
        speed_lo = np.maximum((self._lo - q) * erp_speed, into)
        return np.where(at_hi, -speed_hi, speed_lo)

    def _fudge_torques(self, away: np.ndarray, at_lo: np.ndarray) -> None:
        """ODE's torque on a joint at a stop whose target pulls it ``away`` (reference §2.4): only
        fudge factor × FMax (1e-4 N·m), out of the stop (positive at the lower stop); 0 for
        every other joint."""
        fudge = phys.MOTOR_FUDGE_FACTOR * phys.MOTOR_MAX_TORQUE
        self._data.qfrc_applied[self._qvel_j] = np.where(at_lo, fudge, -fudge) * away

    def _bounce_stops(self) -> None:
        """Fully elastic joint stops (reference §2.4, ODE bounce 1): a stop row whose joint runs
        into the stop asks for the larger of its ERP correction and the reflected speed
        (ODE: ``c = max(−erp·err/h, −bounce·v)``), as a shift of its reference acceleration.
        Called between ``mj_step1`` and ``mj_step2``; the stop rows follow the friction rows."""
        d = self._data
        start = d.ne + d.nf
        rows = slice(start, start + d.nl)
        v = d.efc_vel[rows]
        aref = d.efc_aref[rows]
        # the row velocity after the step that the reference asks for (≥ 0 for a row that is
        # not moving into its stop: its ERP correction), and the bounce's, which wins only for a
        # row moving into the stop (v < 0)
        implied = aref / self._inv_timestep
        implied += v
        bounce = v * -phys.JOINT_STOP_BOUNCE
        np.maximum(bounce, implied, out=bounce)
        bounce -= implied
        bounce *= self._inv_timestep
        aref += bounce

    def _surface_layer(self) -> None:
        """ODE's contact surface layer (reference §7.1) on this step's contacts: the normal row
        pushes only by the depth beyond the 1 mm layer (reference acceleration
        ``−B·v − K·I·min(pos + layer, 0)`` instead of MuJoCo's ``−B·v − K·I·pos``, i.e. a shift of
        ``K·I·max(pos, −layer)``), so a contact within the layer still stops further approach
        and carries friction but does not push out. Called between ``mj_step1`` (which made
        the rows) and ``mj_step2`` (which solves them). Every contact here has three rows
        (condim 3, elliptic cones; checked when the world is built), normal row first, and the
        contacts' rows come last."""
        d = self._data
        start = d.ne + d.nf + d.nl
        rows = slice(start, start + 3 * d.ncon, 3)
        shift = np.maximum(d.efc_pos[rows], -phys.SURFACE_LAYER)
        kbip = d.efc_KBIP[rows]
        shift *= kbip[:, 0]
        shift *= kbip[:, 2]
        d.efc_aref[rows] += shift

    def _ball_ground_contact_mode(self) -> None:
        """Bouncy ball-ground contact only if the ball will hit the ground this cycle faster than
        0.8 m/s (ODE's bounce threshold, reference §5); otherwise ODE's over-damped soft contact."""
        z = self._qpos[self._ball_qpos + 2]
        vz = self._qvel[self._ball_qvel + 2]
        bouncy = bool(
            vz < -phys.BALL_BOUNCE_MIN_SPEED
            and z - phys.BALL_RADIUS - phys.GROUND_PLANE_Z + vz * CYCLE_S < 0.0
        )
        if bouncy != self._ball_bouncy:
            self.model.pair_solref[self._ball_ground_pair] = self._ball_ground_solref[bouncy]
            self._ball_bouncy = bouncy

    def _sense_accelerometers(self) -> None:
        """Each robot's accelerometer (reference §4.5): the torso's change of velocity over the last
        cycle plus gravity, in the torso frame, m/s²; called once the poses are current."""
        for r, v, rot, a_world in self._accel_io:
            np.subtract(v, r.prev_vel, out=a_world)
            a_world *= _INV_CYCLE
            a_world[2] += phys.GRAVITY
            r.prev_vel[:] = v
            a_world.dot(rot, out=r.accel)

    def _apply_drag(self) -> None:
        """Drag F = −0.01 v at each robot body's centre of mass and τ = −0.01 ω (reference §7.5),
        held over the cycle; from the drag sensors, which ``mj_step1`` has just evaluated."""
        if self._drag_force is not None:
            np.multiply(self._drag_vel, _DRAG, out=self._drag_force)
        elif self._drag_index is not None:
            self._data.xfrc_applied[self._drag_index] = self._drag_vel * _DRAG

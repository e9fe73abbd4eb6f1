"""What the ODE world reads back: ball and body poses and velocities, the Nao's perceptors (gyro,
accelerometer, foot sensors, joint angles), ground truth, and what the server's referee and
monitor read (body frames, the ball's touchers). A mixin of :class:`~.world.OdeWorld`, which owns
the state these read (``_state``, the robots, the library handle)."""

from __future__ import annotations

import mujoco
import numpy as np

from robocup_gym.sim.engines.ode import lib as ode
from robocup_gym.sim.vision import PLAYER_PARTS
from robocup_gym.types import ForceResistance, GroundTruth


class OdeReadings:
    """Readings of :class:`~robocup_gym.sim.engines.ode.world.OdeWorld` (SI units; joint angles
    in degrees as the ``HJ`` perceptor gives them)."""

    def _vec(self, ptr) -> np.ndarray:
        return np.array([ptr[0], ptr[1], ptr[2]])

    def _read_state(self) -> np.ndarray:
        """The state snapshot (per body: position, rotation, velocity, angular velocity; every
        hinge's angle and rate), read from ODE once after each change: in one C call, or by the
        Python loops without a compiler (the same numbers)."""
        if not self._fresh:
            if self._fast is not None:
                self._fast.read()
            else:
                lib = self._lib
                for k, b in enumerate(self._state_bodies):
                    p, m = lib.dBodyGetPosition(b), lib.dBodyGetRotation(b)
                    v, w = lib.dBodyGetLinearVel(b), lib.dBodyGetAngularVel(b)
                    self._state[k] = [
                        p[0], p[1], p[2],
                        m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10],
                        v[0], v[1], v[2], w[0], w[1], w[2],
                    ]  # fmt: skip
                for k, h in enumerate(self._all_joints):
                    self._angles[k] = lib.dJointGetHingeAngle(h)
                    self._rates[k] = lib.dJointGetHingeAngleRate(h)
            self._fresh = True
        return self._state

    def _body(self, body: int) -> np.ndarray:
        """Body ``body``'s row of the state snapshot (a view: copy what is kept)."""
        return self._read_state()[self._row[body]]

    def _rotation(self, body: int) -> np.ndarray:
        """Orientation of body handle ``body`` as a 3×3 matrix (its axes in world coordinates)."""
        return self._body(body)[3:12].reshape(3, 3).copy()

    def ball_position(self) -> np.ndarray:
        """Ball centre, world, m."""
        return self._body(self._ball)[0:3].copy()

    def ball_velocity(self) -> np.ndarray:
        """Ball linear velocity, world, m/s."""
        return self._body(self._ball)[12:15].copy()

    def ball_angular_velocity(self) -> np.ndarray:
        """Ball angular velocity, world, rad/s."""
        return self._body(self._ball)[15:18].copy()

    def body_position(self, index: int, name: str) -> np.ndarray:
        """Centre of robot ``index``'s body ``name`` (e.g. ``rfoot``), world, m."""
        r = self.robots[index]
        return self._body(r.bodies[r.body_index[name]])[0:3].copy()

    def body_rotation(self, index: int, name: str) -> np.ndarray:
        """Orientation of robot ``index``'s body ``name`` as a 3×3 matrix (torso-frame axes in
        world coordinates)."""
        r = self.robots[index]
        return self._rotation(r.bodies[r.body_index[name]])

    def torso_quat(self, index: int = 0) -> np.ndarray:
        """Torso orientation of robot ``index`` as a unit quaternion ``(w, x, y, z)``."""
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, self._body(self.robots[index].bodies[0])[3:12])
        return quat

    def torso_velocity(self, index: int = 0) -> np.ndarray:
        """Torso centre velocity of robot ``index``, world, m/s."""
        return self._body(self.robots[index].bodies[0])[12:15].copy()

    def torso_angular_velocity(self, index: int = 0) -> np.ndarray:
        """Torso angular velocity of robot ``index``, world, rad/s."""
        return self._body(self.robots[index].bodies[0])[15:18].copy()

    def gyro(self, index: int = 0) -> np.ndarray:
        """Torso angular velocity in the torso frame, deg/s (``GYR``, as the world's)."""
        row = self._body(self.robots[index].bodies[0])
        return np.degrees(row[15:18] @ row[3:12].reshape(3, 3))

    def accelerometer(self, index: int = 0) -> np.ndarray:
        """The accelerometer (``ACC``) of robot ``index``, m/s², torso frame."""
        return self.robots[index].accel.copy()

    def force_sensors(self, index: int = 0) -> dict[str, ForceResistance]:
        """``FRP`` readings of robot ``index`` from the last step's contact feedback: force (N)
        and centre of pressure (m) in the foot's own frame, as
        :meth:`robocup_gym.sim.engines.mujoco.world.World.force_sensors` gives them (a foot without
        contact
        is omitted; one whose contacts carry no force repeats its last reading)."""
        r = self.robots[index]
        self._sync_frp()
        out: dict[str, ForceResistance] = {}
        for name, (force, centre) in r.frp.items():
            if centre is None:
                if name in r.last_frp:
                    out[name] = r.last_frp[name]
                continue
            row = self._body(r.frp_bodies[name])
            rot = row[3:12].reshape(3, 3)
            out[name] = ForceResistance(point=(centre - row[0:3]) @ rot, force=force @ rot)
        r.last_frp = out
        return out

    def torso_position(self, index: int = 0) -> np.ndarray:
        """Torso centre of robot ``index``, world, m."""
        return self._body(self.robots[index].bodies[0])[0:3].copy()

    def ground_truth(self, index: int = 0) -> GroundTruth:
        """Exact ball and torso state of robot ``index`` (world frame)."""
        return GroundTruth(
            ball_pos=self.ball_position(),
            ball_vel=self.ball_velocity(),
            torso_pos=self.torso_position(index),
            torso_quat=self.torso_quat(index),
            torso_vel=self.torso_velocity(index),
            torso_ang_vel=self.torso_angular_velocity(index),
        )

    def _head_pose(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Head centre (world, m) and rotation matrix of robot ``index``."""
        r = self.robots[index]
        row = self._body(r.bodies[r.body_index["head"]])
        return row[0:3].copy(), row[3:12].reshape(3, 3).copy()

    def _part_positions(self, index: int) -> np.ndarray:
        """World positions of robot ``index``'s parts seen by vision (``PLAYER_PARTS``), m."""
        r = self.robots[index]
        st = self._read_state()
        return st[[self._row[r.bodies[r.body_index[p]]] for p in PLAYER_PARTS], 0:3]

    def torso_up(self, index: int = 0) -> np.ndarray:
        """The torso's up axis (+z of the torso frame) in world coordinates."""
        return self._body(self.robots[index].bodies[0])[[5, 8, 11]].copy()

    def joint_angles_deg(self, index: int = 0) -> np.ndarray:
        """Joint angles of robot ``index`` in degrees, canonical order."""
        self._read_state()
        return np.degrees(self._angles[self.robots[index].joint_slice])

    def joint_velocities(self, index: int = 0) -> np.ndarray:
        """Joint angular velocities of robot ``index`` in rad/s, canonical order."""
        self._read_state()
        return self._rates[self.robots[index].joint_slice].copy()

    # ------------------------------------------------------------------ what a server reads
    def motor_targets(self, index: int) -> np.ndarray:
        """Robot ``index``'s active motor targets (each hinge's ODE motor velocity), rad/s,
        canonical order."""
        get = self._lib.dJointGetHingeParam
        return np.array([get(h, ode.PARAM_VEL) for h in self.robot(index).joints])

    def set_motor_targets(self, index: int, targets: np.ndarray) -> None:
        """Set robot ``index``'s motor targets (rad/s, canonical order) as they are, without the
        hinge effector's rules or waking a body: to restore what :meth:`motor_targets` returned
        after a placement (which zeroes them)."""
        r = self.robot(index)
        values = np.asarray(targets, dtype=float)
        if values.shape != (len(r.joints),) or not np.isfinite(values).all():
            raise ValueError(f"motor targets must be {len(r.joints)} finite numbers")
        for h, v in zip(r.joints, values.tolist(), strict=True):
            self._lib.dJointSetHingeParam(h, ode.PARAM_VEL, v)

    def body_frames(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Every body of robot ``index`` in its model's order (``model.bodies``, torso first):
        centres ``(n, 3)`` (world, m) and rotations ``(n, 3, 3)`` (columns = body axes)."""
        r = self.robot(index)
        rows = self._read_state()[[self._row[b] for b in r.bodies]]
        return rows[:, 0:3].copy(), rows[:, 3:12].reshape(-1, 3, 3).copy()

    def every_body_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`body_frames` of every robot, one after the other in robot order."""
        rows = self.__dict__.get("_robot_rows")  # a world keeps its robots
        if rows is None:
            rows = self._robot_rows = np.array(
                [self._row[b] for r in self.robots for b in r.bodies], dtype=np.intp
            )
        st = self._read_state()[rows]
        return st[:, 0:3], st[:, 3:12].reshape(-1, 3, 3)

    def ball_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """Ball centre (world, m) and rotation matrix."""
        row = self._body(self._ball)
        return row[0:3].copy(), row[3:12].reshape(3, 3).copy()

    def body_positions(self) -> np.ndarray:
        """Centres of every body of the world (robots' parts, the ball; world, m), for a sanity
        check of the whole state."""
        return self._read_state()[:, 0:3]

    def robot_contacts(self) -> dict[tuple[int, int], tuple[np.ndarray, int]]:
        """The robots in contact with each other in the last step, as rcssserver3d's
        agent-collision handlers count them (a contact of two parts counts once for each that is
        not a foot or a toe; two feet do not count): ``{(i, j): (mean contact point (world, m),
        count)}`` for robot indices ``i < j``."""
        if self._robot_contacts_stamp != self._stamp:
            return {}
        return self._robot_contacts

    def ball_touchers(self) -> set[int]:
        """Indices of the robots with a part in contact with the ball in the last step."""
        if not len(self._ball_pairs):
            return set()
        touched = self._hit[self._ball_pairs] == self._stamp
        return set(self._ball_pair_robot[touched].tolist())

"""What the MuJoCo world reads back: ball and body poses and velocities, the Nao's perceptors (gyro,
accelerometer, foot sensors, joint angles), ground truth, and what the server's referee and
monitor read (body frames, the ball's touchers). A mixin of :class:`~.world.World`, which owns
the model, the data and the robots' index arrays these read."""

from __future__ import annotations

import numpy as np

from robocup_gym.types import ForceResistance, GroundTruth


class WorldReadings:
    """Readings of :class:`~robocup_gym.sim.engines.mujoco.world.World` (SI units; joint angles in
    degrees as the ``HJ`` perceptor gives them)."""

    # ------------------------------------------------------------------ perception
    def ground_truth(self, index: int = 0) -> GroundTruth:
        """Exact ball and torso state of robot ``index`` (world frame)."""
        r = self.robot(index)
        d = self._posed()
        a, b = r.qpos_root, r.qvel_root
        rot = d.xmat[r.torso_body].reshape(3, 3)
        bq, bv = self._ball_qpos, self._ball_qvel
        return GroundTruth(
            ball_pos=d.qpos[bq : bq + 3].copy(),
            ball_vel=d.qvel[bv : bv + 3].copy(),
            torso_pos=d.qpos[a : a + 3].copy(),
            torso_quat=d.qpos[a + 3 : a + 7].copy(),
            torso_vel=d.qvel[b : b + 3].copy(),
            torso_ang_vel=rot @ d.qvel[b + 3 : b + 6],
        )

    def torso_velocity(self, index: int = 0) -> np.ndarray:
        """Torso centre velocity of robot ``index``, world, m/s."""
        b = self.robot(index).qvel_root
        return self._data.qvel[b : b + 3].copy()

    def ball_position(self) -> np.ndarray:
        """Ball centre, world, m."""
        return self._data.qpos[self._ball_qpos : self._ball_qpos + 3].copy()

    def ball_velocity(self) -> np.ndarray:
        """Ball linear velocity, world, m/s."""
        return self._data.qvel[self._ball_qvel : self._ball_qvel + 3].copy()

    def ball_angular_velocity(self) -> np.ndarray:
        """Ball angular velocity, world, rad/s."""
        return self._data.qvel[self._ball_qvel + 3 : self._ball_qvel + 6].copy()

    def torso_position(self, index: int = 0) -> np.ndarray:
        """Torso centre of robot ``index``, world, m."""
        a = self.robot(index).qpos_root
        return self._data.qpos[a : a + 3].copy()

    def torso_up(self, index: int = 0) -> np.ndarray:
        """The torso's up axis (+z of the torso frame) in world coordinates."""
        return self._posed().xmat[self.robot(index).torso_body].reshape(3, 3)[:, 2].copy()

    def joint_angles_deg(self, index: int = 0) -> np.ndarray:
        """Joint angles of robot ``index`` in degrees, canonical order."""
        return np.degrees(self._data.qpos[self.robot(index).qpos_joints])

    def joint_velocities(self, index: int = 0) -> np.ndarray:
        """Joint angular velocities of robot ``index`` in rad/s, canonical order."""
        return self._data.qvel[self.robot(index).qvel_joints].copy()

    def gyro(self, index: int = 0) -> np.ndarray:
        """Torso angular velocity in the torso frame, deg/s (``GYR``)."""
        b = self.robot(index).qvel_root
        return np.degrees(self._data.qvel[b + 3 : b + 6])

    def force_sensors(self, index: int = 0) -> dict[str, ForceResistance]:
        """``FRP`` readings of robot ``index`` from the contacts of the last physics step: force
        (N) and force-weighted centre of pressure (m), both in the foot's own frame (reference
        §4.6).
        A foot without contact is omitted; one whose contacts carry no force repeats its last
        reading (as SimSpark does for a disabled body)."""
        r = self.robot(index)
        d = self._posed()
        data = self._sensordata
        out: dict[str, ForceResistance] = {}
        last = r.last_frp
        for name, adr, body in r.frp_sensors:
            if data[adr] == 0.0:  # number of contacts of this foot in the last step
                continue
            force = data[adr + 1 : adr + 4]
            if not force.any():
                if name in last:
                    out[name] = last[name]
                continue
            # world → foot frame: v @ R = Rᵀ v
            rot = d.xmat[body].reshape(3, 3)
            out[name] = ForceResistance(
                point=(data[adr + 4 : adr + 7] - d.xpos[body]) @ rot, force=force @ rot
            )
        r.last_frp = out
        return out

    def accelerometer(self, index: int = 0) -> np.ndarray:
        """The accelerometer (``ACC``) of robot ``index``, m/s², torso frame."""
        return self.robot(index).accel.copy()

    def _head_pose(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Head centre (world, m) and rotation matrix of robot ``index``."""
        r = self.robots[index]
        d = self._posed()
        return d.xpos[r.head_body].copy(), d.xmat[r.head_body].reshape(3, 3).copy()

    def _part_positions(self, index: int) -> np.ndarray:
        """World positions of robot ``index``'s parts seen by vision (``PLAYER_PARTS``), m."""
        return self._posed().xpos[self.robots[index].part_bodies]

    # ------------------------------------------------------------------ what a server reads
    def torso_quat(self, index: int = 0) -> np.ndarray:
        """Torso orientation of robot ``index`` as a unit quaternion ``(w, x, y, z)``."""
        a = self.robot(index).qpos_root
        return self._data.qpos[a + 3 : a + 7].copy()

    def motor_targets(self, index: int) -> np.ndarray:
        """Robot ``index``'s active motor targets, rad/s, canonical order (a copy)."""
        return self.robot(index).targets.copy()

    def body_frames(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Every body of robot ``index`` in its model's order (``model.bodies``, torso first):
        centres ``(n, 3)`` (world, m) and rotations ``(n, 3, 3)`` (columns = body axes)."""
        r = self.robot(index)
        d = self._posed()
        return d.xpos[r.robot_bodies].copy(), d.xmat[r.robot_bodies].reshape(-1, 3, 3).copy()

    def every_body_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`body_frames` of every robot, one after the other in robot order."""
        ids = self.__dict__.get("_robot_body_ids")
        if ids is None:
            ids = self._robot_body_ids = np.concatenate([r.robot_bodies for r in self.robots])
        d = self._posed()
        return d.xpos[ids], d.xmat[ids].reshape(-1, 3, 3)

    def ball_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """Ball centre (world, m) and rotation matrix."""
        d = self._posed()
        b = self._ball_body
        return d.xpos[b].copy(), d.xmat[b].reshape(3, 3).copy()

    def body_positions(self) -> np.ndarray:
        """Centres of every body of the world (robots' parts, the ball; world, m), for a sanity
        check of the whole state."""
        return self._posed().xpos

    def robot_contacts(self) -> dict[tuple[int, int], tuple[np.ndarray, int]]:
        """The robots in contact with each other in the last step, as rcssserver3d's
        agent-collision handlers count them (a contact of two parts counts once for each that is
        not a foot or a toe; two feet do not count): ``{(i, j): (mean contact point (world, m),
        count)}`` for robot indices ``i < j``."""
        d = self._data
        ncon = d.ncon
        if ncon == 0 or len(self.robots) < 2:
            return {}
        handler = self.__dict__.get("_geom_handler")
        if handler is None:
            robot = np.full(self.model.ngeom, -1, dtype=np.int64)
            weight = np.zeros(self.model.ngeom, dtype=np.int64)
            for r in self.robots:
                names = ["rfoot", "lfoot"] + (
                    ["rtoe", "ltoe"] if r.model.robot_type.has_toes else []
                )
                feet = {int(self.model.geom(r.prefix + n).id) for n in names}
                for g in r.robot_geoms:
                    robot[g] = r.index
                    weight[g] = 0 if g in feet else 1
            handler = self.__dict__["_geom_handler"] = (robot, weight)
        robot, weight = handler
        geoms = d.contact.geom[:ncon]
        i, j = robot[geoms[:, 0]], robot[geoms[:, 1]]
        w = weight[geoms[:, 0]] + weight[geoms[:, 1]]
        keep = np.flatnonzero((i >= 0) & (j >= 0) & (i != j) & (w > 0))
        out: dict[tuple[int, int], tuple[np.ndarray, int]] = {}
        sums: dict[tuple[int, int], list] = {}
        for k in keep.tolist():
            a, b = int(i[k]), int(j[k])
            acc = sums.setdefault((min(a, b), max(a, b)), [np.zeros(3), 0])
            acc[0] += int(w[k]) * d.contact.pos[k]
            acc[1] += int(w[k])
        for ij, (total, n) in sums.items():
            out[ij] = (total / n, n)
        return out

    def ball_touchers(self) -> set[int]:
        """Indices of the robots with a part in contact with the ball in the last step."""
        d = self._data
        ncon = d.ncon
        out: set[int] = set()
        if ncon == 0:
            return out
        geom_robot = self._geom_robot
        if geom_robot is None:
            geom_robot = self._geom_robot = [-1] * self.model.ngeom
            for r in self.robots:
                for g in r.robot_geoms:
                    geom_robot[g] = r.index
        ball = self._ball_geom
        for g1, g2 in d.contact.geom[:ncon].tolist():  # a few pairs: plain Python is fastest
            if g1 == ball:
                i = geom_robot[g2]
            elif g2 == ball:
                i = geom_robot[g1]
            else:
                continue
            if i >= 0:
                out.add(i)
        return out

"""Contacts in the ODE world as rcssserver3d makes them: which geom pairs can touch (with the
surfaces SimSpark mixes for them), the collision pass before each step (``dCollide`` on every
pair whose bounding boxes meet, up to four contact joints per pair), the force resistance
perceptors summed from the contacts' feedback, and the contacts between robots that the
referee's fouls read.

:class:`OdeContacts` is a part of :class:`~robocup_gym.sim.engines.ode.world.OdeWorld`; the
compiled loops (:mod:`robocup_gym.sim.engines.ode.fast`) do the same work bit for bit.
"""

from __future__ import annotations

import ctypes
import math
import time

import numpy as np

from robocup_gym.sim import physics as phys
from robocup_gym.sim.engines.ode import lib as ode
from robocup_gym.sim.engines.ode.robot import OdeRobot
from robocup_gym.sim.engines.ode.surfaces import (
    BALL_SURFACE,
    GROUND_SURFACE,
    ROBOT_SURFACE,
    WALL_SURFACE,
    mix_surfaces,
    surface_parameters,
)

MAX_CONTACTS = 4
"""Contact points per geom pair (reference §7.3)."""


def _apart(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two axis-aligned boxes ``(minx, maxx, miny, maxy, minz, maxz)`` are apart (then
    their geoms cannot touch); ``ode_step.c``'s ``apart`` is the same test."""
    return a[1] < b[0] or b[1] < a[0] or a[3] < b[2] or b[3] < a[2] or a[5] < b[4] or b[5] < a[4]


def collision_pairs(
    lib, robots: list[OdeRobot], ball_geom: int, ground: int, statics: list[int]
) -> list[tuple]:
    """Every geom pair that can touch, as ``(geom1, geom2, body1, body2, surface, sensor1,
    sensor2)`` (sensor: the ``(robot, FRP name)`` of a body with a force perceptor, else
    ``None``; body
    ``None`` for the static ground) with its mixed surface: robot parts with the ground,
    the ball and other robots' parts (never with their own robot: inner collision is
    disabled, reference §1.1); the ball with the ground."""
    robot_ground = surface_parameters(mix_surfaces(ROBOT_SURFACE, GROUND_SURFACE))
    robot_ball = surface_parameters(mix_surfaces(ROBOT_SURFACE, BALL_SURFACE))
    robot_robot = surface_parameters(mix_surfaces(ROBOT_SURFACE, ROBOT_SURFACE))
    ball_ground = surface_parameters(mix_surfaces(BALL_SURFACE, GROUND_SURFACE))
    robot_wall = surface_parameters(mix_surfaces(ROBOT_SURFACE, WALL_SURFACE))
    ball_wall = surface_parameters(mix_surfaces(BALL_SURFACE, WALL_SURFACE))
    pairs = [(ball_geom, ground, ball_ground)]
    for i, r in enumerate(robots):
        for g in r.geoms:
            pairs.append((g, ground, robot_ground))
            pairs.append((g, ball_geom, robot_ball))
            for other in robots[i + 1 :]:
                pairs.extend((g, g2, robot_robot) for g2 in other.geoms)
    # walls and goals last: they touch nothing near the centre of the field, so the order of
    # the contacts (and so every result) there is that of a world without them
    for w in statics:
        pairs.append((ball_geom, w, ball_wall))
        pairs.extend((g, w, robot_wall) for r in robots for g in r.geoms)
    body = lib.dGeomGetBody
    sensor = {}  # body handle -> (robot, FRP name)
    for i, r in enumerate(robots):
        for name, b in r.frp_bodies.items():
            sensor[b] = (i, name)
    return [
        (g1, g2, body(g1), body(g2), s, sensor.get(body(g1)), sensor.get(body(g2)))
        for g1, g2, s in pairs
    ]


class OdeContacts:
    """The contact side of :class:`~robocup_gym.sim.engines.ode.world.OdeWorld` (its ODE
    handles, robots and state snapshot are the world's)."""

    def _init_contacts(self) -> None:
        """The geom pairs that can touch, their AABB slots, the feedback slots of the force
        perceptors and the per-pair bookkeeping of the contact loops (Python and compiled)."""
        self._contact_buf = (ode.ContactGeom * MAX_CONTACTS)()
        self._contact = ode.Contact()
        self._pairs = collision_pairs(
            self._lib, self.robots, self._ball_geom, self._ground, self._statics
        )
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

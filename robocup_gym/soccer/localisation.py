"""Where a player is, and where the ball is, from what it perceives on a real server: the
landmarks its restricted vision sees (goal posts and corner flags), its head joints and its
accelerometer, held and turned with the gyroscope between ``See`` messages.

The geometry (vision is relative to the head: x right, y forward, z up; reference §4.7):

1. every seen object's polar coordinates become a vector in the head frame, then in the torso
   frame through the head's yaw (``hj1``, about z) and pitch (``hj2``, about x);
2. the torso's tilt comes from the accelerometer (gravity, when its magnitude is within 30 % of
   g: a robot at rest or walking, not one being thrown about); rotating the tilt away gives each
   object's offset in a level frame that turns with the torso's heading;
3. each seen landmark ``i`` (world position ``L_i``, level offset ``(a_i, b_i)``) then says
   ``L_i = h + R(ψ − 90°) (a_i, b_i)`` for the head's ground position ``h`` and the torso's
   heading ``ψ``; two or more landmarks give ``h`` and ``ψ`` by linear least squares (weighted
   by 1 / distance: SimSpark's noise grows with it), one landmark gives ``h`` from the heading
   carried by the gyroscope.

Positions are in the world frame (the left team's goal at x = −15, whichever side the player
is on: the landmarks' names are absolute). A fix is as good as the landmarks seen: on the
default engine with the server's noise, a robot standing in its half seeing four landmarks is
placed within a few centimetres and 1° (``tests/soccer/test_localisation.py``).
"""

from __future__ import annotations

import collections
import math
from dataclasses import dataclass

import numpy as np

from robocup_gym.robot.nao import NaoModel
from robocup_gym.sim.field import LANDMARKS
from robocup_gym.sim.kinematics import resting_height_and_feet
from robocup_gym.sim.physics import BALL_RADIUS, CYCLE_S, GRAVITY
from robocup_gym.sim.rotations import matrix_to_quat
from robocup_gym.types import GroundTruth, Perception

__all__ = [
    "Estimator",
    "Fix",
    "Localiser",
    "head_frame_vector",
    "level_offsets",
    "level_to_world",
    "locate",
    "untilt",
    "up_from_accel",
]

_TILT_TRUSTED = 0.3
"""The accelerometer tells the tilt when its magnitude is within this share of g."""


def head_frame_vector(polar: np.ndarray) -> np.ndarray:
    """A seen object's polar coordinates ``(distance m, horizontal deg, vertical deg)`` → its
    position relative to the head, head frame (x right, y forward, z up), m."""
    d, theta, phi = (float(v) for v in polar[:3])
    t, f = math.radians(theta), math.radians(phi)
    r = d * math.cos(f)
    return np.array([-r * math.sin(t), r * math.cos(t), d * math.sin(f)])


def _rot_z(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rot_x(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def up_from_accel(accel: np.ndarray | None) -> np.ndarray | None:
    """The world's up direction in the torso frame as the accelerometer (m/s², torso frame)
    tells it, a unit vector; ``None`` when its magnitude is more than 30 % off g (the robot is
    being thrown about, or there is no reading)."""
    if accel is None:
        return None
    a = np.asarray(accel, dtype=float)
    norm = float(np.linalg.norm(a))
    if not (math.isfinite(norm) and abs(norm - GRAVITY) < _TILT_TRUSTED * GRAVITY):
        return None
    return a / norm


def untilt(up: np.ndarray | None) -> np.ndarray:
    """The rotation that takes the torso frame to a level one with the same heading: the
    smallest one turning ``up`` (the world's up direction in the torso frame; ``None``: the
    torso is upright) to +z."""
    if up is None:
        return np.eye(3)
    g = np.asarray(up, dtype=float) / float(np.linalg.norm(up))
    axis = np.cross(g, (0.0, 0.0, 1.0))
    s, c = float(np.linalg.norm(axis)), float(g[2])
    if s < 1e-9:
        return np.eye(3) if c > 0.0 else np.diag([1.0, -1.0, -1.0])
    k = axis / s
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + s * kx + (1.0 - c) * (kx @ kx)


def level_offsets(
    objects: dict[str, np.ndarray],
    head_yaw_deg: float,
    head_pitch_deg: float,
    up: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Each seen object's position relative to the head in the level frame that turns with the
    torso (x right, y forward, z up), m: the polar coordinates through the head joints (deg)
    and the torso's tilt (``up``: the world's up direction in the torso frame; ``None``:
    upright)."""
    to_level = untilt(up) @ _rot_z(head_yaw_deg) @ _rot_x(head_pitch_deg)
    return {name: to_level @ head_frame_vector(p) for name, p in objects.items()}


def level_to_world(heading_deg: float, offset: np.ndarray) -> np.ndarray:
    """A level-frame offset's (x right, y forward) ground part in the world frame (x, y) for a
    torso facing ``heading_deg``."""
    t = math.radians(heading_deg - 90.0)
    c, s = math.cos(t), math.sin(t)
    return np.array([c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]])


@dataclass(frozen=True)
class Fix:
    """Where the robot is: its torso's ground position and heading, world frame."""

    x: float
    """m."""
    y: float
    """m."""
    heading_deg: float
    """Where the torso faces once its tilt is rotated away (by the smallest rotation that makes
    it upright), deg counter-clockwise from +x."""
    landmarks: int
    """How many landmarks placed it (1: the heading was carried, not seen)."""


def locate(
    offsets: dict[str, np.ndarray],
    head_above_torso: np.ndarray,
    heading_deg: float | None = None,
) -> Fix | None:
    """The robot's :class:`Fix` from the level offsets of what it sees (:func:`level_offsets`),
    or ``None`` when too few landmarks are in them (two, or one with ``heading_deg`` known).

    Args:
        offsets: Level-frame offsets by name; names not among the landmarks (the ball) are
            ignored.
        head_above_torso: The head centre relative to the torso centre, level frame, m (its
            horizontal part is subtracted to place the torso).
        heading_deg: The heading carried from an earlier fix, used when one landmark is seen.
    """
    seen = [(LANDMARKS[n], v) for n, v in offsets.items() if n in LANDMARKS]
    if len(seen) >= 2:
        rows, rhs, weights = [], [], []
        for (lx, ly, _), v in seen:
            a, b = float(v[0]), float(v[1])
            w = 1.0 / max(float(np.linalg.norm(v)), 0.5)
            # L = h + (c a − s b, s a + c b) with (c, s) = (cos, sin)(ψ − 90°)
            rows += [[1.0, 0.0, a, -b], [0.0, 1.0, b, a]]
            rhs += [lx, ly]
            weights += [w, w]
        sw = np.sqrt(np.array(weights))
        sol, *_ = np.linalg.lstsq(np.array(rows) * sw[:, None], np.array(rhs) * sw, rcond=None)
        heading = math.degrees(math.atan2(sol[3], sol[2])) + 90.0
    elif len(seen) == 1 and heading_deg is not None:
        heading = float(heading_deg)
    else:
        return None
    # the head where each landmark puts it, averaged with the same weights, then the torso
    heads = np.array([np.asarray(lm[:2]) - level_to_world(heading, v) for lm, v in seen])
    weights = np.array([1.0 / max(float(np.linalg.norm(v)), 0.5) for _, v in seen])
    x, y = weights @ heads / weights.sum() - level_to_world(heading, head_above_torso)
    heading = (heading + 180.0) % 360.0 - 180.0
    return Fix(float(x), float(y), float(heading), len(seen))


class Localiser:
    """One player's estimate of its pose and of the ball, kept from cycle to cycle.

    Call :meth:`update` with every perception. On a ``See`` it takes a fresh fix
    (:func:`locate`) and the ball's position from it; between ``See`` messages, and when too few
    landmarks are in view, the heading turns with the gyroscope and the last position and ball
    are held. :attr:`fix` is ``None`` until the first fix; :attr:`ball_xy` until the ball has
    been seen with a fix.
    """

    def __init__(self, model: NaoModel) -> None:
        head = next(b for b in model.bodies if b.name == "head")
        self._head_offset = np.asarray(head.pos, dtype=float)
        """The head centre relative to the torso centre, torso frame, m."""
        self.fix: Fix | None = None
        self.ball_xy: np.ndarray | None = None
        """The ball's ground position when last seen, world frame, m."""
        self.cycles_since_fix = 0
        self.cycles_since_ball = 0
        self._head_level: np.ndarray | None = None
        """The head centre from the torso centre in the last ``See``'s level frame, m."""

    def reset(self) -> None:
        """Forget everything (a new game, or the robot was moved)."""
        self.fix, self.ball_xy, self._head_level = None, None, None
        self.cycles_since_fix = self.cycles_since_ball = 0

    def place(self, x: float, y: float, heading_deg: float) -> None:
        """Start from a known pose (where the robot beamed to), world frame."""
        self.fix, self.cycles_since_fix = Fix(float(x), float(y), float(heading_deg), 0), 0

    def update(self, p: Perception, up: np.ndarray | None = None) -> Fix | None:
        """Take one cycle's perception; returns the current estimate.

        Args:
            p: The perception.
            up: The world's up direction in the torso frame, if the caller tracks it better
                than one accelerometer reading (:class:`Estimator` filters it); ``None``: from
                this cycle's accelerometer (upright when that is not to be trusted).
        """
        self.cycles_since_fix += 1
        self.cycles_since_ball += 1
        if up is None:
            up = up_from_accel(p.accel)
        if self.fix is not None:  # the gyroscope turns the carried heading (deg/s)
            w = np.asarray(p.gyro, dtype=float)
            turn = float(w @ up) if up is not None else float(w[2])
            f = self.fix
            heading = (f.heading_deg + turn * CYCLE_S + 180.0) % 360.0 - 180.0
            self.fix = Fix(f.x, f.y, heading, f.landmarks)
        v = p.vision
        if v is None:
            return self.fix
        offsets = level_offsets(v.objects, p.joint("hj1"), p.joint("hj2"), up)
        head = untilt(up) @ self._head_offset
        fix = locate(offsets, head, None if self.fix is None else self.fix.heading_deg)
        if fix is not None:
            self.fix, self.cycles_since_fix = fix, 0
        self._head_level = head
        ball = offsets.get("B")
        if ball is not None and self.fix is not None:
            self.ball_xy = self.seen_at(ball)
            self.cycles_since_ball = 0
        return self.fix

    def seen_at(self, offset: np.ndarray) -> np.ndarray:
        """Where something seen in the last ``See`` is on the ground, world (x, y), m, from the
        current fix: its level-frame offset from the head (:func:`level_offsets`, with the tilt
        :meth:`update` used).

        Raises:
            RuntimeError: before the first fix or the first ``See``.
        """
        if self.fix is None or self._head_level is None:
            raise RuntimeError("nothing seen and placed yet: no fix to place it from")
        f = self.fix
        return np.array([f.x, f.y]) + level_to_world(f.heading_deg, offset + self._head_level)


TILT_GAIN = 0.05
"""Each cycle the tracked up direction moves this share of the way to the accelerometer's
(a complementary filter: the gyroscope carries it, gravity corrects its drift)."""
VELOCITY_WINDOW_S = 0.4
"""The ball's velocity is the least-squares slope of its sightings over this long (their noise,
a few centimetres every 3 cycles, gives velocities off by tenths of a m/s between two)."""


class Estimator:
    """What one player knows of its own state and the ball, from its own perceptors only, as a
    :class:`~robocup_gym.types.GroundTruth` (the form the skills and teams read ground truth
    in): what a player on a competition server, which sends no ground truth, plays with.

    * torso orientation: the up direction tracked with the gyroscope and corrected toward the
      accelerometer (:data:`TILT_GAIN`), turned to the heading of the last fix;
    * torso position: the fix's ground position (:class:`Localiser`), and its height from the
      kinematics of the joint angles with the lowest point on the ground
      (:func:`~robocup_gym.sim.kinematics.resting_height_and_feet`);
    * the torso's velocity: leg odometry, the foot that carries the robot (its foot pressure
      perceptor feels more force) held still, so the torso moves opposite to that foot's change
      of place relative to it (the kinematics of two successive cycles' joint angles); between
      fixes the position moves on at that velocity; the turn rate from the gyroscope;
    * the ball: where it was last seen, its velocity the slope of its sightings over
      :data:`VELOCITY_WINDOW_S`.

    Args:
        model: The robot's model (its head's place on the torso, its joints).
    """

    def __init__(self, model: NaoModel) -> None:
        self.model = model
        self.localiser = Localiser(model)
        self.reset()

    def reset(self) -> None:
        """Forget everything."""
        self.localiser.reset()
        self.up: np.ndarray | None = None
        self.vel = np.zeros(3)
        self._feet: tuple[float, np.ndarray] | None = None
        self._moved = np.zeros(2)
        """How far the torso moved (odometry) since the last fix, world (x, y), m."""
        self._balls: collections.deque = collections.deque()

    def place(self, x: float, y: float, heading_deg: float) -> None:
        """Start from a known pose (where the robot beamed to), world frame."""
        self.localiser.place(x, y, heading_deg)
        self._moved[:] = 0.0
        self._balls.clear()

    def _track_up(self, p: Perception) -> np.ndarray:
        measured = up_from_accel(p.accel)
        if self.up is None:
            self.up = measured if measured is not None else np.array([0.0, 0.0, 1.0])
            return self.up
        w = np.radians(np.asarray(p.gyro, dtype=float))
        up = self.up - CYCLE_S * np.cross(w, self.up)  # a fixed world vector, seen turning
        if measured is not None:
            up += TILT_GAIN * (measured - up)
        self.up = up / float(np.linalg.norm(up))
        return self.up

    def update(self, p: Perception) -> GroundTruth | None:
        """Take one cycle's perception; returns the estimate (``None`` before the first fix)."""
        up = self._track_up(p)
        loc = self.localiser
        fix = loc.update(p, up)
        if fix is None:
            return None
        t = float(p.time)
        rot = _rot_z(fix.heading_deg - 90.0) @ untilt(up)  # torso → world
        quat = matrix_to_quat(rot)
        # the feet in the torso frame: the joints alone move them (not the estimate's jitter)
        z, feet = resting_height_and_feet(self.model.robot_type.index, p.joint_angles_deg, quat)
        omega = rot @ np.radians(np.asarray(p.gyro, dtype=float))  # world, rad/s
        # whole cycles since the last percept: the clock's difference itself would differ in
        # its last bits with the clock's value (the same motion would read differently when a
        # game started a cycle later)
        cycles = round((t - self._feet[0]) / CYCLE_S) if self._feet is not None else 0
        if cycles >= 1:
            force = [_force(p, "lf"), _force(p, "rf")]
            if max(force) > 0.0:
                # the foot that carries the robot stays put: 0 = d/dt (torso + R r)
                k = int(force[1] > force[0])
                r_dot = (feet[k] - self._feet[1][k]) / (cycles * CYCLE_S)
                self.vel = -(rot @ r_dot) - np.cross(omega, rot @ feet[k])
        self._feet = (t, feet)
        if loc.cycles_since_fix == 0:
            self._moved[:] = 0.0
        else:
            self._moved += self.vel[:2] * CYCLE_S
        x, y = fix.x + self._moved[0], fix.y + self._moved[1]
        ball = np.zeros(3)
        if loc.ball_xy is not None:
            ball = np.array([loc.ball_xy[0], loc.ball_xy[1], BALL_RADIUS])
            if loc.cycles_since_ball == 0:
                _keep(self._balls, t, ball)
        ball_vel = _slope(self._balls)
        return GroundTruth(
            ball_pos=ball,
            ball_vel=ball_vel,
            torso_pos=np.array([x, y, z]),
            torso_quat=quat,
            torso_vel=self.vel.copy(),
            torso_ang_vel=omega,
        )


def _force(p: Perception, foot: str) -> float:
    """The force a foot pressure perceptor feels (N; 0 without contact)."""
    frp = p.force_sensors.get(foot)
    return 0.0 if frp is None else float(np.linalg.norm(frp.force))


def _keep(track: collections.deque, t: float, value: np.ndarray) -> None:
    """Add ``(t, value)`` to ``track`` and drop what is older than :data:`VELOCITY_WINDOW_S` (a
    clock set back starts it afresh)."""
    if track and t < track[-1][0] - 1e-9:
        track.clear()
    if track and abs(t - track[-1][0]) < 1e-9:
        track.pop()
    track.append((t, value))
    while track[0][0] < t - VELOCITY_WINDOW_S - 1e-9:
        track.popleft()


def _slope(track: collections.deque) -> np.ndarray:
    """The least-squares rate of change of the 3-vectors in ``track`` (zeros for fewer than
    two)."""
    if len(track) < 2:
        return np.zeros(3)
    ts = np.array([t for t, _ in track])
    vs = np.array([v for _, v in track])
    dt = ts - ts.mean()
    return dt @ (vs - vs.mean(axis=0)) / float(dt @ dt)

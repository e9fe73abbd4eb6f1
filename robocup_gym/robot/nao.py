"""The simulated Nao as data: bodies and hinge joints of every robot type (reference §1–3).

This module is the single source of truth for the robot. :func:`nao_model` resolves the rsg
construction (offsets of each part from the previous one, type parameters) into positions of
body centres and joint anchors relative to the torso centre at the zero pose, in the **torso
frame** (x = robot's right, y = robot's forward, z = up). The MJCF is generated from it
(:mod:`robocup_gym.robot.mjcf`).

Joint order (the *canonical order* used by every array in RoboCup Gym) is the numbering of the
spec's joint table: ``he1 he2 lae1-4 lle1-6 rle1-6 rae1-4`` and, for type 4, ``lle7 rle7``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache, cached_property

import numpy as np

from robocup_gym.robot.types import DEFAULT_MAX_SPEED, RobotType, robot_type

Vec3 = tuple[float, float, float]


def _mirror_sign(axis_from: Sequence[float], axis_to: Sequence[float]) -> float:
    """The sign taking a rotation about ``axis_from`` to its mirror image about ``axis_to``
    across the sagittal plane (x ↦ −x, torso frame): ``−axis_to · M axis_from`` with
    ``M = diag(−1, 1, 1)``, rounded."""
    mirrored = np.array(axis_from, dtype=float) * (-1.0, 1.0, 1.0)
    return float(np.round(-np.dot(np.array(axis_to, dtype=float), mirrored), 6))


@dataclass(frozen=True)
class Body:
    """One rigid body of the robot (reference §1.2)."""

    name: str
    """rsg name without side prefix for the torso/neck/head, e.g. ``rthigh``."""
    parent: str | None
    shape: str
    """``box``, ``sphere`` or ``capsule`` (capsule axis = local z)."""
    size: Vec3
    """Box: full edge lengths x, y, z; sphere: (radius, 0, 0); capsule: (radius, cylinder length, 0)."""
    mass: float
    """kg."""
    pos: Vec3
    """Centre relative to the torso centre at the zero pose, torso frame, m."""
    collides: bool
    """False for the mass-only spheres (shoulders, elbows, hips, ankles)."""

    @property
    def inertia(self) -> Vec3:
        """Principal moments (kg·m²) of the uniform solid, as ODE's ``dMassSet*Total``."""
        m = self.mass
        if self.shape == "box":
            x, y, z = self.size
            return (m * (y * y + z * z) / 12, m * (x * x + z * z) / 12, m * (x * x + y * y) / 12)
        if self.shape == "sphere":
            i = 0.4 * m * self.size[0] ** 2
            return (i, i, i)
        if self.shape == "capsule":
            r, length = self.size[0], self.size[1]
            v_cyl = math.pi * r * r * length
            v_sph = 4.0 / 3.0 * math.pi * r**3
            m1 = m * v_cyl / (v_cyl + v_sph)
            m2 = m * v_sph / (v_cyl + v_sph)
            ia = m1 * (0.25 * r * r + length * length / 12) + m2 * (
                0.4 * r * r + 0.375 * r * length + 0.25 * length * length
            )
            ib = (0.5 * m1 + 0.4 * m2) * r * r
            return (ia, ia, ib)
        raise ValueError(f"unknown shape {self.shape!r}")


@dataclass(frozen=True)
class Joint:
    """One hinge joint (reference §2.1)."""

    effector: str
    """Command name on the wire (``he1`` … ``rle7``); velocities in rad/s."""
    perceptor: str
    """Name in ``(HJ (n …))`` (``hj1`` … ``rlj7``); angles in degrees."""
    manual_name: str
    nao_name: str
    parent: str
    child: str
    anchor: Vec3
    """Anchor relative to the torso centre at the zero pose, torso frame, m."""
    axis: Vec3
    """Axis in the torso frame at the zero pose; positive angle = right-hand rotation of child."""
    min_deg: float
    max_deg: float
    max_speed: float
    """Commands are clipped to ±max_speed (rad/s)."""
    max_torque: float = 10.0
    """Motor max torque (ODE ``FMax``), N·m."""

    @property
    def range_rad(self) -> tuple[float, float]:
        """(min, max) angle in radians."""
        return (math.radians(self.min_deg), math.radians(self.max_deg))


@dataclass(frozen=True)
class NaoModel:
    """Bodies and joints of one robot type, resolved to the zero pose."""

    robot_type: RobotType
    bodies: tuple[Body, ...]
    joints: tuple[Joint, ...]

    @property
    def label(self) -> str:
        """How messages name the robot (``"robot type 0"``)."""
        return f"robot type {self.robot_type.index}"

    @property
    def total_mass(self) -> float:
        """Sum of all body masses, kg (4.6071 for every type)."""
        return sum(b.mass for b in self.bodies)

    @cached_property
    def effector_names(self) -> tuple[str, ...]:
        """Effector names in canonical order."""
        return tuple(j.effector for j in self.joints)

    @cached_property
    def perceptor_names(self) -> tuple[str, ...]:
        """Perceptor names in canonical order."""
        return tuple(j.perceptor for j in self.joints)

    @cached_property
    def max_speeds(self) -> np.ndarray:
        """Max joint speeds in canonical order, rad/s."""
        return np.array([j.max_speed for j in self.joints])

    @cached_property
    def mirror_pairs(self) -> tuple[tuple[int, int, float], ...]:
        """``(left index, right index, sign)`` for every left/right joint pair (``lae1``/
        ``rae1``, …), canonical indices: the right joint's angle that mirrors the left one's
        angle θ across the robot's sagittal plane (x ↦ −x, torso frame) is ``sign · θ``.

        A rotation by θ about axis ``a`` reflected by ``M = diag(−1, 1, 1)`` is a rotation by
        −θ about ``M a``; so ``sign = −a_right · M a_left`` (±1 for the Nao's joints), and the
        right joint's range is the left one's times ``sign`` (checked)."""
        index = {j.effector: i for i, j in enumerate(self.joints)}
        out = []
        for i, j in enumerate(self.joints):
            if not j.effector.startswith("l"):
                continue
            k = index.get("r" + j.effector[1:])
            if k is None:
                continue
            right = self.joints[k]
            sign = _mirror_sign(j.axis, right.axis)
            if abs(abs(sign) - 1.0) > 1e-6:
                raise ValueError(f"{j.effector}/{right.effector}: axes are not mirror images")
            lo, hi = sorted((sign * j.min_deg, sign * j.max_deg))
            if abs(lo - right.min_deg) > 1e-6 or abs(hi - right.max_deg) > 1e-6:
                raise ValueError(f"{j.effector}/{right.effector}: ranges are not mirror images")
            out.append((i, k, sign))
        return tuple(out)

    @cached_property
    def mirror_effectors(self) -> dict[str, tuple[str, float]]:
        """Every joint's mirror image across the sagittal plane, by effector name: ``(effector,
        sign)``, its twin of :attr:`mirror_pairs` with that sign, or for a joint without one
        (the head's) itself, with the sign the same rule gives its own axis (the yaw −1, the
        pitch +1)."""
        names = [j.effector for j in self.joints]
        out = {j.effector: (j.effector, _mirror_sign(j.axis, j.axis)) for j in self.joints}
        for i, k, sign in self.mirror_pairs:
            out[names[i]], out[names[k]] = (names[k], sign), (names[i], sign)
        return out

    @cached_property
    def ranges_deg(self) -> np.ndarray:
        """Joint limits in canonical order, shape (n, 2), degrees."""
        return np.array([(j.min_deg, j.max_deg) for j in self.joints])

    @cached_property
    def joint_index(self) -> dict[str, int]:
        """Canonical index of every joint by effector, perceptor and Nao-style name."""
        idx: dict[str, int] = {}
        for i, j in enumerate(self.joints):
            idx[j.effector] = i
            idx[j.perceptor] = i
            idx[j.nao_name] = i
        return idx

    def body(self, name: str) -> Body:
        """The body called ``name``.

        Raises:
            KeyError: listing the valid names.
        """
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(f"unknown body {name!r}; valid: {', '.join(b.name for b in self.bodies)}")

    def joint(self, name: str) -> Joint:
        """The joint with effector or perceptor name ``name``.

        Raises:
            KeyError: listing the valid effector names.
        """
        i = self.joint_index.get(name)
        if i is not None:
            return self.joints[i]
        raise KeyError(
            f"unknown joint {name!r}; valid effector names: {', '.join(self.effector_names)}"
        )

    def sole_height(self) -> float:
        """Height of the torso centre above flat ground at the zero pose (0.385 m for type 0)."""
        return -min(
            b.pos[2] - b.size[2] / 2 for b in self.bodies if b.shape == "box" and b.collides
        )

    def center_of_mass(self) -> np.ndarray:
        """Whole-robot centre of mass relative to the torso centre at the zero pose, m."""
        m = np.array([b.mass for b in self.bodies])
        p = np.array([b.pos for b in self.bodies])
        return (m[:, None] * p).sum(axis=0) / m.sum()


def _add(a: Vec3, b: Vec3) -> Vec3:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _side_bodies_and_joints(t: RobotType, side: str) -> tuple[list[Body], list[Joint], list[Joint]]:
    """Arm and leg of one side (``"r"`` or ``"l"``); returns bodies, leg joints, arm joints."""
    s = 1.0 if side == "r" else -1.0
    left = side == "l"
    full = "Right" if side == "r" else "Left"
    nao = "R" if side == "r" else "L"
    speed = DEFAULT_MAX_SPEED

    # --- arm (naoarm.rsg) ---
    shoulder = (s * 0.098, 0.0, 0.075)
    upperarm = _add(shoulder, (s * 0.01, 0.02, 0.0))
    elbow = _add(upperarm, (-s * 0.01, t.elbow_rel_upperarm_y, 0.009))
    lowerarm = _add(elbow, (0.0, 0.05, 0.0))
    p = side
    bodies = [
        Body(f"{p}shoulder", "torso", "sphere", (0.01, 0, 0), 0.070, shoulder, False),
        Body(f"{p}upperarm", f"{p}shoulder", "box", (0.07, 0.08, 0.06), 0.150, upperarm, True),
        Body(f"{p}elbow", f"{p}upperarm", "sphere", (0.01, 0, 0), 0.035, elbow, False),
        Body(f"{p}lowerarm", f"{p}elbow", "box", (0.05, 0.11, 0.05), 0.200, lowerarm, True),
    ]
    arm = [
        Joint(
            f"{p}ae1",
            f"{p}aj1",
            f"{full} Shoulder Pitch",
            f"{nao}ShoulderPitch",
            "torso",
            f"{p}shoulder",
            shoulder,
            (1, 0, 0),
            -120,
            120,
            speed,
        ),
        Joint(
            f"{p}ae2",
            f"{p}aj2",
            f"{full} Shoulder Yaw",
            f"{nao}ShoulderRoll",
            f"{p}shoulder",
            f"{p}upperarm",
            shoulder,
            (0, 0, 1),
            *((-1, 95) if left else (-95, 1)),
            speed,
        ),
        Joint(
            f"{p}ae3",
            f"{p}aj3",
            f"{full} Shoulder Roll",
            f"{nao}ElbowYaw",
            f"{p}upperarm",
            f"{p}elbow",
            elbow,
            (0, 1, 0),
            -120,
            120,
            speed,
        ),
        Joint(
            f"{p}ae4",
            f"{p}aj4",
            f"{full} Arm Yaw",
            f"{nao}ElbowRoll",
            f"{p}elbow",
            f"{p}lowerarm",
            elbow,
            (0, 0, 1),
            *((-90, 1) if left else (-1, 90)),
            speed,
        ),
    ]

    # --- leg (naoleg.rsg, naolegtoe.rsg) ---
    hip1 = (s * t.hip1_rel_torso_x, -0.01, t.hip1_rel_torso_z)
    hip2 = hip1
    thigh = _add(hip2, (0.0, 0.01, t.thigh_rel_hip2_z))
    shank = _add(thigh, (0.0, 0.005, -0.125))
    ankle = _add(shank, (0.0, -0.01, t.ankle_rel_shank_z))
    if t.toe_length is None:
        foot_size = (0.08, 0.16, 0.02)
        foot_mass = 0.2
        foot = _add(ankle, (0.0, 0.03, -0.04))
    else:
        foot_len = 0.16 - t.toe_length
        foot_size = (0.08, foot_len, 0.02)
        share = (t.toe_length / 0.16) / 2
        foot_mass = (1 - share) * 0.2
        foot = _add(ankle, (0.0, foot_len / 2 - 0.05, -0.04))
    knee = _add(shank, (0.0, -0.01, 0.045))
    roll_anchor = _add(foot, (0.0, -0.03, 0.035))
    bodies += [
        Body(f"{p}hip1", "torso", "sphere", (0.01, 0, 0), 0.090, hip1, False),
        Body(f"{p}hip2", f"{p}hip1", "sphere", (0.01, 0, 0), 0.125, hip2, False),
        Body(f"{p}thigh", f"{p}hip2", "box", (0.07, 0.07, 0.14), 0.275, thigh, True),
        Body(f"{p}shank", f"{p}thigh", "box", (0.08, 0.07, 0.11), 0.225, shank, True),
        Body(f"{p}ankle", f"{p}shank", "sphere", (0.01, 0, 0), 0.125, ankle, False),
        Body(f"{p}foot", f"{p}ankle", "box", foot_size, foot_mass, foot, True),
    ]
    r2 = math.sqrt(0.5)
    leg = [
        Joint(
            f"{p}le1",
            f"{p}lj1",
            f"{full} Hip YawPitch",
            f"{nao}HipYawPitch",
            "torso",
            f"{p}hip1",
            hip1,
            (-r2, 0, -r2) if left else (-r2, 0, r2),
            -90,
            1,
            speed,
        ),
        Joint(
            f"{p}le2",
            f"{p}lj2",
            f"{full} Hip Roll",
            f"{nao}HipRoll",
            f"{p}hip1",
            f"{p}hip2",
            hip2,
            (0, 1, 0),
            *((-25, 45) if left else (-45, 25)),
            speed,
        ),
        Joint(
            f"{p}le3",
            f"{p}lj3",
            f"{full} Hip Pitch",
            f"{nao}HipPitch",
            f"{p}hip2",
            f"{p}thigh",
            hip2,
            (1, 0, 0),
            -25,
            100,
            speed,
        ),
        Joint(
            f"{p}le4",
            f"{p}lj4",
            f"{full} Knee Pitch",
            f"{nao}KneePitch",
            f"{p}thigh",
            f"{p}shank",
            knee,
            (1, 0, 0),
            -130,
            1,
            speed,
        ),
        Joint(
            f"{p}le5",
            f"{p}lj5",
            f"{full} Foot Pitch",
            f"{nao}AnklePitch",
            f"{p}shank",
            f"{p}ankle",
            ankle,
            (1, 0, 0),
            -45,
            75,
            t.ankle_pitch_max_speed,
        ),
        Joint(
            f"{p}le6",
            f"{p}lj6",
            f"{full} Foot Roll",
            f"{nao}AnkleRoll",
            f"{p}ankle",
            f"{p}foot",
            roll_anchor,
            (0, 1, 0),
            *((-45, 25) if left else (-25, 45)),
            t.ankle_roll_max_speed,
        ),
    ]
    if t.toe_length is not None:
        toe = _add(foot, (0.0, 0.08, -0.005))
        share = (t.toe_length / 0.16) / 2
        bodies.append(
            Body(f"{p}toe", f"{p}foot", "box", (0.08, t.toe_length, 0.01), share * 0.2, toe, True)
        )
        leg.append(
            Joint(
                f"{p}le7",
                f"{p}lj7",
                f"{full} Toe Pitch",
                f"{nao}ToePitch",
                f"{p}foot",
                f"{p}toe",
                _add(toe, (0.0, -t.toe_length / 2, -0.005)),
                (1, 0, 0),
                -1,
                70,
                speed,
            )
        )
    return bodies, leg, arm


@cache
def nao_model(type_index: int = 0) -> NaoModel:
    """The resolved Nao of robot type ``type_index`` (0–4).

    Raises:
        ValueError: for a type outside 0–4.
    """
    t = robot_type(type_index)
    speed = DEFAULT_MAX_SPEED
    bodies = [
        Body("torso", None, "box", (0.10, 0.10, 0.18), 1.2171, (0.0, 0.0, 0.0), True),
        Body("neck", "torso", "capsule", (0.015, 0.08, 0), 0.050, (0.0, 0.0, 0.09), True),
        Body("head", "neck", "sphere", (0.065, 0, 0), 0.350, (0.0, 0.0, 0.155), True),
    ]
    head = [
        Joint(
            "he1",
            "hj1",
            "Neck Yaw",
            "HeadYaw",
            "torso",
            "neck",
            (0.0, 0.0, 0.09),
            (0, 0, 1),
            -120,
            120,
            speed,
        ),
        Joint(
            "he2",
            "hj2",
            "Neck Pitch",
            "HeadPitch",
            "neck",
            "head",
            (0.0, 0.0, 0.15),
            (1, 0, 0),
            -45,
            45,
            speed,
        ),
    ]
    rb, rleg, rarm = _side_bodies_and_joints(t, "r")
    lb, lleg, larm = _side_bodies_and_joints(t, "l")
    bodies += rb + lb
    toes = [j for j in lleg + rleg if j.effector.endswith("7")]
    joints = (
        head
        + larm
        + [j for j in lleg if j not in toes]
        + [j for j in rleg if j not in toes]
        + rarm
        + [j for j in toes if j.effector.startswith("l")]
        + [j for j in toes if j.effector.startswith("r")]
    )
    return NaoModel(t, tuple(bodies), tuple(joints))


#: Perceptor names in the order rcssserver3d 0.7.3 sends ``HJ`` predicates (spec protocol §5.11).
def wire_perceptor_order(type_index: int = 0) -> tuple[str, ...]:
    """``HJ`` names in the order the real server sends them for robot type ``type_index``."""
    toes = type_index == 4
    order = ["hj1", "hj2", "raj1", "raj2", "raj3", "raj4", "laj1", "laj2", "laj3", "laj4"]
    order += [f"rlj{i}" for i in range(1, 8 if toes else 7)]
    order += [f"llj{i}" for i in range(1, 8 if toes else 7)]
    return tuple(order)


MESH_BOUNDS: dict[str, tuple[Vec3, Vec3]] = {
    "naobody": ((-0.759925, -1.186159, -0.552179), (0.773802, 1.127901, 0.582243)),
    "naohead": ((-0.660242, -0.512208, -0.575502), (0.660242, 0.487792, 0.544406)),
    "upperarm": ((-0.540651, -1.024425, -0.591468), (0.667725, 0.962256, 0.591468)),
    "lowerarm": ((-0.615816, -1.32, -0.592188), (0.615816, 1.43392, 0.728086)),
    "thigh": ((-0.699674, -0.73527, -1.17803), (0.815795, 0.744477, 1.392327)),
    "shank": ((-0.607233, -0.656782, -1.076334), (0.759024, 0.687822, 1.022094)),
    "foot": ((-0.550013, -1.100003, -0.250012), (0.550022, 1.1, 0.539233)),
}
"""The bounds of the vertices of rcssserver3d's visual models of the Nao (``models/*.obj``, file
units, the right side's; the left side's are mirrored in x). The server's bounding box of a
robot, which its referee tests a safe spot against, is the union of these models' boxes as
the rsg scales and turns them on each part (:meth:`NaoModel.mesh_boxes`)."""


def _mesh_box(name: str, scale: Vec3, left: bool, turned: bool) -> tuple[np.ndarray, np.ndarray]:
    lo, hi = (np.asarray(v, dtype=float) * scale for v in MESH_BOUNDS[name])
    if turned:  # the rsg's (setLocalRotation -90 0 180): model (x, y, z) -> part (-x, z, y)
        lo, hi = np.array([-hi[0], lo[2], lo[1]]), np.array([-lo[0], hi[2], hi[1]])
    if left:
        lo, hi = np.array([-hi[0], lo[1], lo[2]]), np.array([-lo[0], hi[1], hi[2]])
    return lo, hi


@cache
def mesh_boxes(type_index: int) -> tuple[tuple[int, np.ndarray, np.ndarray], ...]:
    """Each visual model of a Nao of type ``type_index`` as ``(body index, low corner, high
    corner)`` of its box in that body's frame (m): the torso and the head (scale 0.1, turned),
    upper and lower arms (0.07, 0.05), thighs (0.07), shanks and feet (0.08); a type-4 foot and
    toe show the foot model scaled to their lengths (naolegtoe.rsg)."""
    model = nao_model(type_index)
    index = {b.name: k for k, b in enumerate(model.bodies)}
    out: list[tuple[int, np.ndarray, np.ndarray]] = []
    out.append((index["torso"], *_mesh_box("naobody", (0.1,) * 3, False, True)))
    out.append((index["head"], *_mesh_box("naohead", (0.1,) * 3, False, True)))
    toe = model.robot_type.toe_length
    for p in ("r", "l"):
        left = p == "l"
        for part, scale in (
            ("upperarm", 0.07),
            ("lowerarm", 0.05),
            ("thigh", 0.07),
            ("shank", 0.08),
        ):
            out.append((index[p + part], *_mesh_box(part, (scale,) * 3, left, False)))
        if toe is None:
            out.append((index[p + "foot"], *_mesh_box("foot", (0.08,) * 3, left, False)))
        else:
            foot_len = 0.16 - toe
            foot_scale = (0.08, 0.08 * foot_len / 0.16, 0.08)
            toe_scale = (0.08, 0.08 * toe / foot_len, 0.08 * 0.01 / 0.02)
            out.append((index[p + "foot"], *_mesh_box("foot", foot_scale, left, False)))
            out.append((index[p + "toe"], *_mesh_box("foot", toe_scale, left, False)))
    return tuple(out)

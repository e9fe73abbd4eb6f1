"""The two types every backend shares: what a robot perceives and what it commands.

An environment talks to a simulator only through these: :class:`Perception` (one robot's view of
one 20 ms cycle, in SimSpark's units and frames) and :class:`AgentCommand` (what the robot's agent
sends for one cycle). The embedded MuJoCo world, the real rcssserver3d backend and the protocol
parser all produce and consume exactly these types, so an environment never knows which simulator
is behind it.

Units (as on the rcssserver3d wire):

* joint angles in **degrees**, joint velocity commands in **rad/s**;
* gyro in **deg/s**, accelerometer in **m/s²**, both in the torso frame
  (x = robot's right, y = robot's forward, z = up);
* foot force sensors: point in **m** and force in **N**, in the foot (toe) body frame;
* vision: polar ``(distance m, horizontal deg, vertical deg)`` relative to the head;
* ground truth: world frame (origin field centre, x towards the right team's goal, z up), metres,
  m/s, rad/s, quaternions ``(w, x, y, z)``.

The checks every configuration dataclass shares (unknown fields, values of the wrong kind) are
here too.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

__all__ = [
    "PLAY_MODES",
    "AgentCommand",
    "ForceResistance",
    "GameState",
    "GroundTruth",
    "HeardMessage",
    "PDCommand",
    "Perception",
    "SeenPlayer",
    "Vision",
    "check_field_kinds",
    "float_array",
    "is_integer",
    "is_names",
    "is_number",
    "reject_unknown_fields",
]


@dataclass
class ForceResistance:
    """One foot (``lf``/``rf``) or toe (``lf1``/``rf1``) pressure sensor reading (``FRP``).

    Present only in cycles in which that foot or toe touched something.
    """

    point: np.ndarray
    """Centre of pressure ``c`` in m, in the foot's own frame (origin at the foot box centre)."""
    force: np.ndarray
    """Total contact force ``f`` on the foot in N, foot frame (z ≈ +22.6 N when standing)."""


PLAY_MODES: tuple[str, ...] = (
    "BeforeKickOff",
    "KickOff_Left",
    "KickOff_Right",
    "PlayOn",
    "KickIn_Left",
    "KickIn_Right",
    "corner_kick_left",
    "corner_kick_right",
    "goal_kick_left",
    "goal_kick_right",
    "offside_left",
    "offside_right",
    "GameOver",
    "Goal_Left",
    "Goal_Right",
    "free_kick_left",
    "free_kick_right",
    "direct_free_kick_left",
    "direct_free_kick_right",
    "pass_left",
    "pass_right",
)
"""Play-mode names by numeric id (agents and trainers use names, monitors ids); case-sensitive."""


@dataclass
class GameState:
    """The ``GS`` perceptor: score, game clock and play mode."""

    play_mode: str = "BeforeKickOff"
    """Play-mode name as on the wire (``BeforeKickOff``, ``PlayOn``, ``KickOff_Left``, …)."""
    game_time: float = 0.0
    """Match clock ``t`` in s (stops in BeforeKickOff and GameOver)."""
    score_left: int = 0
    score_right: int = 0
    unum: int | None = None
    """Uniform number; the server sends it only once, in the first GS after ``init``."""
    team_side: str | None = None
    """``"left"`` or ``"right"``; sent only once, like :attr:`unum`."""


@dataclass
class HeardMessage:
    """One ``hear`` predicate."""

    team: str | None
    """Team name of the speaker (``None`` when the server does not label messages)."""
    time: float
    """Game time in s when heard."""
    direction_deg: float | None
    """Direction to the speaker in the listener's team frame, deg; ``None`` for the own message."""
    message: str

    @property
    def is_self(self) -> bool:
        """True for the robot's own message (``self`` on the wire)."""
        return self.direction_deg is None


@dataclass
class SeenPlayer:
    """A player in the ``See`` perceptor (team-mates, opponents and the robot's own parts)."""

    team: str
    unum: int
    parts: dict[str, np.ndarray] = field(default_factory=dict)
    """Visible parts (``head``, ``rlowerarm``, ``llowerarm``, ``rfoot``, ``lfoot``) → polar
    ``(d m, θ deg, φ deg)``."""


@dataclass
class Vision:
    """The ``See`` perceptor: restricted vision, every third cycle."""

    objects: dict[str, np.ndarray] = field(default_factory=dict)
    """Landmarks and ball (``B``, ``F1L``, ``G2R``, …) → polar ``(d m, θ deg, φ deg)``; θ > 0 is
    to the robot's left, φ > 0 is up, both relative to the head."""
    players: list[SeenPlayer] = field(default_factory=list)
    lines: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 3)))
    """Visible field lines, shape ``(n, 2, 3)``: two polar end points per line."""
    my_pos: np.ndarray | None = None
    """Ground-truth extension ``mypos``: head centre in the team frame, m (only when enabled)."""
    my_orientation_deg: float | None = None
    """Ground-truth extension ``myorien``: heading of the head in the team frame, deg."""
    ball_pos: np.ndarray | None = None
    """Ground-truth extension ``ballpos``: ball centre in the team frame, m."""

    @property
    def ball(self) -> np.ndarray | None:
        """Polar position of the ball, or ``None`` when it is not in view."""
        return self.objects.get("B")


@dataclass
class GroundTruth:
    """Exact world state for rewards, tests and logging (never sent to competition agents).

    All in the world frame (not team-mirrored).
    """

    ball_pos: np.ndarray
    """Ball centre, m."""
    ball_vel: np.ndarray
    """Ball linear velocity, m/s."""
    torso_pos: np.ndarray
    """Torso centre, m."""
    torso_quat: np.ndarray
    """Torso orientation ``(w, x, y, z)`` of the torso frame (x right, y forward, z up)."""
    torso_vel: np.ndarray | None = None
    """Torso linear velocity, m/s (``None`` where the backend cannot measure it)."""
    torso_ang_vel: np.ndarray | None = None
    """Torso angular velocity in the world frame, rad/s (``None`` where unknown)."""
    feet_contact: dict[str, bool] | None = None
    """Whether the left (``"lf"``) and right (``"rf"``) foot touch the ground, for robots
    without foot pressure perceptors (the league's); ``None``: read the ``FRP`` perceptors."""


@dataclass
class Perception:
    """Everything one robot perceives in one cycle, as rcssserver3d would send it.

    ``joint_names`` / ``joint_angles_deg`` use the perceptor names (``hj1``, ``raj1``, …,
    ``llj7``) in the robot's canonical order (see :mod:`robocup_gym.robot.joints`).
    """

    time: float
    """Simulation time ``(time (now …))`` in s since the server started."""
    game: GameState
    gyro: np.ndarray
    """Torso angular velocity in deg/s, torso frame (``GYR``)."""
    accel: np.ndarray
    """Torso proper acceleration in m/s², torso frame (``ACC``); ≈ (0, 0, 9.81) at rest."""
    joint_names: tuple[str, ...]
    """Perceptor names of the joints, in the order of :attr:`joint_angles_deg`."""
    joint_angles_deg: np.ndarray
    """Hinge angles in degrees (``HJ``)."""
    joint_velocities_deg_s: np.ndarray | None = None
    """Joint velocities in deg/s where the simulator sends them (RCSSServerMJ's ``HJ … (vx …)``;
    rcssserver3d sends none: ``None``)."""
    force_sensors: dict[str, ForceResistance] = field(default_factory=dict)
    """``FRP`` by name (``lf``, ``rf``, ``lf1``, ``rf1``); a missing name means no contact."""
    vision: Vision | None = None
    """``See`` (every third cycle), else ``None``."""
    heard: list[HeardMessage] = field(default_factory=list)
    ground_truth: GroundTruth | None = None
    """Exact state when the backend knows it (always on the embedded world)."""

    def joint(self, name: str) -> float:
        """Angle in degrees of the joint with perceptor name ``name`` (e.g. ``"rlj3"``).

        Raises:
            KeyError: for an unknown name, listing the valid ones.
        """
        try:
            return float(self.joint_angles_deg[self.joint_names.index(name)])
        except ValueError:
            raise KeyError(
                f"unknown joint perceptor {name!r}; valid names: {', '.join(self.joint_names)}"
            ) from None


@dataclass(frozen=True)
class PDCommand:
    """One joint's command on RCSSServerMJ (the league's robots), in the wire's units:
    ``(<name> q dq kp kd tau)``. The simulator applies ``kp (q − q_now) + kd (dq − dq_now) + tau``
    (angles converted to rad), clamped to the actuator's torque range."""

    q_deg: float
    """Target angle, degrees."""
    dq_deg_s: float = 0.0
    """Target velocity, degrees per second."""
    kp: float = 0.0
    """Proportional gain, N·m per rad."""
    kd: float = 0.0
    """Derivative gain, N·m·s per rad."""
    tau: float = 0.0
    """Feed-forward torque, N·m."""

    def __post_init__(self) -> None:
        for f in ("q_deg", "dq_deg_s", "kp", "kd", "tau"):
            v = getattr(self, f)
            if not math.isfinite(v):
                raise ValueError(f"joint command {f} must be finite, got {v}")


@dataclass
class AgentCommand:
    """What one agent sends in one cycle.

    ``joint_velocities`` maps effector names (``he1``, ``rle3``, …) to target angular velocities in
    **rad/s** (the Nao on rcssserver3d). As on rcssserver3d, targets are sticky: joints not named
    keep their previous target. A full array in the robot's canonical effector order is also
    accepted. ``joint_pd`` is the league robots' form (RCSSServerMJ): effector name →
    :class:`PDCommand`, also sticky.
    """

    joint_velocities: Mapping[str, float] | np.ndarray = field(default_factory=dict)
    joint_pd: Mapping[str, PDCommand] | None = None
    """PD joint commands by effector name (league robots); ``None``: none this cycle."""
    beam: tuple[float, float, float] | None = None
    """``(x m, y m, rot deg)`` in the team frame; only honoured before kick-off and after goals."""
    say: str | None = None
    """At most 20 printable characters, no spaces or parentheses."""


def reject_unknown_fields(
    cls: type, names, what: str, plural: str, error: type[Exception] = ValueError
) -> None:
    """Raise ``error`` naming the ``names`` that are not fields of the dataclass ``cls`` and
    listing the ones that are: ``unknown {what}(s) a, b; {plural}: x, y, z``."""
    known = {f.name for f in fields(cls)}
    unknown = sorted(set(names) - known)
    if unknown:
        raise error(f"unknown {what}(s) {', '.join(unknown)}; {plural}: {', '.join(sorted(known))}")


def is_number(v: Any) -> bool:
    """Whether ``v`` is a real number (Python's or numpy's), not a flag."""
    return isinstance(v, numbers.Real) and not isinstance(v, bool | np.bool_)


def float_array(v: Any) -> np.ndarray | None:
    """``v`` as a float array, or ``None`` where it is text or not numbers (numpy would read
    the text ``"1.5"`` as a number, and fail with its own words on others)."""
    if isinstance(v, str | bytes):
        return None
    try:
        return np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        return None


def is_names(v: Any) -> bool:
    """Whether ``v`` is a sequence of names (a list or tuple of texts, not one text)."""
    return (
        not isinstance(v, str | bytes)
        and isinstance(v, Sequence)
        and all(isinstance(x, str) for x in v)
    )


def _numbers(n: int) -> Callable[[Any], bool]:
    def check(v: Any) -> bool:
        if isinstance(v, str | bytes) or not isinstance(v, Sequence | np.ndarray):
            return False
        return len(v) == n and all(is_number(x) for x in v)

    return check


def is_integer(v: Any) -> bool:
    """Whether ``v`` is an integer (Python's or numpy's), not a flag."""
    return is_number(v) and isinstance(v, numbers.Integral)


FIELD_KINDS: dict[str, tuple[str, Callable[[Any], bool]]] = {
    "float": ("a number", is_number),
    "float | None": ("a number or None", lambda v: v is None or is_number(v)),
    "int": ("an integer", is_integer),
    "bool": ("true or false", lambda v: isinstance(v, bool | np.bool_)),
    "str": ("a name", lambda v: isinstance(v, str)),
    "str | None": ("a name or None", lambda v: v is None or isinstance(v, str)),
    "tuple[float, float]": ("2 numbers", _numbers(2)),
    "tuple[float, float, float]": ("3 numbers", _numbers(3)),
    "tuple[str, ...]": ("a list of names", is_names),
    "tuple[str, ...] | None": ("a list of names or None", lambda v: v is None or is_names(v)),
    "float | Mapping[str, float]": (
        "a number or a mapping of names to numbers",
        lambda v: (
            is_number(v)
            or (isinstance(v, Mapping) and is_names(list(v)) and all(map(is_number, v.values())))
        ),
    ),
    "Mapping[str, Any]": ("a mapping of names to values", lambda v: isinstance(v, Mapping)),
    "dict[str, Any]": ("a mapping of names to values", lambda v: isinstance(v, Mapping)),
}
"""What a dataclass field of each annotation (as written) holds, and how an error names it;
:func:`check_field_kinds` checks the fields of these annotations (the others are their class's
to check)."""


def check_field_kinds(
    obj: Any, error: type[Exception] = ValueError, skip: Collection[str] = ()
) -> None:
    """Raise ``error`` for the first field of the dataclass ``obj`` that holds a value of
    another kind than its annotation says (:data:`FIELD_KINDS`; annotations in ``skip`` are
    left to the class): ``{field} must be {kind}, got {value!r}``. A text where a number
    belongs (``--env guide_speed=fast``, a config file's ``timesteps: 1e6``), say, or the text
    ``"false"`` for a flag, which would read as true."""
    for f in fields(obj):
        annotation = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", "")
        if annotation in skip:
            continue
        kind = FIELD_KINDS.get(annotation)
        if kind is not None and not kind[1](getattr(obj, f.name)):
            raise error(f"{f.name} must be {kind[0]}, got {getattr(obj, f.name)!r}")

"""The MuJoCo world against the ODE reference on a library of scripted motions.

A :class:`Motion` is what ``kick_D.json`` is: a placement and a sequence of blocks of joint
velocity commands (rad/s, all joints sent every cycle, unlisted ones 0). :func:`compare` replays
it on :class:`robocup_gym.sim.engines.mujoco.world.World` and on
:class:`robocup_gym.sim.engines.ode.OdeWorld` and
measures how far the two drift apart (torso, joints, ball, cycle by cycle). ``MOTIONS`` covers
what the real server's fixtures do not: standing, squatting, arm swings, joints driven into their
stops, the kick, falls, a rolling ball and random flailing. ``benchmarks/ode_compare.py`` prints
the table. :class:`record_world` and :func:`replay_recording` do the same for any episode of an
environment (a trained policy's, ``benchmarks/ode_transfer.py``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from robocup_gym.robot.nao import nao_model
from robocup_gym.sim.fidelity import load_data

Block = tuple[int, dict[str, float]]
"""(cycles, {effector: rad/s}) — one block of a scripted motion."""


@dataclass(frozen=True)
class Motion:
    """A scripted open-loop motion of one robot (type ``robot_type``) facing +x at (−1, 0)."""

    name: str
    blocks: tuple[Block, ...]
    robot_type: int = 0
    asleep: bool = False
    """Start hanging asleep at z = 0.385 m, as the real server leaves a moved robot (kick D)."""
    ball: tuple[float, float] = (5.0, 5.0)
    """Ball start (x, y), resting on the ground."""
    ball_velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    description: str = ""

    @property
    def cycles(self) -> int:
        """Length of the motion in 20 ms cycles."""
        return sum(n for n, _ in self.blocks)


def _kick_d() -> Motion:
    spec = load_data("kick_D.json")
    blocks = tuple(
        (int(b["cycles"]), dict(b["velocities_rad_per_s"])) for b in spec["command_sequence"]
    )
    start = spec["ball_start"]
    return Motion(
        "kick_D",
        blocks,
        asleep=True,
        ball=(start[0], start[1]),
        description="the real server's scripted kick (kick_D.json)",
    )


def _random_flail(seed: int, cycles: int = 150, hold: int = 5, scale: float = 0.5) -> Motion:
    """Random joint velocities (uniform within ``scale`` × max speed), each held ``hold`` cycles."""
    model = nao_model(0)
    rng = np.random.default_rng(seed)
    blocks = []
    for _ in range(cycles // hold):
        v = rng.uniform(-1, 1, len(model.joints)) * model.max_speeds * scale
        blocks.append((hold, {n: float(x) for n, x in zip(model.effector_names, v, strict=True)}))
    return Motion(
        f"flail_{seed}",
        tuple(blocks),
        description=f"random velocities ≤ {scale:g}·max, held {hold} cycles (seed {seed})",
    )


def _both(side_value: dict[str, float]) -> dict[str, float]:
    """Apply leg/arm commands given for the right side to both sides, mirrored: the joints
    whose ranges are mirrored between the sides (hip and ankle roll, shoulder yaw, elbow roll
    and yaw; reference §2.1) change sign."""
    out = dict(side_value)
    for name, v in side_value.items():
        if name[0] == "r":
            mirrored = name[-1] in "26" if name[1:3] == "le" else name[-1] in "234"
            out["l" + name[1:]] = -v if mirrored else v
    return out


def motions() -> tuple[Motion, ...]:
    """The comparison library (see the module docstring)."""
    v = 2.0
    return (
        Motion("stand", ((150, {}),), description="all joint velocities 0 for 3 s"),
        _kick_d(),
        Motion(
            "squat",
            (
                (10, {}),
                (20, _both({"rle3": v, "rle4": -2 * v, "rle5": v})),
                (20, _both({"rle3": -v, "rle4": 2 * v, "rle5": -v})),
                (50, {}),
            ),
            description="hips, knees and ankles bend together and stretch back (2 rad/s)",
        ),
        Motion(
            "arm_swing",
            (
                *(
                    blk
                    for _ in range(3)
                    for blk in (
                        (10, _both({"rae1": -6.0, "rae2": -3.0})),
                        (10, _both({"rae1": 6.0, "rae2": 3.0})),
                    )
                ),
                (40, {}),
            ),
            description="both arms swing at full speed, three times",
        ),
        Motion(
            "stops",
            (
                (10, {}),
                (25, {"lae1": 6.0, "rae1": 6.0, "he1": 6.0, "he2": -6.0, "rae4": 6.0}),
                (25, {"lae1": -6.0, "rae1": -6.0, "he1": -6.0, "he2": 6.0, "rae4": -6.0}),
                (40, {}),
            ),
            description="arms, neck and elbow driven into their stops and back at full speed",
        ),
        Motion(
            "fall_forward",
            ((5, {}), (15, _both({"rle5": -3.0})), (80, {})),
            description="both ankles pitch the robot forward onto its arms and chest",
        ),
        Motion(
            "ball_roll",
            ((100, {}),),
            ball=(0.0, 2.0),
            ball_velocity=(2.5, 0.0, 0.0),
            description="the ball launched along the ground at 2.5 m/s",
        ),
        _random_flail(0),
        _random_flail(1),
        _random_flail(2),
    )


@dataclass
class Trace:
    """What a world did during a motion, one row per cycle."""

    torso: list = field(default_factory=list)
    up: list = field(default_factory=list)
    joints: list = field(default_factory=list)
    ball: list = field(default_factory=list)

    def arrays(self) -> tuple[np.ndarray, ...]:
        """``(torso (n, 3) m, up (n, 3), joints (n, J) deg, ball (n, 3) m)``."""
        return tuple(np.array(x) for x in (self.torso, self.up, self.joints, self.ball))


def replay(motion: Motion, world) -> Trace:
    """Run ``motion`` on ``world`` (a ``World`` or ``OdeWorld`` with one robot of the motion's
    type) and record it."""
    model = nao_model(motion.robot_type)
    names = model.effector_names
    if motion.asleep:
        world.place_robot(0, x=-1.0, y=0.0, z=0.385, heading_deg=0.0, asleep=True)
    else:
        world.place_robot(0, x=-1.0, y=0.0, heading_deg=0.0)
    world.place_ball(motion.ball, vel=motion.ball_velocity)
    trace = Trace()
    for cycles, velocities in motion.blocks:
        cmd = np.zeros(len(names))
        for name, v in velocities.items():
            cmd[names.index(name)] = v
        for _ in range(cycles):
            world.step({0: cmd})
            trace.torso.append(world.torso_position(0))
            trace.up.append(world.torso_up(0))
            trace.joints.append(world.joint_angles_deg(0))
            trace.ball.append(world.ball_position())
    return trace


@dataclass
class Comparison:
    """How far the MuJoCo world's replay of a motion is from the ODE reference's."""

    motion: str
    cycles: int
    torso_final_m: float
    """Distance between the two torso centres at the end, m."""
    torso_max_m: float
    tilt_final_deg: float
    """Angle between the two torsos' up axes at the end, degrees."""
    joints_rms_deg: float
    """RMS over cycles and joints of the joint-angle difference, degrees."""
    ball_final_m: float
    ball_travel_m: tuple[float, float]
    """Distance the ball travelled on the ground (MuJoCo, ODE), m."""
    diverged_cycle: int | None
    """First cycle at which the torsos are more than 1 cm apart (``None``: never)."""
    fell: tuple[bool, bool]
    """Whether the robot ended on the ground (torso up-axis z < 0.5) in (MuJoCo, ODE)."""

    def row(self) -> dict:
        """The comparison as a JSON-ready dict."""
        return {k: (round(v, 4) if isinstance(v, float) else v) for k, v in self.__dict__.items()}


def compare_traces(motion: Motion, mj: Trace, ref: Trace) -> Comparison:
    """Distances between two replays of ``motion``."""
    t1, u1, j1, b1 = mj.arrays()
    t2, u2, j2, b2 = ref.arrays()
    dist = np.linalg.norm(t1 - t2, axis=1)
    off = np.nonzero(dist > 0.01)[0]
    cos = float(np.clip(np.dot(u1[-1], u2[-1]), -1.0, 1.0))
    start = np.array(motion.ball)
    return Comparison(
        motion=motion.name,
        cycles=len(dist),
        torso_final_m=float(dist[-1]),
        torso_max_m=float(dist.max()),
        tilt_final_deg=math.degrees(math.acos(cos)),
        joints_rms_deg=float(np.sqrt(np.mean((j1 - j2) ** 2))),
        ball_final_m=float(np.linalg.norm(b1[-1] - b2[-1])),
        ball_travel_m=(
            float(np.linalg.norm(b1[-1, :2] - start)),
            float(np.linalg.norm(b2[-1, :2] - start)),
        ),
        diverged_cycle=int(off[0]) + 1 if len(off) else None,
        fell=(bool(u1[-1, 2] < 0.5), bool(u2[-1, 2] < 0.5)),
    )


def compare(
    motion: Motion,
    make_world: Callable | None = None,
    make_reference: Callable | None = None,
) -> Comparison:
    """Replay ``motion`` on a MuJoCo world and on the ODE reference and compare them.

    ``make_world(robot_types)`` / ``make_reference(robot_types)`` build the two worlds (default:
    ``World`` and ``OdeWorld`` with their defaults)."""
    from robocup_gym.sim.engines.mujoco.world import World
    from robocup_gym.sim.engines.ode.world import OdeWorld

    types = [motion.robot_type]
    mj = replay(motion, (make_world or World)(types))
    reference = (make_reference or OdeWorld)(types)
    try:
        ref = replay(motion, reference)
    finally:
        reference.close()
    return compare_traces(motion, mj, ref)


# ------------------------------------------------------------------ recorded episodes
@dataclass
class WorldRecording:
    """Everything a ``World`` was told during an episode, in order: placements, commands and
    per-cycle joint commands (canonical arrays, rad/s, NaN = joint not commanded), so that the same
    episode can be replayed open-loop on another world (:func:`replay_recording`)."""

    calls: list = field(default_factory=list)

    @property
    def cycles(self) -> int:
        """Number of 20 ms cycles recorded."""
        return sum(1 for kind, _ in self.calls if kind == "step")


class record_world:  # noqa: N801 (used as a context manager, like contextlib's helpers)
    """Record what ``world`` is told while the ``with`` block runs (the world behaves exactly as
    without the recording)::

        with record_world(env.unwrapped.backend.world) as rec:
            ...  # run an episode
        replay_recording(rec, OdeWorld([0]))
    """

    def __init__(self, world) -> None:
        self.world = world
        self.recording = WorldRecording()

    def __enter__(self) -> WorldRecording:
        w, calls = self.world, self.recording.calls
        step, command = w.step, w.command
        place_robot, place_ball = w.place_robot, w.place_ball

        def recording_command(index, cmd):
            velocities = getattr(cmd, "joint_velocities", cmd)
            copied = dict(velocities) if isinstance(velocities, dict) else np.array(velocities)
            calls.append(("command", (index, copied)))
            return command(index, cmd)

        def recording_step(commands=None):
            arrays = {}
            for i, c in (commands or {}).items():
                if c is not None:
                    velocities = getattr(c, "joint_velocities", c)
                    arrays[i] = w.command_array(i, velocities).copy()
            calls.append(("step", arrays))
            return step(commands)

        def recording_place_robot(index, x, y, **kwargs):
            keep = ("heading_deg", "z", "joint_angles_deg", "asleep")
            calls.append(("robot", (index, x, y, {k: v for k, v in kwargs.items() if k in keep})))
            return place_robot(index, x, y, **kwargs)

        def recording_place_ball(pos, vel=(0.0, 0.0, 0.0), angular_vel=(0.0, 0.0, 0.0), **kwargs):
            calls.append(("ball", (tuple(pos), tuple(vel))))
            return place_ball(pos, vel, angular_vel, **kwargs)

        w.step, w.command, w.place_robot, w.place_ball = (
            recording_step,
            recording_command,
            recording_place_robot,
            recording_place_ball,
        )
        return self.recording

    def __exit__(self, *exc) -> None:
        for name in ("step", "command", "place_robot", "place_ball"):
            del self.world.__dict__[name]


def replay_recording(recording: WorldRecording, world, on_cycle: Callable | None = None) -> None:
    """Replay ``recording`` open-loop on ``world`` (a ``World`` or ``OdeWorld``): the same
    placements and the same commands in the same cycles. ``on_cycle(world)`` after each."""
    for kind, arg in recording.calls:
        if kind == "robot":
            index, x, y, kwargs = arg
            world.place_robot(index, x, y, **kwargs)
        elif kind == "ball":
            pos, vel = arg
            world.place_ball(pos, vel=vel)
        elif kind == "command":
            index, velocities = arg
            world.command(index, velocities)
        else:
            world.step(arg)
            if on_cycle is not None:
                on_cycle(world)

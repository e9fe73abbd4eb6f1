"""The kicks TargetKick-v1 plays: a library of open-loop Nao kicks, each searched for a distance
and a direction, with where each lands on every Nao type, and the choice of one for a command.

``python benchmarks/kick_landings.py --write`` measures every kick of the library on every Nao
type again and writes ``robocup_gym/data/commanded_kick_landings.json`` (a few minutes); run it
after a change to the kicks or to the physics.
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from robocup_gym.envs.config import EnvConfig
from robocup_gym.envs.tasks.long_kick import (
    LONG_KICK_BALL_START_POS,
    LONG_KICK_KEYFRAMES,
    LONG_KICK_KEYFRAMES_BY_TYPE,
)
from robocup_gym.envs.tasks.reference_kick import Keyframes, mirror_keyframes
from robocup_gym.robot.types import TYPE_NUMBERS

__all__ = [
    "KICK_DIRECTION_TOLERANCE_DEG",
    "KICK_DISTANCE_TOLERANCE",
    "CommandedKick",
    "choose_kick",
    "commanded_kick",
    "kick_landings",
    "kick_library",
    "landing_cost",
    "measure_landings",
    "write_landings",
]

KICK_DISTANCE_TOLERANCE = 0.15
"""The distance error (a fraction of the command) that counts as one unit of miss."""
KICK_DIRECTION_TOLERANCE_DEG = 5.0
"""The direction error, deg, that counts as one unit of miss."""
_FALL_COST = 25.0
"""Added times the share of landings after which the robot was down."""
LANDING_EPISODES = 8
"""Kicks measured per kick and Nao type."""
MEASURED_ON = "RobocupGym/TargetKick-v1"
"""The environment whose settings the landings are measured on (its ball spawn noise among
them), with the kick under test instead of the command's."""
_LANDING_SEED = 10_000
_LANDINGS_FILE = "commanded_kick_landings.json"


@dataclass(frozen=True)
class CommandedKick:
    """One kick of the library: a right-foot kick for a robot at the default start
    (:attr:`EnvConfig.robot_start_pos`, heading 0) in the crouched standing pose."""

    aim: tuple[float, float]
    """The distance (m) and direction (deg from the heading, CCW positive) it was searched
    for; where it lands is measured (:func:`kick_landings`)."""
    keyframes: Keyframes
    """Target-angle offsets (deg) by effector at keyframe times (s), as ``kick_keyframes``."""
    ball_spot: tuple[float, float]
    """Where the ball lies for it, world x/y, m."""
    keyframes_by_type: tuple[tuple[int, Keyframes], ...] = ()
    """Nao types that play a kick of their own instead of :attr:`keyframes`."""
    robot_types: tuple[int, ...] = TYPE_NUMBERS
    """The Nao types it is made for (searched on those alone when not all)."""

    def keyframes_for(self, robot_type: int) -> Keyframes:
        return dict(self.keyframes_by_type).get(robot_type, self.keyframes)

    @property
    def key(self) -> str:
        """``distance/direction`` of its aim, ``/type N`` added for a kick made for one type."""
        types = (
            ""
            if self.robot_types == TYPE_NUMBERS
            else "/type " + ",".join(map(str, self.robot_types))
        )
        return f"{self.aim[0]:g}/{self.aim[1]:g}{types}"


@functools.cache
def kick_library() -> tuple[CommandedKick, ...]:
    """Every kick of ``robocup_gym/data/commanded_kicks.json``, found by CMA-ES on the default
    engine from the long kick (:data:`~robocup_gym.envs.tasks.long_kick.LONG_KICK_KEYFRAMES`,
    the library's 10 m, 0° kick, which type 4 plays its own of) or from a neighbour, and the
    long kick itself."""
    text = resources.files("robocup_gym.data").joinpath("commanded_kicks.json").read_text()
    kicks = [
        CommandedKick(
            aim=(float(k["distance_m"]), float(k["direction_deg"])),
            keyframes=tuple((float(t), dict(offsets)) for t, offsets in k["keyframes"]),
            ball_spot=(float(k["ball_start_pos"][0]), float(k["ball_start_pos"][1])),
            robot_types=tuple(k.get("robot_types", TYPE_NUMBERS)),
        )
        for k in json.loads(text)["kicks"]
    ]
    kicks.append(
        CommandedKick(
            aim=(10.0, 0.0),
            keyframes=LONG_KICK_KEYFRAMES,
            ball_spot=LONG_KICK_BALL_START_POS,
            keyframes_by_type=tuple(sorted(LONG_KICK_KEYFRAMES_BY_TYPE.items())),
        )
    )
    return tuple(kicks)


@functools.cache
def kick_landings() -> dict[int, dict[str, np.ndarray]]:
    """Where each kick of the library lands, by Nao type and kick (:attr:`CommandedKick.key`):
    one row per measured kick, (distance m, direction deg from the heading, 1.0 if the robot was
    down 1 s later else 0.0), :data:`LANDING_EPISODES` of them, measured by
    :func:`measure_landings`."""
    text = resources.files("robocup_gym.data").joinpath(_LANDINGS_FILE).read_text()
    return {
        int(t): {key: np.asarray(rows, dtype=float) for key, rows in by_kick.items()}
        for t, by_kick in json.loads(text)["landings"].items()
    }


@functools.cache
def _kicks_for(robot_type: int) -> tuple[tuple[CommandedKick, ...], np.ndarray | None]:
    """The library's kicks made for ``robot_type`` and their landings on it, stacked (kick,
    landing, (distance, direction, down)), for :func:`choose_kick`; ``None`` landings for a
    type the table does not have."""
    by_kick = kick_landings().get(robot_type)
    if by_kick is None:
        return (), None
    kicks = tuple(k for k in kick_library() if robot_type in k.robot_types)
    return kicks, np.stack([by_kick[k.key] for k in kicks])


def landing_cost(
    landings: np.ndarray, distance_m: float, direction_deg: float | np.ndarray
) -> np.ndarray:
    """The median miss of ``landings`` (..., landing, 3) against a command, in units of the
    tolerances, and the cost of its falls: one number per set of landings (``direction_deg``
    may hold one direction per set)."""
    d, a, down = landings[..., 0], landings[..., 1], landings[..., 2]
    direction = np.asarray(direction_deg, dtype=float)[..., None]
    miss = ((d - distance_m) / (distance_m * KICK_DISTANCE_TOLERANCE)) ** 2 + (
        (a - direction) / KICK_DIRECTION_TOLERANCE_DEG
    ) ** 2
    return np.median(miss, axis=-1) + _FALL_COST * np.mean(down, axis=-1)


def commanded_kick(
    distance_m: float, direction_deg: float, robot_type: int = 0
) -> tuple[Keyframes, tuple[float, float]]:
    """The kick for a command and where the ball must lie for it.

    Of the library's kicks made for this Nao type (:func:`kick_library`) and their mirror
    images (the left foot kicks, :func:`~robocup_gym.envs.tasks.reference_kick.mirror_keyframes`,
    the ball's spot mirrored too; a mirrored kick lands at the mirrored angle), the one whose
    landings measured on this Nao type (:func:`kick_landings`) miss the command least: the
    median over its landings of (distance error / (15 % of the command))² + (direction error /
    5°)², plus 25 times the share of them after which the robot was down (:func:`choose_kick`).
    Kicks are not blended: a kick is sharp, and blends of two kicks missed by more than either.

    Args:
        distance_m: Commanded distance, m (the library spans about 1.5–10).
        direction_deg: Commanded direction, deg from the robot's heading, CCW positive (±45).
        robot_type: The Nao type (0–4).

    Returns:
        (keyframes, (x, y)): the kick as ``kick_keyframes`` are written (time s, offsets deg by
        effector) and the ball's spot, m, world frame, for a robot at the default start
        (:attr:`EnvConfig.robot_start_pos`, heading 0).

    Raises:
        ValueError: for a distance or direction that is not a finite number, a distance that is
            not positive, or a robot type that is not a Nao type.
    """
    kick, mirrored, _ = choose_kick(distance_m, direction_deg, robot_type)
    keyframes, (x, y) = kick.keyframes_for(robot_type), kick.ball_spot
    if mirrored:
        return mirror_keyframes(keyframes, robot_type), (x, 2.0 * EnvConfig.robot_start_pos[1] - y)
    return keyframes, (x, y)


def choose_kick(
    distance_m: float, direction_deg: float, robot_type: int = 0
) -> tuple[CommandedKick, bool, np.ndarray]:
    """The choice :func:`commanded_kick` makes: the library's kick, whether it is played
    mirrored, and its measured landings as they go for the command (directions mirrored with
    the kick): what the command can expect. Raises as :func:`commanded_kick`."""
    if not (math.isfinite(distance_m) and math.isfinite(direction_deg)) or distance_m <= 0.0:
        raise ValueError(
            f"a kick command must be a positive finite distance (m) and a finite direction "
            f"(deg), got ({distance_m!r}, {direction_deg!r})"
        )
    kicks, landings = _kicks_for(robot_type)
    if landings is None:
        raise ValueError(f"commanded kicks exist for Nao types {TYPE_NUMBERS}, not {robot_type!r}")
    # every kick played both ways, the way the command's side favours first (ties go to it)
    ways = (direction_deg < 0.0, direction_deg >= 0.0)
    rows = np.stack([landings * (1.0, -1.0 if m else 1.0, 1.0) for m in ways], axis=1)
    best = int(np.argmin(landing_cost(rows, distance_m, direction_deg)))  # the first of the least
    kick, way = divmod(best, len(ways))
    return kicks[kick], ways[way], rows[kick, way]


def measure_landings(
    kick: CommandedKick, robot_type: int, episodes: int = LANDING_EPISODES
) -> np.ndarray:
    """Play ``kick`` with zero actions on TargetKick-v1's settings (1 cm of ball spawn noise)
    ``episodes`` times, seeded from 10000 on: (distance m, direction deg, down 1 s later) rows,
    as :func:`kick_landings` holds them."""
    import gymnasium

    env = gymnasium.make(
        MEASURED_ON,
        robot_type=robot_type,
        kick_per_command=False,
        kick_keyframes=kick.keyframes_for(robot_type),
        ball_start_pos=kick.ball_spot,
    ).unwrapped
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    rows = []
    try:
        for k in range(episodes):
            env.reset(seed=_LANDING_SEED + k, options={"kick_target": kick.aim})
            done, info = False, {}
            while not done:
                _, _, terminated, truncated, info = env.step(zero)
                done = terminated or truncated
            travel = np.array([info["rest_x"], info["rest_y"]]) - env.ball_spawn_pos[:2]
            direction = math.degrees(math.atan2(travel[1], travel[0]))
            rows.append((float(np.hypot(*travel)), direction, float(bool(info["fallen"]))))
    finally:
        env.close()
    return np.asarray(rows)


def write_landings(path: Path | None = None) -> Path:
    """Measure every kick of the library on every Nao type (:func:`measure_landings`) and write
    the table :func:`kick_landings` reads (to ``path``; default the package's own file)."""
    out = path or Path(str(resources.files("robocup_gym.data").joinpath(_LANDINGS_FILE)))
    landings = {
        str(robot_type): {
            kick.key: measure_landings(kick, robot_type).round(4).tolist()
            for kick in kick_library()
            if robot_type in kick.robot_types
        }
        for robot_type in TYPE_NUMBERS
    }
    doc = {
        "about": (
            "Where each kick of commanded_kicks.json (and the long kick, 10/0) lands, by Nao type "
            "and kick (aim distance m / direction deg): distance m, direction deg from the "
            "heading, 1.0 if the robot was down 1 s later; zero actions on TargetKick-v1's "
            "settings, ODE. Written by python benchmarks/kick_landings.py --write."
        ),
        "episodes": LANDING_EPISODES,
        "measured_on": MEASURED_ON,
        "landings": landings,
    }
    out.write_text(json.dumps(doc, separators=(",", ":")) + "\n")
    kick_landings.cache_clear()
    _kicks_for.cache_clear()
    return out

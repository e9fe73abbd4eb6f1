"""Agent commands, agent → server (wire reference §3, §4).

Client side: :func:`format_command`, :func:`format_scene`, :func:`format_init` write what an
agent sends. Server side: :func:`parse_agent_message` reads it into typed actions with the real
server's leniency (§1.5, §3.6): numbers are read like C ``atof`` (non-numeric text is 0), a
``beam`` with fewer than 3 values, a ``say`` longer than 20 characters or with illegal
characters and a joint command without a value are dropped, unknown predicates become
:class:`Unknown`, top-level atoms are ignored. Only structurally broken S-expressions raise
:class:`~robocup_gym.protocol.errors.ProtocolError`.

Units: joint velocities in **rad/s**; beam x, y in m (team frame), rotation in degrees.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from functools import cache
from typing import Union

import numpy as np

from robocup_gym.protocol.sexpr import SExpr, dumps, parse
from robocup_gym.protocol.values import atof, atoi, fmt_short, is_atom
from robocup_gym.robot.nao import nao_model
from robocup_gym.types import AgentCommand

__all__ = [
    "HINGE_EFFECTORS",
    "NAO_SCENE_PATH",
    "SAY_MAX_LENGTH",
    "AgentAction",
    "Beam",
    "Hinge",
    "Init",
    "Pass",
    "Say",
    "Scene",
    "Syn",
    "Unknown",
    "format_action",
    "format_actions",
    "format_command",
    "format_init",
    "format_scene",
    "is_valid_say",
    "parse_agent_message",
]

NAO_SCENE_PATH = "rsg/agent/nao/nao_hetero.rsg"
"""Scene file of the heterogeneous Nao (its template argument is the robot type 0–4)."""

SAY_MAX_LENGTH = 20
"""Longest ``say`` message in characters."""

HINGE_EFFECTORS: frozenset[str] = frozenset(
    name for t in range(5) for name in nao_model(t).effector_names
)
"""Effector names of all Nao types (``he1`` … ``rle7``)."""

_SAY_OK = re.compile(rf"[\x21-\x27\x2a-\x7e]{{1,{SAY_MAX_LENGTH}}}")


@dataclass(frozen=True)
class Scene:
    """``(scene <path> <args>…)``: load a robot (§3.3)."""

    path: str
    robot_type: int | None = None
    """Nao type: the first template argument of ``nao_hetero.rsg`` (read like C ``atoi``), 0
    for ``nao.rsg``, ``None`` for other scene files."""
    args: tuple[str, ...] = ()
    """All template arguments as sent."""


@dataclass(frozen=True)
class Init:
    """``(init (unum <N>) (teamname <name>))``: join a team (§3.4).

    Missing parts give 0 / ``""``.
    """

    unum: int = 0
    teamname: str = ""


@dataclass(frozen=True)
class Hinge:
    """``(<effector> <velocity>)``: target velocity of one hinge joint in **rad/s** (§4.1).

    Given as sent: neither clipped to the joint's maximum speed nor checked for NaN/inf (the
    world does that).
    """

    effector: str
    velocity: float


@dataclass(frozen=True)
class Beam:
    """``(beam <x> <y> <rot>)``: x, y in m (team frame), rot in degrees (§4.3)."""

    x: float
    y: float
    rot: float


@dataclass(frozen=True)
class Say:
    """``(say <message>)``: 1–20 printable ASCII characters without space and parentheses."""

    text: str


@dataclass(frozen=True)
class Pass:
    """``(pass)``: request pass mode (§4.5)."""


@dataclass(frozen=True)
class Syn:
    """``(syn)``: done for this cycle in sync mode (§4.6)."""


@dataclass(frozen=True)
class Unknown:
    """Any other predicate, kept verbatim (the real server ignores it)."""

    name: str
    args: tuple[SExpr, ...] = ()


AgentAction = Union[Scene, Init, Hinge, Beam, Say, Pass, Syn, Unknown]  # noqa: UP007
"""One action of an agent message."""


def is_valid_say(text: object) -> bool:
    """True if ``text`` is a legal ``say`` message (1–20 chars in 0x21–0x7E except ``(``/``)``)."""
    return isinstance(text, str) and _SAY_OK.fullmatch(text) is not None


# --------------------------------------------------------------------------------------------
# Server side
# --------------------------------------------------------------------------------------------


def parse_agent_message(msg: str | bytes | bytearray) -> list[AgentAction]:
    """The actions of one agent message (one frame's payload), in order.

    Lenient like rcssserver3d; see the module docstring for what is dropped.

    Raises:
        ProtocolError: only for structurally broken text (unbalanced or truncated parentheses,
            nesting too deep).
    """
    actions: list[AgentAction] = []
    append = actions.append
    hinges = HINGE_EFFECTORS
    for expr in parse(msg):
        if isinstance(expr, str) or not expr:
            continue  # a top-level atom or "()" is ignored
        name = expr[0]
        if not isinstance(name, str):
            continue
        if name in hinges:
            if len(expr) >= 2 and isinstance(expr[1], str):
                append(Hinge(name, atof(expr[1])))
        else:
            action = _parse_other(name, expr)
            if action is not None:
                append(action)
    return actions


def _parse_other(name: str, expr: list[SExpr]) -> AgentAction | None:
    args = expr[1:]
    if name == "syn":
        return Syn()
    if name == "beam":
        if len(args) < 3 or not all(isinstance(a, str) for a in args[:3]):
            return None
        x, y, rot = (atof(a) for a in args[:3])  # type: ignore[arg-type]
        return Beam(x, y, rot)
    if name == "say":
        if args and is_valid_say(args[0]):
            return Say(args[0])  # type: ignore[arg-type]
        return None
    if name == "pass":
        return Pass()
    if name == "init":
        return _parse_init(args)
    if name == "scene":
        if not args or not isinstance(args[0], str):
            return None
        path = args[0]
        rest = tuple(a for a in args[1:] if isinstance(a, str))
        if path.endswith("nao_hetero.rsg"):
            robot_type = atoi(rest[0]) if rest else None
        elif path.endswith("nao.rsg"):
            robot_type = 0
        else:
            robot_type = None
        return Scene(path, robot_type, rest)
    return Unknown(name, tuple(args))


def _parse_init(args: list[SExpr]) -> Init:
    unum = 0
    team = ""
    seen_unum = seen_team = False
    for item in args:
        if not isinstance(item, list) or len(item) < 2 or not isinstance(item[1], str):
            continue
        if item[0] == "unum" and not seen_unum:
            unum = atoi(item[1])
            seen_unum = True
        elif item[0] == "teamname" and not seen_team:
            team = item[1]
            seen_team = True
    return Init(unum, team)


# --------------------------------------------------------------------------------------------
# Client side
# --------------------------------------------------------------------------------------------


@cache
def _effectors(robot_type: int) -> tuple[tuple[str, ...], frozenset[str]]:
    names = nao_model(robot_type).effector_names
    return names, frozenset(names)


def format_command(
    cmd: AgentCommand, robot_type: int = 0, sync: bool = True, decimals: int = 2
) -> str:
    """The message an agent sends for ``cmd``: joints, then ``beam``, ``say``, ``(syn)``.

    Example: ``(he1 0.00)(he2 1.25)…(beam -1 0 0)(say hi)(syn)``.

    Args:
        cmd: joint velocities in **rad/s**, by effector name (in the mapping's order) or as an
            array in the canonical effector order of ``nao_model(robot_type)``; NaN/inf are
            written as ``nan``/``inf``.
        robot_type: the robot's type 0–4 (type 4 has ``lle7``/``rle7``).
        sync: append ``(syn)`` (needed every cycle in sync mode, harmless otherwise).
        decimals: digits after the point for velocities (FC Portugal sends 5).

    Raises:
        ValueError: for an unknown effector name, an array of the wrong length, or an illegal
            ``say`` message (it would corrupt the stream or be dropped by the server).
    """
    names, valid = _effectors(robot_type)
    spec = f".{int(decimals)}f"
    parts: list[str] = []
    velocities = cmd.joint_velocities
    if isinstance(velocities, Mapping):
        for name, value in velocities.items():
            if name not in valid:
                raise ValueError(
                    f"unknown effector {name!r} for robot type {robot_type}; "
                    f"valid: {', '.join(names)}"
                )
            parts.append(f"({name} {format(float(value), spec)})")
    else:
        arr = np.asarray(velocities, dtype=float)
        if arr.shape != (len(names),):
            raise ValueError(
                f"joint_velocities array must have shape ({len(names)},) for robot type "
                f"{robot_type} (canonical effector order), got {arr.shape}"
            )
        for name, value in zip(names, arr.tolist(), strict=True):
            parts.append(f"({name} {format(value, spec)})")
    if cmd.beam is not None:
        x, y, rot = cmd.beam
        parts.append(f"(beam {fmt_short(x)} {fmt_short(y)} {fmt_short(rot)})")
    if cmd.say is not None:
        if not is_valid_say(cmd.say):
            raise ValueError(
                f"illegal say message {cmd.say!r}: 1-{SAY_MAX_LENGTH} printable ASCII characters, "
                "no spaces or parentheses"
            )
        parts.append(f"(say {cmd.say})")
    if sync:
        parts.append("(syn)")
    return "".join(parts)


def format_scene(robot_type: int = 0, path: str = NAO_SCENE_PATH) -> str:
    """``(scene rsg/agent/nao/nao_hetero.rsg <type>)``: the first message after connecting.

    Raises:
        ValueError: for a type outside 0–4 or a path that is not a single atom.
    """
    nao_model(robot_type)  # validates the type
    if not is_atom(path):
        raise ValueError(f"scene path {path!r} must be a single atom")
    return f"(scene {path} {int(robot_type)})"


def format_init(unum: int, team: str) -> str:
    """``(init (unum <N>) (teamname <team>))``; ``unum`` 0 lets the server choose.

    Raises:
        ValueError: for a negative number or a team name that is not a single atom.
    """
    if isinstance(unum, bool) or int(unum) != unum or unum < 0:
        raise ValueError(f"uniform number must be an integer >= 0, got {unum!r}")
    if not is_atom(team):
        raise ValueError(f"team name {team!r} must be a single atom (no spaces or parentheses)")
    return f"(init (unum {int(unum)}) (teamname {team}))"


def format_action(action: AgentAction) -> str:
    """One action as text; numbers are written so that they read back exactly."""
    if isinstance(action, Hinge):
        return f"({_atom(action.effector)} {fmt_short(action.velocity)})"
    if isinstance(action, Syn):
        return "(syn)"
    if isinstance(action, Beam):
        return f"(beam {fmt_short(action.x)} {fmt_short(action.y)} {fmt_short(action.rot)})"
    if isinstance(action, Say):
        if not is_valid_say(action.text):
            raise ValueError(f"illegal say message {action.text!r}")
        return f"(say {action.text})"
    if isinstance(action, Pass):
        return "(pass)"
    if isinstance(action, Init):
        team = f" (teamname {_atom(action.teamname)})" if action.teamname else ""
        return f"(init (unum {int(action.unum)}){team})"
    if isinstance(action, Scene):
        return dumps(["scene", _atom(action.path), *map(_atom, action.args)])
    if isinstance(action, Unknown):
        return dumps([_atom(action.name), *action.args])
    raise TypeError(f"not an agent action: {action!r}")


def format_actions(actions: Iterable[AgentAction]) -> str:
    """Several actions back to back, as one agent message."""
    return "".join(format_action(a) for a in actions)


def _atom(text: str) -> str:
    if not is_atom(text):
        raise ValueError(f"{text!r} is not a single atom (no spaces or parentheses)")
    return text

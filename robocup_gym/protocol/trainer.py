"""Monitor/trainer commands, monitor port → server (wire reference §8).

Client side: one function per command returning its text (:func:`ball`, :func:`agent_move`,
:func:`play_mode`, …) or :func:`format_trainer_command` for the typed form. Server side:
:func:`parse_trainer_message` turns a frame into typed commands.

All coordinates are **global** (not team-mirrored), in m and m/s; angles in degrees. Team atoms
are ``Left`` / ``Right`` (``kickOff`` also ``None``), case-sensitive.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Union

import numpy as np

from robocup_gym.protocol.constants import PLAY_MODES, TEAM_SIDES
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.sexpr import SExpr, dumps, parse_spans
from robocup_gym.protocol.values import fmt_short, is_atom, strict_float, strict_int

__all__ = [
    "AgentCmd",
    "BallCmd",
    "DropBallCmd",
    "GetAckCmd",
    "InvalidCmd",
    "KickOffCmd",
    "KillCmd",
    "KillSimCmd",
    "PlayModeCmd",
    "ReposCmd",
    "ReqFullStateCmd",
    "ScoreCmd",
    "SelectCmd",
    "TimeCmd",
    "TrainerCommand",
    "UnknownCmd",
    "agent",
    "agent_move",
    "agent_pos",
    "ball",
    "drop_ball",
    "format_trainer_command",
    "format_trainer_commands",
    "get_ack",
    "kick_off",
    "kill",
    "killsim",
    "parse_trainer_command",
    "parse_trainer_message",
    "play_mode",
    "quat_from_rot",
    "repos",
    "reqfullstate",
    "rot_from_quat",
    "score",
    "select",
    "set_time",
]

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class BallCmd:
    """``(ball (pos x y z) (vel vx vy vz))``; either part optional. m, m/s, global frame."""

    pos: Vec3 | None = None
    vel: Vec3 | None = None


@dataclass(frozen=True)
class AgentCmd:
    """``(agent (unum N) (team Left|Right) (pos …) (move …) (battery b) (temperature t))``, and
    the SPL fork's ``(rot rx ry rz)``.

    Without both ``unum`` and ``team`` the server only clears its player selection.
    """

    unum: int | None = None
    team: str | None = None
    pos: Vec3 | None = None
    """Teleport the torso to (x, y, z) m, orientation kept."""
    move: tuple[float, float, float, float] | None = None
    """(x, y, z, yaw°): torso position and heading in the model's raw frame (the Nao faces +y
    at yaw 0, so facing +x needs yaw −90)."""
    battery: float | None = None
    temperature: float | None = None
    rot: Vec3 | None = None
    """(rx, ry, rz)°, the SPL fork's extension (upstream 0.7.3 ignores it): after ``pos`` and
    ``move``, turn the robot rigidly about its torso centre so that the torso's orientation
    becomes ``Rx(rx)·Ry(ry)·Rz(rz)`` (world frame; :func:`rot_from_quat`)."""


def rot_from_quat(quat: Sequence[float]) -> tuple[float, float, float]:
    """The ``(rot rx ry rz)`` angles (deg) that give a torso the orientation ``quat`` (w, x, y,
    z): ``R = Rx(rx)·Ry(ry)·Rz(rz)``, as the fork's ``SoccerBase::RotateAgent`` builds it."""
    import mujoco  # not at import time: importing mujoco fails on a bad MUJOCO_GL

    r = np.zeros(9)
    mujoco.mju_quat2Mat(r, np.asarray(quat, dtype=float) / np.linalg.norm(quat))
    r = r.reshape(3, 3)
    ry = math.asin(max(-1.0, min(1.0, r[0, 2])))
    rx = math.atan2(-r[1, 2], r[2, 2])
    rz = math.atan2(-r[0, 1], r[0, 0])
    return (math.degrees(rx), math.degrees(ry), math.degrees(rz))


def quat_from_rot(rot: Sequence[float]) -> np.ndarray:
    """The torso orientation (w, x, y, z) that ``(rot rx ry rz)`` (deg) sets:
    ``Rx(rx)·Ry(ry)·Rz(rz)``."""
    import mujoco

    out = np.array([1.0, 0.0, 0.0, 0.0])
    for axis, angle in zip(np.eye(3), rot, strict=True):
        q = np.zeros(4)
        mujoco.mju_axisAngle2Quat(q, axis, math.radians(float(angle)))
        mujoco.mju_mulQuat(out, out.copy(), q)
    return out


@dataclass(frozen=True)
class PlayModeCmd:
    """``(playMode <name>)`` with a name of :data:`~robocup_gym.protocol.constants.PLAY_MODES`."""

    mode: str


@dataclass(frozen=True)
class KickOffCmd:
    """``(kickOff Left|Right|None)``."""

    team: str = "None"


@dataclass(frozen=True)
class DropBallCmd:
    """``(dropBall)``."""


@dataclass(frozen=True)
class TimeCmd:
    """``(time <t>)``: set the game time, s."""

    time: float


@dataclass(frozen=True)
class ScoreCmd:
    """``(score (left <n>) (right <m>))``."""

    left: int
    right: int


@dataclass(frozen=True)
class SelectCmd:
    """``(select (unum N) (team T))``; ``(select)`` = next player, ``(select (unum -1))`` = none."""

    unum: int | None = None
    team: str | None = None


@dataclass(frozen=True)
class KillCmd:
    """``(kill (unum N) (team T))``, or ``(kill)`` for the selected player."""

    unum: int | None = None
    team: str | None = None


@dataclass(frozen=True)
class ReposCmd:
    """``(repos (unum N) (team T))``, or ``(repos)`` for the selected player."""

    unum: int | None = None
    team: str | None = None


@dataclass(frozen=True)
class ReqFullStateCmd:
    """``(reqfullstate)``: the next monitor frame is a full scene."""


@dataclass(frozen=True)
class KillSimCmd:
    """``(killsim)``: shut the server down."""


@dataclass(frozen=True)
class GetAckCmd:
    """``(getAck)``."""


@dataclass(frozen=True)
class UnknownCmd:
    """A command the server does not know (e.g. RoboViz's ``(init)``); ignored by the server."""

    name: str
    args: tuple[SExpr, ...] = ()


@dataclass(frozen=True)
class InvalidCmd:
    """A malformed known command (only returned by ``parse_trainer_message(strict=False)``)."""

    name: str
    args: tuple[SExpr, ...]
    reason: str


TrainerCommand = Union[  # noqa: UP007
    BallCmd,
    AgentCmd,
    PlayModeCmd,
    KickOffCmd,
    DropBallCmd,
    TimeCmd,
    ScoreCmd,
    SelectCmd,
    KillCmd,
    ReposCmd,
    ReqFullStateCmd,
    KillSimCmd,
    GetAckCmd,
    UnknownCmd,
    InvalidCmd,
]
"""One monitor/trainer command."""

_NO_ARGS: dict[str, type] = {
    "dropBall": DropBallCmd,
    "reqfullstate": ReqFullStateCmd,
    "killsim": KillSimCmd,
    "getAck": GetAckCmd,
}


# --------------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------------


def _nums(values: Sequence[float], count: int, what: str) -> str:
    if len(values) != count:
        raise ValueError(f"{what} needs {count} numbers, got {len(values)}")
    return " ".join(fmt_short(v) for v in values)


def _team(team: str, allow_none: bool = False) -> str:
    allowed = (*TEAM_SIDES, "None") if allow_none else TEAM_SIDES
    if team not in allowed:
        raise ValueError(f"team must be one of {', '.join(allowed)} (case-sensitive), got {team!r}")
    return team


def _int(value: int, what: str, minimum: int | None = None) -> int:
    if isinstance(value, bool) or int(value) != value:
        raise ValueError(f"{what} must be an integer, got {value!r}")
    if minimum is not None and value < minimum:
        raise ValueError(f"{what} must be >= {minimum}, got {value!r}")
    return int(value)


def _who(unum: int | None, team: str | None) -> str:
    parts = ""
    if unum is not None:
        parts += f" (unum {_int(unum, 'unum')})"
    if team is not None:
        parts += f" (team {_team(team)})"
    return parts


def format_trainer_command(cmd: TrainerCommand) -> str:
    """The text of one command.

    Raises:
        ValueError: for an invalid team, play mode, score or vector length.
    """
    if isinstance(cmd, BallCmd):
        text = "(ball"
        if cmd.pos is not None:
            text += f" (pos {_nums(cmd.pos, 3, 'ball pos')})"
        if cmd.vel is not None:
            text += f" (vel {_nums(cmd.vel, 3, 'ball vel')})"
        return text + ")"
    if isinstance(cmd, AgentCmd):
        text = "(agent" + _who(cmd.unum, cmd.team)
        if cmd.pos is not None:
            text += f" (pos {_nums(cmd.pos, 3, 'agent pos')})"
        if cmd.move is not None:
            text += f" (move {_nums(cmd.move, 4, 'agent move')})"
        if cmd.rot is not None:
            text += f" (rot {_nums(cmd.rot, 3, 'agent rot')})"
        if cmd.battery is not None:
            text += f" (battery {fmt_short(cmd.battery)})"
        if cmd.temperature is not None:
            text += f" (temperature {fmt_short(cmd.temperature)})"
        return text + ")"
    if isinstance(cmd, PlayModeCmd):
        if cmd.mode not in PLAY_MODES:
            raise ValueError(f"unknown play mode {cmd.mode!r}; valid: {', '.join(PLAY_MODES)}")
        return f"(playMode {cmd.mode})"
    if isinstance(cmd, KickOffCmd):
        return f"(kickOff {_team(cmd.team, allow_none=True)})"
    if isinstance(cmd, TimeCmd):
        return f"(time {fmt_short(cmd.time)})"
    if isinstance(cmd, ScoreCmd):
        left = _int(cmd.left, "left score", 0)
        right = _int(cmd.right, "right score", 0)
        return f"(score (left {left}) (right {right}))"
    if isinstance(cmd, SelectCmd):
        return "(select" + _who(cmd.unum, cmd.team) + ")"
    if isinstance(cmd, KillCmd):
        return "(kill" + _who(cmd.unum, cmd.team) + ")"
    if isinstance(cmd, ReposCmd):
        return "(repos" + _who(cmd.unum, cmd.team) + ")"
    for name, kind in _NO_ARGS.items():
        if isinstance(cmd, kind):
            return f"({name})"
    if isinstance(cmd, UnknownCmd | InvalidCmd):
        if not is_atom(cmd.name):
            raise ValueError(f"command name {cmd.name!r} is not a single atom")
        return dumps([cmd.name, *cmd.args])
    raise TypeError(f"not a trainer command: {cmd!r}")


def format_trainer_commands(cmds: Iterable[TrainerCommand]) -> str:
    """Several commands back to back in one frame."""
    return "".join(format_trainer_command(c) for c in cmds)


def ball(pos: Sequence[float] | None = None, vel: Sequence[float] | None = None) -> str:
    """``(ball (pos x y z) (vel vx vy vz))``: teleport the ball (m), set its velocity (m/s)."""
    return format_trainer_command(
        BallCmd(
            None if pos is None else tuple(pos),  # type: ignore[arg-type]
            None if vel is None else tuple(vel),  # type: ignore[arg-type]
        )
    )


def agent(
    unum: int | None,
    team: str | None,
    *,
    pos: Sequence[float] | None = None,
    move: Sequence[float] | None = None,
    battery: float | None = None,
    temperature: float | None = None,
    rot: Sequence[float] | None = None,
) -> str:
    """``(agent (unum N) (team T) …)`` with any of pos, move, battery, temperature and the SPL
    fork's rot."""
    return format_trainer_command(
        AgentCmd(
            unum,
            team,
            None if pos is None else tuple(pos),  # type: ignore[arg-type]
            None if move is None else tuple(move),  # type: ignore[arg-type]
            battery,
            temperature,
            None if rot is None else tuple(rot),  # type: ignore[arg-type]
        )
    )


def agent_pos(unum: int, team: str, pos: Sequence[float]) -> str:
    """``(agent (unum N) (team T) (pos x y z))``: teleport player N's torso to ``pos`` (m)."""
    return agent(unum, team, pos=pos)


def agent_move(unum: int, team: str, pos: Sequence[float], yaw_deg: float) -> str:
    """``(agent (unum N) (team T) (move x y z yaw))``: torso to ``pos`` (m), upright, heading
    ``yaw_deg`` in the model's raw frame (global heading − 90°: facing +x is −90)."""
    return agent(unum, team, move=(*pos, yaw_deg))


def play_mode(name: str) -> str:
    """``(playMode <name>)``."""
    return format_trainer_command(PlayModeCmd(name))


def set_time(t: float) -> str:
    """``(time <t>)``: set the game time in s."""
    return format_trainer_command(TimeCmd(t))


def kick_off(team: str = "None") -> str:
    """``(kickOff Left|Right|None)``."""
    return format_trainer_command(KickOffCmd(team))


def drop_ball() -> str:
    """``(dropBall)``."""
    return "(dropBall)"


def kill(unum: int | None = None, team: str | None = None) -> str:
    """``(kill (unum N) (team T))`` or ``(kill)``."""
    return format_trainer_command(KillCmd(unum, team))


def repos(unum: int | None = None, team: str | None = None) -> str:
    """``(repos (unum N) (team T))`` or ``(repos)``."""
    return format_trainer_command(ReposCmd(unum, team))


def select(unum: int | None = None, team: str | None = None) -> str:
    """``(select (unum N) (team T))``, ``(select (unum -1))`` or ``(select)``."""
    return format_trainer_command(SelectCmd(unum, team))


def killsim() -> str:
    """``(killsim)``."""
    return "(killsim)"


def reqfullstate() -> str:
    """``(reqfullstate)``."""
    return "(reqfullstate)"


def get_ack() -> str:
    """``(getAck)``."""
    return "(getAck)"


def score(left: int, right: int) -> str:
    """``(score (left n) (right m))``."""
    return format_trainer_command(ScoreCmd(left, right))


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------


class _MalformedError(Exception):
    pass


def parse_trainer_message(
    msg: str | bytes | bytearray, *, strict: bool = True
) -> list[TrainerCommand]:
    """The commands of one monitor-port frame, in order.

    Top-level atoms and lists without a name are ignored; unknown names give
    :class:`UnknownCmd`.

    Args:
        msg: the payload.
        strict: raise on a malformed known command; with ``False`` it is returned as
            :class:`InvalidCmd` (the real server ignores it) and parsing goes on.

    Raises:
        ProtocolError: for structurally broken text, and (``strict``) for a malformed command
            such as ``(ball (pos 1 2))``, ``(playMode Foo)`` or ``(time x)``; the message names
            the command and its offset.
    """
    text = msg if isinstance(msg, str) else bytes(msg).decode("latin-1")
    commands: list[TrainerCommand] = []
    for offset, expr in parse_spans(text):
        if isinstance(expr, str) or not expr or not isinstance(expr[0], str):
            continue
        try:
            commands.append(_parse_command(expr))
        except _MalformedError as exc:
            if strict:
                raise ProtocolError(str(exc), offset=offset, predicate=expr[0], text=text) from None
            commands.append(InvalidCmd(expr[0], tuple(expr[1:]), str(exc)))
    return commands


def parse_trainer_command(expr: SExpr | str) -> TrainerCommand:
    """One command from its S-expression (or its text).

    Raises:
        ProtocolError: if it is malformed.
    """
    if isinstance(expr, str):
        commands = parse_trainer_message(expr)
        if len(commands) != 1:
            raise ProtocolError(f"expected exactly one command, found {len(commands)}")
        return commands[0]
    if not expr or not isinstance(expr[0], str):
        raise ProtocolError("a command is a list that starts with its name")
    try:
        return _parse_command(expr)
    except _MalformedError as exc:
        raise ProtocolError(str(exc), predicate=expr[0]) from None


def _parse_command(expr: list[SExpr]) -> TrainerCommand:
    name = expr[0]
    assert isinstance(name, str)
    args = expr[1:]
    if name == "ball":
        subs = _subs(args)
        return BallCmd(_vec(subs, "pos", 3), _vec(subs, "vel", 3))  # type: ignore[arg-type]
    if name == "agent":
        subs = _subs(args)
        unum, team = _who_parse(subs)
        battery = _vec(subs, "battery", 1)
        temperature = _vec(subs, "temperature", 1)
        return AgentCmd(
            unum,
            team,
            _vec(subs, "pos", 3),  # type: ignore[arg-type]
            _vec(subs, "move", 4),  # type: ignore[arg-type]
            None if battery is None else battery[0],
            None if temperature is None else temperature[0],
            _vec(subs, "rot", 3),  # type: ignore[arg-type]
        )
    if name == "playMode":
        mode = _single_atom(args, name)
        if mode not in PLAY_MODES:
            raise _MalformedError(f"unknown play mode {mode!r}")
        return PlayModeCmd(mode)
    if name == "kickOff":
        team = _single_atom(args, name)
        if team not in (*TEAM_SIDES, "None"):
            raise _MalformedError(f"kickOff team must be Left, Right or None, got {team!r}")
        return KickOffCmd(team)
    if name == "time":
        return TimeCmd(_number(_single_atom(args, name)))
    if name == "score":
        subs = _subs(args)
        left = _vec(subs, "left", 1, integer=True)
        right = _vec(subs, "right", 1, integer=True)
        if left is None or right is None:
            raise _MalformedError("score needs both (left n) and (right m)")
        if left[0] < 0 or right[0] < 0:
            raise _MalformedError("scores must be >= 0")
        return ScoreCmd(int(left[0]), int(right[0]))
    if name in ("select", "kill", "repos"):
        unum, team = _who_parse(_subs(args))
        kind = {"select": SelectCmd, "kill": KillCmd, "repos": ReposCmd}[name]
        return kind(unum, team)
    kind = _NO_ARGS.get(name)
    if kind is not None:
        return kind()
    return UnknownCmd(name, tuple(args))


def _subs(args: list[SExpr]) -> dict[str, list[SExpr]]:
    """Sub-lists by their first atom; the first occurrence counts (as in the server)."""
    found: dict[str, list[SExpr]] = {}
    for item in args:
        if isinstance(item, list) and item and isinstance(item[0], str):
            found.setdefault(item[0], item)
    return found


def _number(text: SExpr, integer: bool = False) -> float:
    if not isinstance(text, str):
        raise _MalformedError("expected a number, got a list")
    try:
        return strict_int(text) if integer else strict_float(text)
    except ProtocolError as exc:
        raise _MalformedError(str(exc)) from None


def _vec(
    subs: dict[str, list[SExpr]], key: str, count: int, integer: bool = False
) -> tuple[float, ...] | None:
    item = subs.get(key)
    if item is None:
        return None
    if len(item) != count + 1:
        raise _MalformedError(f"({key} …) needs {count} number(s), got {len(item) - 1}")
    return tuple(_number(x, integer) for x in item[1:])


def _single_atom(args: list[SExpr], name: str) -> str:
    if len(args) != 1 or not isinstance(args[0], str):
        raise _MalformedError(f"({name} …) needs exactly one atom")
    return args[0]


def _who_parse(subs: dict[str, list[SExpr]]) -> tuple[int | None, str | None]:
    unum_v = _vec(subs, "unum", 1, integer=True)
    unum = None if unum_v is None else int(unum_v[0])
    team = None
    item = subs.get("team")
    if item is not None:
        if len(item) != 2 or item[1] not in TEAM_SIDES:
            raise _MalformedError(f"team must be (team Left) or (team Right), got {dumps(item)}")
        team = item[1]
        assert isinstance(team, str)
    return unum, team

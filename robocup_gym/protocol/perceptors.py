"""Agent percepts, server → agent: text → :class:`~robocup_gym.types.Perception` (wire reference
§5).

Units are kept as on the wire: joint angles, gyro rates and vision angles in **degrees**
(gyro deg/s), accelerations m/s², distances and positions m, forces N, times s.

Two parsers sit behind :func:`parse_perception`:

* a fast path of specialised regular expressions for messages in the exact layout the real
  server writes (2- or 3-decimal numbers, the SPL fork's extra ``GS`` fields included); it
  only accepts a message when every character is covered by a well-formed, known predicate;
* a general path (S-expression reader + tree walk) for everything else: other spacing, unknown
  predicates (ignored), and malformed input, which it reports as
  :class:`~robocup_gym.protocol.errors.ProtocolError` with offset and predicate name.

Both give identical results wherever the fast path applies (tested).
"""

from __future__ import annotations

import re
from functools import cache

import numpy as np

from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.perceptor_format import format_perception
from robocup_gym.protocol.sexpr import SExpr, parse_spans
from robocup_gym.protocol.values import strict_float, strict_int
from robocup_gym.robot.nao import nao_model
from robocup_gym.types import (
    ForceResistance,
    GameState,
    HeardMessage,
    Perception,
    SeenPlayer,
    Vision,
)

__all__ = ["format_perception", "joint_names_for", "parse_perception"]


def parse_perception(msg: str | bytes | bytearray, robot_type: int | None = None) -> Perception:
    """Parse one percept message (the payload of one frame, without the length prefix).

    Args:
        msg: the message text; bytes are decoded as Latin-1.
        robot_type: the robot's heterogeneous type 0–4. ``None`` infers it from the joints:
            4 when ``llj7``/``rlj7`` are present, else 0 (types 0–3 send the same joints).

    Returns:
        The :class:`~robocup_gym.types.Perception`, joints in the canonical order of
        :func:`robocup_gym.robot.nao.nao_model` (``joint_names == nao_model(t).perceptor_names``).
        ``GS`` ``unum``/``team`` are set only when present; the SPL fork's ``k`` and ``ti`` and
        any unknown predicate are ignored. The arrays of one result may be views of a single
        buffer (each covers only its own values); copy one before resizing it in place.

    Raises:
        ProtocolError: for malformed text (unbalanced/truncated, a top-level atom such as an
            unstripped length prefix, non-numeric values, missing ``time``/``GS``/``GYR``/``ACC``
            or joints, joints the robot type does not have).
        ValueError: for a ``robot_type`` outside 0–4.
    """
    text = msg if isinstance(msg, str) else bytes(msg).decode("latin-1")
    if robot_type is not None:
        nao_model(robot_type)  # validates 0-4
    result = _parse_fast(text, robot_type)
    if result is None:
        result = _parse_tree(text, robot_type)
    return result


@cache
def joint_names_for(robot_type: int) -> tuple[str, ...]:
    """``HJ`` names of robot type ``robot_type`` in canonical order (cached)."""
    return nao_model(robot_type).perceptor_names


def _infer_type(names: tuple[str, ...] | dict[str, object], robot_type: int | None) -> int:
    if robot_type is not None:
        return robot_type
    return 4 if ("llj7" in names or "rlj7" in names) else 0


# --------------------------------------------------------------------------------------------
# Fast path
# --------------------------------------------------------------------------------------------

_A = r"[^\s()]+"  # any atom
# Numbers and joint names: explicit character sets are faster than [^\s()] and exclude "_"
# (float() would accept "1_0", the general path does not); anything else goes the general way.
_N = r"[-+.0-9a-zA-Z]+"
_J = r"[a-z0-9]+"

_TIME = re.compile(rf"\(time \(now ({_N})\)\)")
_GS = re.compile(
    rf"(\(GS(?: \(unum ({_N})\))?(?: \(team ({_A})\))? \(sl ({_N})\) \(sr ({_N})\) \(t ({_N})\)"
    rf" \(pm ({_A})\)(?: \(k {_A}\))?(?: \(ti(?: \((?: ?\([^()]*+\))*+\))*+\))?\))"
)
_HEAR = re.compile(rf"(\(hear ({_A}) ({_A}) ({_A})(?: ({_A}))?\))")
_GYR = re.compile(rf"\(GYR \(n ({_A})\) \(rt ({_N}) ({_N}) ({_N})\)\)")
_ACC = re.compile(rf"\(ACC \(n ({_A})\) \(a ({_N}) ({_N}) ({_N})\)\)")
_HJ = re.compile(rf"\(HJ \(n ({_J})\) \(ax ({_N})\)\)")
_HJ_FIXED = len("(HJ (n ) (ax ))")
_FRP = re.compile(rf"\(FRP \(n ({_A})\) \(c ({_N}) ({_N}) ({_N})\) \(f ({_N}) ({_N}) ({_N})\)\)")
_FRP_FIXED = len("(FRP (n ) (c   ) (f   ))")
# See: three levels of nesting inside (See (P (head (pol …)))); items are checked strictly below.
_SEE = re.compile(r"(\(See((?: \((?:[^()]++|\((?:[^()]++|\([^()]*+\))*+\))*+\))*+)\))")

_POL = rf"\(pol ({_N}) ({_N}) ({_N})\)"
_SEE_OBJ = re.compile(rf" \((?!(?:P|L|mypos|myorien|ballpos) )({_A}) {_POL}\)")
_SEE_PLAYER = re.compile(
    rf" \(P \(team ({_A})\) \(id ({_N})\)"
    rf"((?: \((?!(?:team|id) ){_A} \(pol {_N} {_N} {_N}\)\))*)\)"
)
_SEE_PART = re.compile(rf" \(({_A}) {_POL}\)")
_SEE_LINE = re.compile(rf" \(L {_POL} {_POL}\)")
_SEE_VEC = re.compile(rf" \((mypos|ballpos) ({_N}) ({_N}) ({_N})\)")
_SEE_ORIEN = re.compile(rf" \(myorien ({_N})\)")

_PERM_CACHE: dict[tuple[tuple[str, ...], int | None], tuple[int, np.ndarray]] = {}
_PERM_CACHE_MAX = 64


def _joint_perm(names: tuple[str, ...], robot_type: int | None) -> tuple[int, np.ndarray] | None:
    """(type, index array taking wire order to canonical order), or None if not a clean set."""
    key = (names, robot_type)
    hit = _PERM_CACHE.get(key)
    if hit is not None:
        return hit
    t = _infer_type(names, robot_type)
    canon = joint_names_for(t)
    if len(names) != len(canon) or set(names) != set(canon):
        return None
    index = {n: i for i, n in enumerate(names)}
    hit = (t, np.array([index[n] for n in canon], dtype=np.intp))
    if len(_PERM_CACHE) < _PERM_CACHE_MAX:
        _PERM_CACHE[key] = hit
    return hit


class _NotFastError(Exception):
    """Raised inside the fast path to hand the message to the general path."""


def _parse_fast(s: str, robot_type: int | None) -> Perception | None:
    """The fast path; ``None`` whenever it cannot vouch for the result.

    All numbers are collected as text, converted in one go and handed out as views of one
    array (the arrays of one Perception share a buffer; each view covers only its own values).
    """
    if not s.isascii():
        return None
    # The head of a percept is always time, GS, hear…, GYR, ACC (wire reference §5.11): match it
    # in place.
    m = _TIME.match(s)
    if m is None:
        return None
    now_text = m.group(1)
    m = _GS.match(s, m.end())
    if m is None:
        return None
    gs = m.groups()
    pos = m.end()
    hears = []
    while s.startswith("(hear ", pos):
        m = _HEAR.match(s, pos)
        if m is None:
            return None
        hears.append(m.groups())
        pos = m.end()
    m = _GYR.match(s, pos)
    if m is None:
        return None
    gyr = m.groups()
    m = _ACC.match(s, m.end())
    if m is None:
        return None
    acc = m.groups()
    pos = m.end()
    # The rest: HJ and FRP predicates and at most one See, in any order.
    hj = _HJ.findall(s, pos)
    if not hj:
        return None
    frps = _FRP.findall(s, pos)
    sees = _SEE.findall(s, pos) if "(See" in s else ()

    # Every character must belong to exactly one recognised predicate. The strict patterns
    # cannot contain one another, so equal total length means complete, disjoint coverage.
    names, vals = zip(*hj, strict=True)
    covered = pos + _HJ_FIXED * len(hj) + sum(map(len, names)) + sum(map(len, vals))
    for g in frps:
        covered += _FRP_FIXED + sum(map(len, g))
    if sees:
        if len(sees) > 1:
            return None
        covered += len(sees[0][0])
    if covered != len(s):
        return None
    perm = _joint_perm(names, robot_type)
    if perm is None:
        return None
    t, index = perm

    n = len(vals)
    nums = list(vals)
    nums += gyr[1:]
    nums += acc[1:]
    feet = {}
    for f in frps:
        feet[f[0]] = len(nums)  # last one wins, as in a dict
        nums += f[1:]
    try:
        see = _scan_see(sees[0][1], nums) if sees else None
        arr = np.array(list(map(float, nums)))
        _, unum, team, sl, sr, gt, pm = gs
        game = GameState(
            play_mode=pm,
            game_time=float(gt),
            score_left=int(sl),
            score_right=int(sr),
            unum=int(unum) if unum else None,
            team_side=team or None,
        )
        heard = [_fast_hear(h) for h in hears]
        vision = see.build(arr) if see is not None else None
        now = float(now_text)
    except (ValueError, _NotFastError):
        return None
    return Perception(
        time=now,
        game=game,
        gyro=arr[n : n + 3],
        accel=arr[n + 3 : n + 6],
        joint_names=joint_names_for(t),
        joint_angles_deg=arr[:n][index],
        force_sensors={
            k: ForceResistance(arr[i : i + 3], arr[i + 3 : i + 6]) for k, i in feet.items()
        },
        vision=vision,
        heard=heard,
    )


def _fast_hear(h: tuple[str, ...]) -> HeardMessage:
    _, a, b, c, d = h
    if d:
        team, when, direction, message = a, b, c, d
    else:
        team, when, direction, message = None, a, b, c
    if "_" in when or "_" in direction:
        raise _NotFastError
    return HeardMessage(
        team=team,
        time=float(when),
        direction_deg=None if direction == "self" else float(direction),
        message=message,
    )


class _SeeScan:
    """Where the numbers of one ``See`` went in the shared number list."""

    __slots__ = ("ball_pos", "line_count", "lines_at", "my_orien", "my_pos", "objects", "players")

    def __init__(self) -> None:
        self.objects: dict[str, int] = {}
        self.players: list[tuple[str, str, dict[str, int]]] = []
        self.lines_at = 0
        self.line_count = 0
        self.my_pos: int | None = None
        self.ball_pos: int | None = None
        self.my_orien: str | None = None

    def build(self, arr: np.ndarray) -> Vision:
        vision = Vision(
            objects={k: arr[i : i + 3] for k, i in self.objects.items()},
            players=[
                SeenPlayer(team, int(unum), {k: arr[i : i + 3] for k, i in parts.items()})
                for team, unum, parts in self.players
            ],
        )
        if self.line_count:
            i = self.lines_at
            vision.lines = arr[i : i + 6 * self.line_count].reshape(-1, 2, 3)
        if self.my_pos is not None:
            vision.my_pos = arr[self.my_pos : self.my_pos + 3]
        if self.ball_pos is not None:
            vision.ball_pos = arr[self.ball_pos : self.ball_pos + 3]
        if self.my_orien is not None:
            vision.my_orientation_deg = float(self.my_orien)
        return vision


def _scan_see(body: str, nums: list[str]) -> _SeeScan:
    scan = _SeeScan()
    lines: list[str] = []
    pos = 0
    end = len(body)
    while pos < end:
        space = body.find(" ", pos + 2)
        name = body[pos + 2 : space]
        if name == "P":
            m = _SEE_PLAYER.match(body, pos)
            if m is None:
                raise _NotFastError
            parts = {}
            for p in _SEE_PART.findall(m.group(3)):
                parts[p[0]] = len(nums)
                nums += p[1:]
            scan.players.append((m.group(1), m.group(2), parts))
        elif name == "L":
            m = _SEE_LINE.match(body, pos)
            if m is None:
                raise _NotFastError
            lines += m.groups()
        elif name == "mypos" or name == "ballpos":
            m = _SEE_VEC.match(body, pos)
            if m is None:
                raise _NotFastError
            if name == "mypos":
                scan.my_pos = len(nums)
            else:
                scan.ball_pos = len(nums)
            nums += m.groups()[1:]
        elif name == "myorien":
            m = _SEE_ORIEN.match(body, pos)
            if m is None:
                raise _NotFastError
            scan.my_orien = m.group(1)
        else:
            m = _SEE_OBJ.match(body, pos)
            if m is None:
                raise _NotFastError
            scan.objects[m.group(1)] = len(nums)
            nums += m.groups()[1:]
        pos = m.end()
    if lines:
        scan.lines_at = len(nums)
        scan.line_count = len(lines) // 6
        nums += lines
    return scan


# --------------------------------------------------------------------------------------------
# General path
# --------------------------------------------------------------------------------------------


class _BadPredicateError(Exception):
    """A problem inside one predicate; turned into a ProtocolError with its offset."""


def _parse_tree(s: str, robot_type: int | None) -> Perception:
    spans = parse_spans(s)
    now: float | None = None
    game: GameState | None = None
    gyro: np.ndarray | None = None
    accel: np.ndarray | None = None
    joints: dict[str, float] = {}
    joint_offsets: dict[str, int] = {}
    force: dict[str, ForceResistance] = {}
    vision: Vision | None = None
    heard: list[HeardMessage] = []
    for offset, expr in spans:
        if isinstance(expr, str):
            raise ProtocolError(
                f"unexpected top-level atom {expr[:20]!r}: percepts consist of lists only "
                "(is the 4-byte length prefix still attached?)",
                offset=offset,
                text=s,
            )
        if not expr or not isinstance(expr[0], str):
            continue
        name = expr[0]
        try:
            if name == "time":
                now = _num(_sub_required(expr, "now"), 1)[0]
            elif name == "GS":
                game = _tree_gs(expr)
            elif name == "GYR":
                gyro = np.array(_num(_sub_required(expr, "rt"), 3))
            elif name == "ACC":
                accel = np.array(_num(_sub_required(expr, "a"), 3))
            elif name == "HJ":
                joint = _atom(_sub_required(expr, "n"))
                joints[joint] = _num(_sub_required(expr, "ax"), 1)[0]
                joint_offsets[joint] = offset
            elif name == "FRP":
                foot = _atom(_sub_required(expr, "n"))
                force[foot] = ForceResistance(
                    np.array(_num(_sub_required(expr, "c"), 3)),
                    np.array(_num(_sub_required(expr, "f"), 3)),
                )
            elif name == "hear":
                heard.append(_tree_hear(expr))
            elif name == "See":
                vision = _tree_see(expr)
        except (_BadPredicateError, ProtocolError) as exc:
            raise ProtocolError(str(exc), offset=offset, predicate=name, text=s) from None
    for value, what in ((now, "time"), (game, "GS"), (gyro, "GYR"), (accel, "ACC")):
        if value is None:
            raise ProtocolError(f"percept has no {what} predicate", predicate=what)
    t = _infer_type(joints, robot_type)
    canon = joint_names_for(t)
    for joint, offset in joint_offsets.items():
        if joint not in canon:
            raise ProtocolError(
                f"unknown joint {joint!r} for robot type {t}; expected {', '.join(canon)}",
                offset=offset,
                predicate="HJ",
                text=s,
            )
    missing = [j for j in canon if j not in joints]
    if missing:
        raise ProtocolError(
            f"percept lacks the angle of joint(s) {', '.join(missing)} (robot type {t})",
            predicate="HJ",
        )
    assert now is not None and game is not None and gyro is not None and accel is not None
    return Perception(
        time=now,
        game=game,
        gyro=gyro,
        accel=accel,
        joint_names=canon,
        joint_angles_deg=np.array([joints[j] for j in canon], dtype=float),
        force_sensors=force,
        vision=vision,
        heard=heard,
    )


def _sub(expr: list[SExpr], key: str) -> list[SExpr] | None:
    """The last sub-list of ``expr`` whose first element is the atom ``key``."""
    found = None
    for item in expr[1:]:
        if isinstance(item, list) and item and item[0] == key:
            found = item
    return found


def _sub_required(expr: list[SExpr], key: str) -> list[SExpr]:
    found = _sub(expr, key)
    if found is None:
        raise _BadPredicateError(f"missing ({key} …)")
    return found


def _atom(item: list[SExpr]) -> str:
    if len(item) != 2 or not isinstance(item[1], str):
        raise _BadPredicateError(f"({item[0]} …) must hold exactly one atom")
    return item[1]


def _num(item: list[SExpr], count: int) -> list[float]:
    if len(item) != count + 1:
        raise _BadPredicateError(
            f"({item[0]} …) must hold {count} number(s), has {len(item) - 1} element(s)"
        )
    return [_float(x) for x in item[1:]]


def _float(x: SExpr) -> float:
    if not isinstance(x, str):
        raise _BadPredicateError("expected a number, got a list")
    return strict_float(x)


def _int(x: SExpr) -> int:
    if not isinstance(x, str):
        raise _BadPredicateError("expected an integer, got a list")
    return strict_int(x)


def _tree_gs(expr: list[SExpr]) -> GameState:
    game = GameState()
    for item in expr[1:]:
        if not isinstance(item, list) or not item or not isinstance(item[0], str):
            continue
        key = item[0]
        if key == "unum":
            game.unum = _int(_atom(item))
        elif key == "team":
            game.team_side = _atom(item)
        elif key == "sl":
            game.score_left = _int(_atom(item))
        elif key == "sr":
            game.score_right = _int(_atom(item))
        elif key == "t":
            game.game_time = _float(_atom(item))
        elif key == "pm":
            game.play_mode = _atom(item)
    return game


def _tree_hear(expr: list[SExpr]) -> HeardMessage:
    args = expr[1:]
    if not all(isinstance(a, str) for a in args) or len(args) not in (3, 4):
        raise _BadPredicateError("expected (hear [<team>] <time> self|<direction> <message>)")
    team = args[0] if len(args) == 4 else None
    when, direction, message = args[-3:]
    assert isinstance(when, str) and isinstance(direction, str) and isinstance(message, str)
    return HeardMessage(
        team=team if isinstance(team, str) else None,
        time=_float(when),
        direction_deg=None if direction == "self" else _float(direction),
        message=message,
    )


def _pol(item: SExpr) -> list[float]:
    if not isinstance(item, list):
        raise _BadPredicateError("expected (pol <distance> <horizontal> <vertical>)")
    return _num(item, 3)


def _tree_see(expr: list[SExpr]) -> Vision:
    vision = Vision()
    lines: list[list[float]] = []
    for item in expr[1:]:
        if not isinstance(item, list) or not item or not isinstance(item[0], str):
            continue
        key = item[0]
        if key == "P":
            vision.players.append(_tree_player(item))
        elif key == "L":
            pols = [p for p in item[1:] if isinstance(p, list) and p and p[0] == "pol"]
            if len(pols) != 2:
                raise _BadPredicateError(
                    f"a line (L …) needs two (pol …) end points, has {len(pols)}"
                )
            lines.append(_pol(pols[0]) + _pol(pols[1]))
        elif key == "mypos":
            vision.my_pos = np.array(_num(item, 3))
        elif key == "ballpos":
            vision.ball_pos = np.array(_num(item, 3))
        elif key == "myorien":
            vision.my_orientation_deg = _num(item, 1)[0]
        else:
            pol = _sub(item, "pol")
            if pol is not None:
                vision.objects[key] = np.array(_pol(pol))
    if lines:
        vision.lines = np.array(lines, dtype=float).reshape(-1, 2, 3)
    return vision


def _tree_player(item: list[SExpr]) -> SeenPlayer:
    team = _sub(item, "team")
    ident = _sub(item, "id")
    if team is None or ident is None:
        raise _BadPredicateError("a player (P …) needs (team …) and (id …)")
    player = SeenPlayer(team=_atom(team), unum=_int(_atom(ident)))
    for part in item[1:]:
        if not isinstance(part, list) or not part or not isinstance(part[0], str):
            continue
        if part[0] in ("team", "id"):
            continue
        pol = _sub(part, "pol")
        if pol is not None:
            player.parts[part[0]] = np.array(_pol(pol))
    return player

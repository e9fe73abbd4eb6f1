"""Agent percepts, server side: :class:`~robocup_gym.types.Perception` → rcssserver3d 0.7.3 text.

The output is byte-compatible with the real server (wire reference §5.1, §5.11, §5.13): one
predicate per perceptor without separators, one space before every element inside a predicate,
floats in fixed notation with 2 decimals (``-0.00`` included), integers as integers, predicates in
the Nao's model order. Units as on the wire: degrees, deg/s, m/s², m, N, s.
"""

from __future__ import annotations

from collections.abc import Iterable
from operator import itemgetter

import numpy as np

from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.values import is_atom
from robocup_gym.types import ForceResistance, GameState, HeardMessage, Perception, Vision

__all__ = ["LANDMARK_ORDER", "PLAYER_PART_ORDER", "format_perception"]

LANDMARK_ORDER = ("G1L", "G2L", "G2R", "G1R", "F1L", "F2L", "F1R", "F2R", "B")
"""Order of the landmark/ball group inside ``See`` (model order, wire reference §5.10)."""

PLAYER_PART_ORDER = ("head", "rlowerarm", "llowerarm", "rfoot", "lfoot")
"""Order of the visible body parts inside a ``P`` entry."""

# Model order of the joint and foot perceptors after GYR/ACC (wire reference §5.11). Entries
# starting with "@" are slots for See and the FRPs; joints that the robot lacks are simply skipped.
_SEQUENCE = (
    "hj1",
    "hj2",
    "@See",
    "raj1",
    "raj2",
    "raj3",
    "raj4",
    "laj1",
    "laj2",
    "laj3",
    "laj4",
    "rlj1",
    "rlj2",
    "rlj3",
    "rlj4",
    "rlj5",
    "@rf",
    "rlj6",
    "@rf1",
    "rlj7",
    "llj1",
    "llj2",
    "llj3",
    "llj4",
    "llj5",
    "@lf",
    "llj6",
    "@lf1",
    "llj7",
)
_KNOWN_JOINTS = frozenset(x for x in _SEQUENCE if not x.startswith("@"))
_KNOWN_FEET = ("rf", "rf1", "lf", "lf1")


def format_perception(p: Perception, decimals: int = 2) -> str:
    """The percept text rcssserver3d 0.7.3 would send for ``p``.

    Predicate order: ``time``, ``GS``, ``hear``…, ``GYR``, ``ACC``, ``HJ hj1``, ``HJ hj2``,
    ``See``, arms (``raj1–4``, ``laj1–4``), right leg with ``FRP rf`` between ``rlj5`` and
    ``rlj6`` and ``FRP rf1`` before ``rlj7``, left leg likewise. Joints or force sensors with
    other names are appended at the end. :attr:`~robocup_gym.types.Perception.ground_truth` is
    not part of the wire format and is not written.

    Args:
        p: the percept.
        decimals: digits after the point (2 as upstream 0.7.3; the SPL fork prints 3).

    Raises:
        ProtocolError: for a name or message that is not a single atom (it would corrupt the
            stream: spaces or parentheses).
    """
    decimals = int(decimals)
    spec = f".{decimals}f"
    out: list[str] = [f"(time (now {format(p.time, spec)}))", _format_gs(p.game, spec)]
    out.extend(_format_hear(h, spec) for h in p.heard)
    angles = np.asarray(p.joint_angles_deg, dtype=float).tolist()
    names = tuple(p.joint_names)
    if len(names) != len(angles):  # as zip(strict=True)
        raise ValueError(f"{len(names)} joint names for {len(angles)} joint angles")
    feet = p.force_sensors
    key = (names, tuple(feet), decimals)
    plan = _PLANS.get(key)
    if plan is None:
        plan = _make_plan(names, tuple(feet), decimals)
        if len(_PLANS) >= _MAX_PLANS:
            _PLANS.clear()
        _PLANS[key] = plan
    head, tail, pick_head, pick_tail = plan
    values = _floats3(p.gyro) + _floats3(p.accel) + angles
    for frp in feet.values():
        values += _floats3(frp.point)
        values += _floats3(frp.force)
    out.append(head % pick_head(values))
    if p.vision is not None:
        out.append(_format_see(p.vision, spec))
    out.append(tail % pick_tail(values))
    return "".join(out)


_PLANS: dict[tuple, tuple] = {}
_MAX_PLANS = 256


def _picker(indices: list[int]):
    """``values`` → tuple of ``values[i]`` for ``i`` in ``indices`` (also for 0 and 1 indices)."""
    if not indices:
        return lambda values: ()
    if len(indices) == 1:
        k = indices[0]
        return lambda values: (values[k],)
    return itemgetter(*indices)


def _make_plan(names: tuple[str, ...], feet: tuple[str, ...], decimals: int) -> tuple:
    """Templates (``%``-format strings) and value pickers of everything from ``GYR`` to the end
    except ``See``, for one set of joint names and force sensors: ``values`` holds gyro (3),
    accel (3), the joint angles in ``names`` order, then 6 numbers per force sensor (point,
    force) in ``feet`` order."""
    num = f"%.{decimals}f"
    v3 = f"{num} {num} {num}"
    joint_at = {name: 6 + k for k, name in enumerate(names)}  # a repeated name: last angle
    base = 6 + len(names)
    foot_at = {name: base + 6 * k for k, name in enumerate(feet)}

    def frp(name: str, parts: list[str], picks: list[int]) -> None:
        parts.append(f"(FRP (n {_checked(name, 'force sensor name').replace('%', '%%')}) (c {v3})")
        parts.append(f" (f {v3}))")
        k = foot_at[name]
        picks.extend(range(k, k + 6))

    def hj(name: str, parts: list[str], picks: list[int]) -> None:
        parts.append(f"(HJ (n {name.replace('%', '%%')}) (ax {num}))")
        picks.append(joint_at[name])

    head: list[str] = [f"(GYR (n torso) (rt {v3}))", f"(ACC (n torso) (a {v3}))"]
    head_picks = [0, 1, 2, 3, 4, 5]
    tail: list[str] = []
    tail_picks: list[int] = []
    parts, picks = head, head_picks
    has_rlj7 = "rlj7" in joint_at
    has_llj7 = "llj7" in joint_at
    for slot in _SEQUENCE:
        if slot[0] != "@":
            if slot in joint_at:
                hj(slot, parts, picks)
            if slot == "rlj6" and not has_rlj7 and "rf1" in foot_at:
                frp("rf1", parts, picks)
            elif slot == "llj6" and not has_llj7 and "lf1" in foot_at:
                frp("lf1", parts, picks)
        elif slot == "@See":
            parts, picks = tail, tail_picks
        else:
            foot = slot[1:]
            if foot in foot_at and (
                foot in ("rf", "lf") or (has_rlj7 if foot == "rf1" else has_llj7)
            ):
                frp(foot, parts, picks)
    for name in joint_at:
        if name not in _KNOWN_JOINTS:
            hj(_checked(name, "joint name"), parts, picks)
    for name in feet:
        if name not in _KNOWN_FEET:
            frp(name, parts, picks)
    return "".join(head), "".join(tail), _picker(head_picks), _picker(tail_picks)


def _floats3(v: Iterable[float]) -> list[float]:
    """The three components of ``v`` as Python floats."""
    if type(v) is np.ndarray and v.dtype == np.float64 and v.shape == (3,):
        return v.tolist()
    x, y, z = (float(c) for c in v)
    return [x, y, z]


def _checked(text: object, what: str) -> str:
    if not is_atom(text):
        raise ProtocolError(f"{what} {text!r} is not a single atom (no spaces or parentheses)")
    return str(text)


def _v3(v: Iterable[float], spec: str) -> str:
    x, y, z = (float(c) for c in v)
    return f"{format(x, spec)} {format(y, spec)} {format(z, spec)}"


def _format_gs(g: GameState, spec: str) -> str:
    parts = ["(GS"]
    if g.unum is not None:
        parts.append(f" (unum {int(g.unum)})")
    if g.team_side is not None:
        parts.append(f" (team {_checked(g.team_side, 'team side')})")
    parts.append(
        f" (sl {int(g.score_left)}) (sr {int(g.score_right)}) (t {format(g.game_time, spec)})"
        f" (pm {_checked(g.play_mode, 'play mode')}))"
    )
    return "".join(parts)


def _format_hear(h: HeardMessage, spec: str) -> str:
    direction = "self" if h.direction_deg is None else format(h.direction_deg, spec)
    message = _checked(h.message, "heard message")
    if h.team is None:
        return f"(hear {format(h.time, spec)} {direction} {message})"
    return f"(hear {_checked(h.team, 'team name')} {format(h.time, spec)} {direction} {message})"


def _format_frp(name: str, frp: ForceResistance, spec: str) -> str:
    return (
        f"(FRP (n {_checked(name, 'force sensor name')}) (c {_v3(frp.point, spec)})"
        f" (f {_v3(frp.force, spec)}))"
    )


def _esc(text: str) -> str:
    return text.replace("%", "%%")


def _format_see(v: Vision, spec: str) -> str:
    # one %-template for the whole predicate: names go into the template, numbers into ``vals``
    num = "%" + spec
    pol3 = f" (pol {num} {num} {num}))"
    items: list[str] = []
    vals: list[float] = []
    objects = v.objects
    for name in LANDMARK_ORDER:
        pol = objects.get(name)
        if pol is not None:
            items.append(f"({name}{pol3}")
            vals += _floats3(pol)
    for name, pol in objects.items():
        if name not in LANDMARK_ORDER:
            items.append(f"({_esc(_checked(name, 'object name'))}{pol3}")
            vals += _floats3(pol)
    for player in v.players:
        entry = [f"(P (team {_esc(_checked(player.team, 'team name'))}) (id {int(player.unum)})"]
        for part in PLAYER_PART_ORDER:
            pol = player.parts.get(part)
            if pol is not None:
                entry.append(f" ({part}{pol3}")
                vals += _floats3(pol)
        for part, pol in player.parts.items():
            if part not in PLAYER_PART_ORDER:
                entry.append(f" ({_esc(_checked(part, 'body part'))}{pol3}")
                vals += _floats3(pol)
        entry.append(")")
        items.append("".join(entry))
    if v.my_pos is not None:
        items.append(f"(mypos {num} {num} {num})")
        vals += _floats3(v.my_pos)
    if v.my_orientation_deg is not None:
        items.append(f"(myorien {num})")
        vals.append(float(v.my_orientation_deg))
    if v.ball_pos is not None:
        items.append(f"(ballpos {num} {num} {num})")
        vals += _floats3(v.ball_pos)
    lines = np.asarray(v.lines, dtype=float).reshape(-1, 6)
    if len(lines):
        items.extend([f"(L (pol {num} {num} {num}){pol3}"] * len(lines))
        vals += lines.ravel().tolist()
    if not items:
        return "(See)"
    return ("(See " + " ".join(items) + ")") % tuple(vals)

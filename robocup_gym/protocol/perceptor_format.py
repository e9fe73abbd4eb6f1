"""Agent percepts, server side: :class:`~robocup_gym.types.Perception` → rcssserver3d 0.7.3 text.

The output is byte-compatible with the real server (protocol spec §5.1, §5.11, §5.13): one
predicate per perceptor without separators, one space before every element inside a predicate,
floats in fixed notation with 2 decimals (``-0.00`` included), integers as integers, predicates in
the Nao's model order. Units as on the wire: degrees, deg/s, m/s², m, N, s.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.values import is_atom
from robocup_gym.types import ForceResistance, GameState, HeardMessage, Perception, Vision

__all__ = ["LANDMARK_ORDER", "PLAYER_PART_ORDER", "format_perception"]

LANDMARK_ORDER = ("G1L", "G2L", "G2R", "G1R", "F1L", "F2L", "F1R", "F2R", "B")
"""Order of the landmark/ball group inside ``See`` (model order, spec §5.10)."""

PLAYER_PART_ORDER = ("head", "rlowerarm", "llowerarm", "rfoot", "lfoot")
"""Order of the visible body parts inside a ``P`` entry."""

# Model order of the joint and foot perceptors after GYR/ACC (spec §5.11). Entries starting with
# "@" are slots for See and the FRPs; joints that the robot lacks are simply skipped.
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
    spec = f".{int(decimals)}f"
    out: list[str] = [f"(time (now {format(p.time, spec)}))", _format_gs(p.game, spec)]
    out.extend(_format_hear(h, spec) for h in p.heard)
    out.append(f"(GYR (n torso) (rt {_v3(p.gyro, spec)}))")
    out.append(f"(ACC (n torso) (a {_v3(p.accel, spec)}))")
    angles = dict(
        zip(p.joint_names, np.asarray(p.joint_angles_deg, dtype=float).tolist(), strict=True)
    )
    feet = p.force_sensors
    has_rlj7 = "rlj7" in angles
    has_llj7 = "llj7" in angles
    for slot in _SEQUENCE:
        if slot[0] != "@":
            angle = angles.get(slot)
            if angle is not None:
                out.append(f"(HJ (n {slot}) (ax {format(angle, spec)}))")
            if slot == "rlj6" and not has_rlj7 and "rf1" in feet:
                out.append(_format_frp("rf1", feet["rf1"], spec))
            elif slot == "llj6" and not has_llj7 and "lf1" in feet:
                out.append(_format_frp("lf1", feet["lf1"], spec))
        elif slot == "@See":
            if p.vision is not None:
                out.append(_format_see(p.vision, spec))
        else:
            foot = slot[1:]
            if foot in feet and (foot in ("rf", "lf") or (has_rlj7 if foot == "rf1" else has_llj7)):
                out.append(_format_frp(foot, feet[foot], spec))
    for name, angle in angles.items():
        if name not in _KNOWN_JOINTS:
            out.append(f"(HJ (n {_checked(name, 'joint name')}) (ax {format(angle, spec)}))")
    for name, frp in feet.items():
        if name not in _KNOWN_FEET:
            out.append(_format_frp(name, frp, spec))
    return "".join(out)


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


def _format_see(v: Vision, spec: str) -> str:
    items: list[str] = []
    objects = v.objects
    for name in LANDMARK_ORDER:
        pol = objects.get(name)
        if pol is not None:
            items.append(f"({name} (pol {_v3(pol, spec)}))")
    for name, pol in objects.items():
        if name not in LANDMARK_ORDER:
            items.append(f"({_checked(name, 'object name')} (pol {_v3(pol, spec)}))")
    for player in v.players:
        entry = [f"(P (team {_checked(player.team, 'team name')}) (id {int(player.unum)})"]
        for part in PLAYER_PART_ORDER:
            pol = player.parts.get(part)
            if pol is not None:
                entry.append(f" ({part} (pol {_v3(pol, spec)}))")
        for part, pol in player.parts.items():
            if part not in PLAYER_PART_ORDER:
                entry.append(f" ({_checked(part, 'body part')} (pol {_v3(pol, spec)}))")
        entry.append(")")
        items.append("".join(entry))
    if v.my_pos is not None:
        items.append(f"(mypos {_v3(v.my_pos, spec)})")
    if v.my_orientation_deg is not None:
        items.append(f"(myorien {format(float(v.my_orientation_deg), spec)})")
    if v.ball_pos is not None:
        items.append(f"(ballpos {_v3(v.ball_pos, spec)})")
    lines = np.asarray(v.lines, dtype=float).reshape(-1, 6).tolist()
    for a, b, c, d, e, f in lines:
        items.append(
            f"(L (pol {format(a, spec)} {format(b, spec)} {format(c, spec)})"
            f" (pol {format(d, spec)} {format(e, spec)} {format(f, spec)}))"
        )
    if not items:
        return "(See)"
    return "(See " + " ".join(items) + ")"

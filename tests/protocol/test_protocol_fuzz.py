"""Property-based fuzzing: malformed input gives ProtocolError or a valid result, nothing else.

Budgets are small so the whole protocol suite stays fast; hypothesis' deadline is off because
the first examples include import/JIT warm-up.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from protocol_helpers import MONITOR, PERCEPTS, UPSTREAM, assert_same_perception

from robocup_gym.protocol.effectors import parse_agent_message
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.monitor import parse_monitor_message
from robocup_gym.protocol.perceptors import (
    _parse_fast,
    _parse_tree,
    format_perception,
    parse_perception,
)
from robocup_gym.protocol.sexpr import parse
from robocup_gym.protocol.trainer import parse_trainer_message
from robocup_gym.robot.nao import nao_model
from robocup_gym.types import (
    ForceResistance,
    GameState,
    HeardMessage,
    Perception,
    SeenPlayer,
    Vision,
)

FUZZ = settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
SOURCES = [*PERCEPTS[:7], UPSTREAM]


@st.composite
def mutated(draw: st.DrawFn) -> str:
    """A real message with a few random edits (delete, insert, replace a slice)."""
    text = draw(st.sampled_from(SOURCES))
    for _ in range(draw(st.integers(1, 3))):
        i = draw(st.integers(0, len(text)))
        j = draw(st.integers(i, min(len(text), i + 12)))
        insert = draw(st.text(alphabet="() .-0123456789abnHJ_\t\x00é", max_size=6))
        text = text[:i] + insert + text[j:]
    return text


@FUZZ
@given(mutated())
def test_mutated_percepts_parse_or_raise_and_paths_agree(text: str) -> None:
    try:
        result = parse_perception(text)
    except ProtocolError:
        assert _parse_fast(text, None) is None  # the fast path never accepts what fails
        return
    assert isinstance(result, Perception)
    fast = _parse_fast(text, None)
    if fast is not None:
        assert_same_perception(fast, _parse_tree(text, None))


@FUZZ
@given(st.binary(max_size=300))
def test_random_bytes_never_crash_the_percept_parser(data: bytes) -> None:
    try:
        result = parse_perception(data)
    except ProtocolError:
        return
    assert isinstance(result, Perception)  # pragma: no cover - random bytes are never valid


@FUZZ
@given(st.sampled_from(SOURCES), st.data())
def test_extra_whitespace_changes_nothing(text: str, data: st.DataObject) -> None:
    base = parse_perception(text)
    positions = [i for i, c in enumerate(text) if c in "()"]
    chosen = data.draw(st.lists(st.sampled_from(positions), max_size=5, unique=True))
    ws = data.draw(st.sampled_from([" ", "\n", "\t", "  \r\n"]))
    out = text
    for i in sorted(chosen, reverse=True):
        out = out[:i] + ws + out[i] + ws + out[i + 1 :]
    assert_same_perception(parse_perception(out), base)


_finite = st.floats(-500, 500, allow_nan=False, allow_infinity=False)
_vec = st.tuples(_finite, _finite, _finite).map(np.array)
_name = st.text(alphabet="abcXYZ019!_=", min_size=1, max_size=8)


@st.composite
def perceptions(draw: st.DrawFn) -> Perception:
    robot_type = draw(st.sampled_from([0, 4]))
    names = nao_model(robot_type).perceptor_names
    feet = draw(st.lists(st.sampled_from(["lf", "rf", "lf1", "rf1"][: 4 if robot_type else 2])))
    vision = None
    if draw(st.booleans()):
        objects = {n: draw(_vec) for n in draw(st.lists(st.sampled_from(["B", "F1L", "G2R"])))}
        players = [
            SeenPlayer(draw(_name), draw(st.integers(1, 11)), {"head": draw(_vec)})
            for _ in range(draw(st.integers(0, 2)))
        ]
        lines = np.array(draw(st.lists(st.lists(_finite, min_size=6, max_size=6), max_size=3)))
        vision = Vision(objects, players, lines.reshape(-1, 2, 3))
        if draw(st.booleans()):
            vision.my_pos, vision.my_orientation_deg, vision.ball_pos = (
                draw(_vec),
                draw(_finite),
                draw(_vec),
            )
    heard = [
        HeardMessage(
            draw(st.none() | _name),
            draw(_finite),
            draw(st.none() | _finite),
            draw(_name),
        )
        for _ in range(draw(st.integers(0, 2)))
    ]
    return Perception(
        time=draw(st.floats(0, 1e4)),
        game=GameState(
            draw(st.sampled_from(["BeforeKickOff", "PlayOn", "Goal_Left"])),
            draw(st.floats(0, 600)),
            draw(st.integers(0, 20)),
            draw(st.integers(0, 20)),
            draw(st.none() | st.integers(1, 11)),
            draw(st.none() | st.sampled_from(["left", "right"])),
        ),
        gyro=draw(_vec),
        accel=draw(_vec),
        joint_names=names,
        joint_angles_deg=np.array([draw(_finite) for _ in names]),
        force_sensors={f: ForceResistance(draw(_vec), draw(_vec)) for f in feet},
        vision=vision,
        heard=heard,
    )


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(perceptions())
def test_format_parse_round_trip_random(p: Perception) -> None:
    text = format_perception(p)
    q = parse_perception(text)
    assert q.joint_names == p.joint_names
    np.testing.assert_allclose(q.joint_angles_deg, p.joint_angles_deg, atol=0.00501)
    np.testing.assert_allclose(q.gyro, p.gyro, atol=0.00501)
    assert q.game.unum == p.game.unum and q.game.team_side == p.game.team_side
    assert (q.game.score_left, q.game.score_right) == (p.game.score_left, p.game.score_right)
    assert set(q.force_sensors) == set(p.force_sensors)
    assert [(h.team, h.message, h.is_self) for h in q.heard] == [
        (h.team, h.message, h.is_self) for h in p.heard
    ]
    assert (q.vision is None) == (p.vision is None)
    if p.vision is not None and q.vision is not None:
        assert set(q.vision.objects) == set(p.vision.objects)
        assert q.vision.lines.shape == p.vision.lines.shape
        assert len(q.vision.players) == len(p.vision.players)
    assert format_perception(q) == text  # the text is a fixed point
    fast = _parse_fast(text, None)
    assert fast is not None  # our own output always takes the fast path
    assert_same_perception(fast, _parse_tree(text, None))


@FUZZ
@given(st.text(alphabet="()abcdefhilnprsuy 0123456789.-\t", max_size=80))
def test_agent_and_trainer_parsers_only_raise_protocol_error(text: str) -> None:
    try:
        actions = parse_agent_message(text)
    except ProtocolError:
        actions = None
    try:
        commands = parse_trainer_message(text)
    except ProtocolError:
        commands = None
    assert actions is None or isinstance(actions, list)
    assert commands is None or isinstance(commands, list)
    parse_trainer_message_lenient(text)


def parse_trainer_message_lenient(text: str) -> None:
    try:
        commands = parse_trainer_message(text, strict=False)
    except ProtocolError:
        # Non-strict parsing fails only where the S-expression itself is broken.
        with pytest.raises(ProtocolError):
            parse(text)
        return
    assert isinstance(commands, list)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(MONITOR), st.integers(0, 10_000), st.integers(1, 40))
def test_damaged_monitor_frames(frame: str, start: int, length: int) -> None:
    start %= len(frame)
    broken = frame[:start] + frame[start + length :]
    try:
        frame = parse_monitor_message(broken)
    except ProtocolError:
        return
    assert frame.full in (True, False)

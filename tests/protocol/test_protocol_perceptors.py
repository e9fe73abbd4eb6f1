"""Percepts: parsing the real-server captures, formatting byte-compatible text, round trips."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from protocol_helpers import PERCEPTS, UPSTREAM, assert_same_perception

from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.perceptors import (
    _parse_fast,
    _parse_tree,
    format_perception,
    parse_perception,
)
from robocup_gym.robot.nao import nao_model, wire_perceptor_order
from robocup_gym.types import GameState, HeardMessage

CANON0 = nao_model(0).perceptor_names
CANON4 = nao_model(4).perceptor_names


def _strip_fork_gs(msg: str) -> str:
    """The fork message as upstream would print it (without the GS extras k and ti)."""
    return re.sub(r" \(k [a-z]+\) \(ti (?:\((?:\([^()]*\))*\) ?)*\)", "", msg)


# --------------------------------------------------------------------------------------------
# Real-server fixture (SPL fork, 3 decimals)
# --------------------------------------------------------------------------------------------


def test_every_fixture_message_parses() -> None:
    for i, msg in enumerate(PERCEPTS):
        p = parse_perception(msg)
        assert p.time == pytest.approx(6.74 + 0.02 * i)
        assert p.joint_names == CANON0
        assert p.joint_angles_deg.shape == (22,)
        assert p.game.play_mode == "BeforeKickOff"
        assert (p.game.score_left, p.game.score_right, p.game.game_time) == (0, 0, 0.0)
        assert p.heard == []
    seeing = [i for i, m in enumerate(PERCEPTS) if parse_perception(m).vision is not None]
    assert seeing == [0, 3, 6, 9, 12, 15, 18]  # every third cycle


def test_fixture_first_message_values() -> None:
    p = parse_perception(PERCEPTS[0])
    assert p.time == 6.74
    assert p.game == GameState("BeforeKickOff", 0.0, 0, 0, None, None)
    np.testing.assert_array_equal(p.gyro, [0.002, -0.0, 0.0])
    np.testing.assert_array_equal(p.accel, [0.0, 0.0, 0.0])
    assert p.force_sensors == {}
    assert p.vision is not None
    assert list(p.vision.objects) == ["F1L", "F1R", "B"]
    np.testing.assert_array_equal(p.vision.objects["F1L"], [18.686, 53.847, -5.134])
    np.testing.assert_array_equal(p.vision.ball, [1.890, -0.172, -57.927])
    assert p.vision.players == []
    assert p.vision.lines.shape == (0, 2, 3)


def test_fixture_unum_and_team_only_in_the_first_gs_after_init() -> None:
    games = [parse_perception(m).game for m in PERCEPTS]
    assert [(g.unum, g.team_side) for g in games[:4]] == [
        (None, None),
        (None, None),
        (1, "left"),
        (None, None),
    ]
    p = parse_perception(PERCEPTS[2])
    np.testing.assert_array_equal(p.accel, [-0.0, -0.0, 29.42])  # huge right after teleport


def test_fixture_see_with_player() -> None:
    v = parse_perception(PERCEPTS[3]).vision
    assert v is not None
    assert list(v.objects) == ["G2R", "G1R", "F1R", "F2R", "B"]
    np.testing.assert_array_equal(v.objects["G2R"], [15.975, -9.815, 1.088])
    np.testing.assert_array_equal(v.ball, [1.084, -4.739, -28.260])
    assert len(v.players) == 1
    me = v.players[0]
    assert (me.team, me.unum) == ("Probe", 1)
    assert list(me.parts) == ["rlowerarm", "llowerarm"]
    np.testing.assert_array_equal(me.parts["rlowerarm"], [0.191, -34.410, -23.377])
    np.testing.assert_array_equal(me.parts["llowerarm"], [0.190, 33.855, -23.659])
    assert v.lines.shape == (0, 2, 3)
    assert v.my_pos is None and v.ball_pos is None and v.my_orientation_deg is None


def test_fixture_joints_land_in_canonical_order() -> None:
    p = parse_perception(PERCEPTS[4])
    np.testing.assert_array_equal(p.gyro, [16.964, 14.279, 15.700])
    np.testing.assert_array_equal(p.accel, [-0.0, -0.0, 9.809])
    # canonical: hj1 hj2 laj1-4 llj1-6 rlj1-6 raj1-4
    expected = [0.314, -0.528, -1.052, -1.108, 0.718, 0.946, 0.724, -1.140, 0.819, -1.069, 0.526]
    expected += [-0.743, 0.832, 0.095, -0.459, -0.177, -1.081, -0.861, 0.244, 0.526, 0.100, 0.997]
    np.testing.assert_array_equal(p.joint_angles_deg, expected)
    assert p.joint("raj4") == 0.997
    assert p.joint("llj6") == -0.743
    assert p.joint("hj2") == -0.528
    # Every HJ value of every message is where its name says.
    for msg in PERCEPTS:
        p = parse_perception(msg)
        for name, value in re.findall(r"\(HJ \(n (\w+)\) \(ax ([-\d.]+)\)\)", msg):
            assert p.joint(name) == float(value)


def test_fixture_force_sensors() -> None:
    p = parse_perception(PERCEPTS[5])
    assert list(p.force_sensors) == ["rf"]
    np.testing.assert_array_equal(p.force_sensors["rf"].point, [-0.033, 0.080, -0.010])
    np.testing.assert_array_equal(p.force_sensors["rf"].force, [-4.853, -13.638, 101.736])
    p = parse_perception(PERCEPTS[6])
    assert sorted(p.force_sensors) == ["lf", "rf"]
    np.testing.assert_array_equal(p.force_sensors["lf"].point, [-0.012, -0.081, -0.011])
    np.testing.assert_array_equal(p.force_sensors["lf"].force, [-16.675, -24.022, 33.631])
    p = parse_perception(PERCEPTS[19])
    np.testing.assert_array_equal(p.gyro, [-57.848, 5.306, -0.845])
    assert p.joint("llj6") == -0.579
    np.testing.assert_array_equal(p.force_sensors["lf"].force, [4.703, 8.355, 45.443])
    counts = [len(parse_perception(m).force_sensors) for m in PERCEPTS]
    assert counts == [len(re.findall(r"\(FRP ", m)) for m in PERCEPTS]


def test_bytes_and_fork_format_reproduced_without_gs_extras() -> None:
    for msg in PERCEPTS:
        p = parse_perception(msg.encode("latin-1"))
        # Our writer with 3 decimals gives the fork's exact text minus (k …) (ti …).
        assert format_perception(p, decimals=3) == _strip_fork_gs(msg)


def test_fast_and_general_paths_agree_on_fixtures() -> None:
    for msg in [*PERCEPTS, UPSTREAM]:
        fast = _parse_fast(msg, None)
        assert fast is not None, "the fast path should take every real-server message"
        assert_same_perception(fast, _parse_tree(msg, None))


# --------------------------------------------------------------------------------------------
# Upstream 0.7.3 (2 decimals), §5.13 and hand-built variants
# --------------------------------------------------------------------------------------------


def test_upstream_example_values() -> None:
    p = parse_perception(UPSTREAM)
    assert p.time == 3.24
    assert p.game == GameState("BeforeKickOff", 0.0, 0, 0, None, None)
    assert p.heard == [HeardMessage(team="Alpha", time=0.0, direction_deg=None, message="Hi!")]
    assert p.heard[0].is_self
    np.testing.assert_array_equal(p.gyro, [48.49, 6.29, 28.19])
    np.testing.assert_array_equal(p.accel, [0.25, 1.46, 9.44])
    assert p.joint("hj1") == 18.33
    assert p.joint("hj2") == 0.0 and math.copysign(1, p.joint("hj2")) == -1  # "-0.00"
    assert p.joint("rlj4") == -18.33
    assert p.joint("rlj5") == 2.71
    v = p.vision
    assert v is not None
    assert list(v.objects) == ["G1R", "F1R"]
    assert v.ball is None
    np.testing.assert_array_equal(v.objects["G1R"], [18.06, -57.50, -7.67])
    assert [(pl.team, pl.unum, list(pl.parts)) for pl in v.players] == [
        ("Alpha", 1, ["rlowerarm", "llowerarm"])
    ]
    np.testing.assert_array_equal(v.players[0].parts["llowerarm"], [0.18, 16.70, -22.92])
    assert v.lines.shape == (10, 2, 3)
    np.testing.assert_array_equal(v.lines[0], [[3.08, -59.63, -18.11], [9.51, 14.85, -12.45]])
    np.testing.assert_array_equal(v.lines[9], [[1.53, -52.13, -29.99], [1.46, -60.10, -30.38]])
    np.testing.assert_array_equal(p.force_sensors["rf"].force, [12.29, 18.63, 11.66])
    np.testing.assert_array_equal(p.force_sensors["lf"].point, [0.02, -0.08, -0.01])


def test_upstream_example_is_reproduced_byte_for_byte() -> None:
    assert format_perception(parse_perception(UPSTREAM)) == UPSTREAM
    assert format_perception(parse_perception(UPSTREAM.encode())).encode() == UPSTREAM.encode()


# Snippets quoted in §5.13 (observed on the real 0.7.3 server).
GS_INIT = "(GS (unum 1) (team left) (sl 0) (sr 0) (t 0.00) (pm BeforeKickOff))"
HEAR_TWO = "(hear Alpha 0.00 self A1msg)(hear Beta 0.00 0.04 B2msg)"
GROUND_TRUTH = "(mypos -14.29 9.09 0.52) (myorien -10.29) (ballpos 0.00 0.00 0.04)"


def _variant() -> str:
    msg = UPSTREAM.replace("(GS (sl 0) (sr 0) (t 0.00) (pm BeforeKickOff))", GS_INIT)
    msg = msg.replace("(hear Alpha 0.00 self Hi!)", HEAR_TWO)
    return msg.replace(" (L (pol 3.08", f" {GROUND_TRUTH} (L (pol 3.08", 1)


def test_hand_built_upstream_variant() -> None:
    msg = _variant()
    p = parse_perception(msg)
    assert (p.game.unum, p.game.team_side) == (1, "left")
    assert p.heard == [
        HeardMessage("Alpha", 0.0, None, "A1msg"),
        HeardMessage("Beta", 0.0, 0.04, "B2msg"),
    ]
    assert p.vision is not None
    np.testing.assert_array_equal(p.vision.my_pos, [-14.29, 9.09, 0.52])
    assert p.vision.my_orientation_deg == -10.29
    np.testing.assert_array_equal(p.vision.ball_pos, [0.0, 0.0, 0.04])
    assert p.vision.lines.shape == (10, 2, 3)
    assert format_perception(p) == msg
    assert_same_perception(p, _parse_tree(msg, None))


def test_hear_without_team_label() -> None:
    msg = UPSTREAM.replace("(hear Alpha 0.00 self Hi!)", "(hear 12.34 -112.37 h8Ab=)")
    p = parse_perception(msg)
    assert p.heard == [HeardMessage(None, 12.34, -112.37, "h8Ab=")]
    assert format_perception(p) == msg


def test_type4_toes_inferred_and_ordered() -> None:
    msg = UPSTREAM.replace(
        "(HJ (n rlj6) (ax 0.00))",
        "(HJ (n rlj6) (ax 0.00))(FRP (n rf1) (c 0.00 0.01 -0.01) (f 0.50 0.00 3.00))"
        "(HJ (n rlj7) (ax 1.50))",
    ).replace("(HJ (n llj6) (ax 0.00))", "(HJ (n llj6) (ax 0.00))(HJ (n llj7) (ax -0.50))")
    p = parse_perception(msg)
    assert p.joint_names == CANON4
    assert p.joint("rlj7") == 1.5 and p.joint("llj7") == -0.5
    assert list(p.joint_names[-2:]) == ["llj7", "rlj7"]
    np.testing.assert_array_equal(p.force_sensors["rf1"].force, [0.5, 0.0, 3.0])
    assert format_perception(p) == msg
    assert tuple(re.findall(r"\(HJ \(n (\w+)\)", msg)) == wire_perceptor_order(4)
    assert parse_perception(msg, robot_type=4).joint_names == CANON4
    with pytest.raises(ProtocolError, match="unknown joint 'rlj7' for robot type 0"):
        parse_perception(msg, robot_type=0)
    with pytest.raises(ProtocolError, match="llj7, rlj7"):
        parse_perception(UPSTREAM, robot_type=4)
    assert parse_perception(UPSTREAM, robot_type=2).joint_names == CANON0
    with pytest.raises(ValueError):
        parse_perception(UPSTREAM, robot_type=5)


def test_wire_order_of_formatted_joints() -> None:
    text = format_perception(parse_perception(PERCEPTS[6]))
    names = re.findall(r"\(HJ \(n (\w+)\)", text)
    assert tuple(names) == wire_perceptor_order(0)
    # FRP rf between rlj5 and rlj6, FRP lf between llj5 and llj6; See right after hj2.
    assert "(HJ (n rlj5) (ax 0.62))(FRP (n rf)" in text
    assert "(FRP (n lf) (c -0.01 -0.08 -0.01) (f -16.68 -24.02 33.63))(HJ (n llj6)" in text
    assert "(HJ (n hj2) (ax 0.70))(See (G2R" in text


def test_nan_negative_zero_and_integers() -> None:
    msg = (
        UPSTREAM.replace("(ax 18.33)", "(ax nan)")
        .replace("(rt 48.49 6.29 28.19)", "(rt -nan inf -inf)")
        .replace("(sl 0) (sr 0)", "(sl 2) (sr 11)")
    )
    p = parse_perception(msg)
    assert math.isnan(p.joint("hj1"))
    assert math.isnan(p.gyro[0]) and p.gyro[1] == math.inf and p.gyro[2] == -math.inf
    assert (p.game.score_left, p.game.score_right) == (2, 11)
    text = format_perception(p)
    assert "(sl 2) (sr 11)" in text and "(HJ (n hj1) (ax nan))" in text
    assert "(rt nan inf -inf)" in text


def test_unknown_predicates_and_other_spacing_are_accepted() -> None:
    base = parse_perception(UPSTREAM)
    odd = UPSTREAM.replace(
        "(GYR", "(AgentState (battery 100) (temp 30))(UJ (n x) (ax1 1) (ax2 2))()(GYR"
    )
    odd = odd.replace("(See (G1R", "(See (XYZ 1 2) (G1R").replace(
        "(HJ (n raj1) (ax -0.00))", "( HJ\n(n raj1)(ax -0.00) )"
    )
    odd = odd.replace(")(HJ (n raj2)", ") \t (HJ (n raj2)")
    assert _parse_fast(odd, None) is None  # not the server's layout: general path
    assert_same_perception(parse_perception(odd), base)


def test_duplicates_last_wins() -> None:
    msg = UPSTREAM + "(HJ (n hj1) (ax 5.00))(time (now 9.00))"
    p = parse_perception(msg)
    assert p.joint("hj1") == 5.0
    assert p.time == 9.0


# --------------------------------------------------------------------------------------------
# Malformed input
# --------------------------------------------------------------------------------------------


def test_truncated_messages_are_rejected() -> None:
    for msg in (PERCEPTS[6], UPSTREAM):
        for cut in range(0, len(msg), 7):
            with pytest.raises(ProtocolError):
                parse_perception(msg[:cut])
        with pytest.raises(ProtocolError, match="unclosed"):
            parse_perception(msg[:-1])


def test_length_prefix_left_on_is_explained() -> None:
    raw = len(UPSTREAM).to_bytes(4, "big") + UPSTREAM.encode()
    with pytest.raises(ProtocolError, match="length prefix") as info:
        parse_perception(raw)
    assert info.value.offset == 0


def test_bad_values_name_predicate_and_offset() -> None:
    msg = UPSTREAM.replace("(HJ (n rlj4) (ax -18.33))", "(HJ (n rlj4) (ax abc))")
    with pytest.raises(ProtocolError, match="expected a number, got 'abc'") as info:
        parse_perception(msg)
    assert info.value.predicate == "HJ"
    assert info.value.offset == msg.index("(HJ (n rlj4)")
    with pytest.raises(ProtocolError, match="3 number"):
        parse_perception(UPSTREAM.replace("(rt 48.49 6.29 28.19)", "(rt 48.49 6.29)"))
    with pytest.raises(ProtocolError, match="integer"):
        parse_perception(UPSTREAM.replace("(sl 0)", "(sl 0.5)"))
    with pytest.raises(ProtocolError, match="needs two"):
        parse_perception(UPSTREAM.replace("(pol 9.51 14.85 -12.45)", ""))
    with pytest.raises(ProtocolError, match=r"\(team …\) and \(id …\)"):
        parse_perception(UPSTREAM.replace("(id 1) ", ""))


@pytest.mark.parametrize("name", ["time", "GS", "GYR", "ACC"])
def test_missing_required_predicates(name: str) -> None:
    msg = re.sub(rf"\({name} (?:[^()]|\([^()]*\))*\)", "", UPSTREAM, count=1)
    assert msg != UPSTREAM
    with pytest.raises(ProtocolError, match=f"no {name} predicate"):
        parse_perception(msg)


def test_missing_and_unknown_joints() -> None:
    with pytest.raises(ProtocolError, match=r"lacks the angle of joint.* raj3"):
        parse_perception(UPSTREAM.replace("(HJ (n raj3) (ax -0.00))", ""))
    with pytest.raises(ProtocolError, match="unknown joint 'hj3'"):
        parse_perception(UPSTREAM + "(HJ (n hj3) (ax 1.00))")


# --------------------------------------------------------------------------------------------
# format → parse
# --------------------------------------------------------------------------------------------


def test_format_parse_round_trip_on_fixtures() -> None:
    for msg in [*PERCEPTS, UPSTREAM, _variant()]:
        p = parse_perception(msg)
        # 3 decimals hold the fixture values exactly.
        assert_same_perception(parse_perception(format_perception(p, decimals=3)), p)
        # 2 decimals: the same structure, values to the printed precision, and stable text.
        text = format_perception(p)
        q = parse_perception(text)
        np.testing.assert_allclose(q.joint_angles_deg, p.joint_angles_deg, atol=0.0051)
        np.testing.assert_allclose(q.gyro, p.gyro, atol=0.0051)
        assert q.joint_names == p.joint_names
        assert list(q.force_sensors) == list(p.force_sensors)
        assert format_perception(q) == text


def test_format_orders_see_in_model_order() -> None:
    p = parse_perception(PERCEPTS[3])
    assert p.vision is not None
    # Insert in the wrong order; the writer uses G1L G2L G2R G1R F1L F2L F1R F2R B, then others.
    objs = p.vision.objects
    p.vision.objects = {"B": objs["B"], "X9": objs["F1R"], "F1R": objs["F1R"], "G1R": objs["G1R"]}
    p.vision.my_orientation_deg = 12.5
    text = format_perception(p)
    see = text[text.index("(See") : text.index(")(HJ (n raj1)")]
    assert [m for m in re.findall(r"\((\w+) \(pol", see) if m != "rlowerarm"][:4] == [
        "G1R",
        "F1R",
        "B",
        "X9",
    ]
    assert "(myorien 12.50)" in see
    p.vision.objects = {}
    p.vision.players = []
    p.vision.my_orientation_deg = None
    assert "(See)" in format_perception(p)


def test_format_rejects_text_that_would_corrupt_the_stream() -> None:
    p = parse_perception(UPSTREAM)
    p.heard[0].message = "two words"
    with pytest.raises(ProtocolError, match="not a single atom"):
        format_perception(p)
    p = parse_perception(UPSTREAM)
    p.game.play_mode = "Play(On"
    with pytest.raises(ProtocolError):
        format_perception(p)

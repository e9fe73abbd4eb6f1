"""Agent commands: client formatting and the lenient server-side parser."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robocup_gym.protocol.effectors import (
    HINGE_EFFECTORS,
    Beam,
    Hinge,
    Init,
    Pass,
    Say,
    Scene,
    Syn,
    Unknown,
    format_actions,
    format_command,
    format_init,
    format_scene,
    is_valid_say,
    parse_agent_message,
)
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.robot.nao import nao_model
from robocup_gym.types import AgentCommand

EFF0 = nao_model(0).effector_names


def test_format_command_mapping_beam_say_syn() -> None:
    cmd = AgentCommand(joint_velocities={"he1": 0.0, "he2": 1.25}, beam=(-1.0, 0.0, 0.0), say="hi")
    assert format_command(cmd) == "(he1 0.00)(he2 1.25)(beam -1 0 0)(say hi)(syn)"
    assert format_command(cmd, sync=False).endswith("(say hi)")
    assert format_command(AgentCommand({"rle3": -1.25}), decimals=5) == "(rle3 -1.25000)(syn)"
    assert format_command(AgentCommand()) == "(syn)"
    assert format_command(AgentCommand(beam=(-14.5, 0.25, 90))) == "(beam -14.5 0.25 90)(syn)"


def test_format_command_array_in_canonical_order() -> None:
    v = np.arange(22) / 10.0
    text = format_command(AgentCommand(joint_velocities=v))
    actions = parse_agent_message(text)
    assert [a.effector for a in actions if isinstance(a, Hinge)] == list(EFF0)
    assert [a.velocity for a in actions if isinstance(a, Hinge)] == pytest.approx(v.tolist())
    assert text.startswith("(he1 0.00)(he2 0.10)(lae1 0.20)")
    assert isinstance(actions[-1], Syn)
    text4 = format_command(AgentCommand(joint_velocities=np.zeros(24)), robot_type=4)
    assert text4.endswith("(lle7 0.00)(rle7 0.00)(syn)")
    nan = format_command(AgentCommand({"he1": math.nan, "he2": -math.inf}))
    assert nan == "(he1 nan)(he2 -inf)(syn)"


def test_format_command_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="unknown effector 'lle7' for robot type 0"):
        format_command(AgentCommand({"lle7": 1.0}))
    with pytest.raises(ValueError, match=r"shape \(22,\)"):
        format_command(AgentCommand(joint_velocities=np.zeros(24)))
    for bad in ("two words", "a(b", "x" * 21, ""):
        with pytest.raises(ValueError, match="say"):
            format_command(AgentCommand(say=bad))


def test_format_scene_and_init() -> None:
    assert format_scene(2) == "(scene rsg/agent/nao/nao_hetero.rsg 2)"
    assert format_init(7, "FCPortugal") == "(init (unum 7) (teamname FCPortugal))"
    assert format_init(0, "a") == "(init (unum 0) (teamname a))"
    with pytest.raises(ValueError):
        format_scene(5)
    with pytest.raises(ValueError):
        format_init(1, "two words")
    with pytest.raises(ValueError):
        format_init(-1, "x")


def test_parse_typical_client_messages() -> None:
    assert parse_agent_message("(scene rsg/agent/nao/nao_hetero.rsg 2)(syn)") == [
        Scene("rsg/agent/nao/nao_hetero.rsg", 2, ("2",)),
        Syn(),
    ]
    assert parse_agent_message("(scene rsg/agent/nao/nao.rsg)") == [
        Scene("rsg/agent/nao/nao.rsg", 0, ())
    ]
    assert parse_agent_message("(scene rsg/agent/soccerbot.rsg)") == [
        Scene("rsg/agent/soccerbot.rsg", None, ())
    ]
    # Sub-lists of init are found by name, in any order; RobocupGym writes no spaces.
    assert parse_agent_message("(init (teamname wits_test)(unum 1))(syn)(syn)") == [
        Init(1, "wits_test"),
        Syn(),
        Syn(),
    ]
    assert parse_agent_message("(init)") == [Init(0, "")]
    msg = "(he1 0.10000)(rle3 -1.25000)(beam -14.5 0.0 0)(say h8Ab=)(pass)(syn)"
    assert parse_agent_message(msg) == [
        Hinge("he1", 0.1),
        Hinge("rle3", -1.25),
        Beam(-14.5, 0.0, 0.0),
        Say("h8Ab="),
        Pass(),
        Syn(),
    ]
    assert parse_agent_message(b"(he1 0)(he2 0)(syn)") == parse_agent_message(
        "(he1 0) (he2 0) (syn)"
    )


def test_parse_is_lenient_like_the_server() -> None:
    got = parse_agent_message(
        "(he1 abc)(he2 1.5xyz)(lae1)(lae2 (1))(rle7 3.7 9)"
        "(beam 1 2)(beam (1) 2 3)(beam a b c)"
        "(say)(say two words)(say abcdefghijklmnopqrstu)(say abcdefghijklmnopqrst)"
        "lonely_atom ()((x))(kick 1 (a b))(syn extra)(pass 1)(init (unum 3.7) (teamname))"
    )
    assert got == [
        Hinge("he1", 0.0),  # non-numeric -> 0 (atof)
        Hinge("he2", 1.5),  # numeric prefix
        Hinge("rle7", 3.7),  # known toe effector; extra values ignored
        Beam(0.0, 0.0, 0.0),  # (beam 1 2) and (beam (1) …) dropped
        Say("two"),  # extra atoms after the first are ignored
        Say("abcdefghijklmnopqrst"),  # 20 chars ok, 21 dropped
        Unknown("kick", ("1", ["a", "b"])),
        Syn(),
        Pass(),
        Init(3, ""),
    ]


def test_nan_and_inf_velocities_are_kept() -> None:
    a, b, c = parse_agent_message("(he1 nan)(he2 -inf)(lle1 1e400)")
    assert isinstance(a, Hinge) and math.isnan(a.velocity)
    assert isinstance(b, Hinge) and b.velocity == -math.inf
    assert isinstance(c, Hinge) and c.velocity == math.inf


def test_structural_errors_raise() -> None:
    for bad in ("(he1 0", "(he1 0))", "(syn)(", ")"):
        with pytest.raises(ProtocolError):
            parse_agent_message(bad)


def test_say_validation() -> None:
    assert is_valid_say("!~azAZ09")
    assert is_valid_say('a"b')
    assert not is_valid_say("a b")
    assert not is_valid_say("é")
    assert not is_valid_say("")
    assert not is_valid_say("x" * 21)


_velocity = st.floats(allow_nan=False, width=64) | st.sampled_from([math.inf, -math.inf, -0.0])
_coord = st.floats(-1e6, 1e6, allow_nan=False)
_action = st.one_of(
    st.builds(Hinge, st.sampled_from(sorted(HINGE_EFFECTORS)), _velocity),
    st.builds(Beam, _coord, _coord, _coord),
    st.builds(
        Say,
        st.text(
            alphabet=st.characters(
                min_codepoint=0x21, max_codepoint=0x7E, blacklist_characters="()"
            ),
            min_size=1,
            max_size=20,
        ),
    ),
    st.builds(Init, st.integers(0, 11), st.sampled_from(["", "Alpha", "wits_test"])),
    st.builds(Scene, st.just("rsg/agent/nao/nao_hetero.rsg"), st.integers(0, 4)).map(
        lambda s: Scene(s.path, s.robot_type, (str(s.robot_type),))
    ),
    st.just(Pass()),
    st.just(Syn()),
    st.builds(Unknown, st.sampled_from(["kick", "foo"]), st.just(("1", ["a", "2"]))),
)


@settings(max_examples=120, deadline=None)
@given(st.lists(_action, max_size=8))
def test_format_parse_round_trip(actions: list) -> None:
    assert parse_agent_message(format_actions(actions)) == actions

"""Monitor/trainer commands: text helpers, typed formatting and the server-side parser."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robocup_gym.protocol import trainer as tr
from robocup_gym.protocol.constants import PLAY_MODES
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.trainer import (
    AgentCmd,
    BallCmd,
    DropBallCmd,
    GetAckCmd,
    InvalidCmd,
    KickOffCmd,
    KillCmd,
    KillSimCmd,
    PlayModeCmd,
    ReposCmd,
    ReqFullStateCmd,
    ScoreCmd,
    SelectCmd,
    TimeCmd,
    UnknownCmd,
    format_trainer_command,
    format_trainer_commands,
    parse_trainer_command,
    parse_trainer_message,
)


def test_text_helpers() -> None:
    assert tr.ball((1, 0, 0.042), (0, 0, 0)) == "(ball (pos 1 0 0.042) (vel 0 0 0))"
    assert tr.ball(vel=(0.5, -1, 0)) == "(ball (vel 0.5 -1 0))"
    assert (
        tr.agent_pos(1, "Left", (-1, 0, 0.385)) == "(agent (unum 1) (team Left) (pos -1 0 0.385))"
    )
    assert (
        tr.agent_move(7, "Left", (-3.0, 0.5, 0.5), -90)
        == "(agent (unum 7) (team Left) (move -3 0.5 0.5 -90))"
    )
    assert tr.agent(2, "Right", battery=50, temperature=20.5) == (
        "(agent (unum 2) (team Right) (battery 50) (temperature 20.5))"
    )
    assert tr.play_mode("PlayOn") == "(playMode PlayOn)"
    assert tr.set_time(0) == "(time 0)"
    assert tr.kick_off("Left") == "(kickOff Left)"
    assert tr.kick_off() == "(kickOff None)"
    assert tr.drop_ball() == "(dropBall)"
    assert tr.kill(7, "Right") == "(kill (unum 7) (team Right))"
    assert tr.kill() == "(kill)"
    assert tr.repos(3, "Left") == "(repos (unum 3) (team Left))"
    assert tr.select(-1) == "(select (unum -1))"
    assert tr.select() == "(select)"
    assert tr.killsim() == "(killsim)"
    assert tr.reqfullstate() == "(reqfullstate)"
    assert tr.get_ack() == "(getAck)"
    assert tr.score(2, 1) == "(score (left 2) (right 1))"


def test_helpers_reject_invalid_values() -> None:
    with pytest.raises(ValueError, match="play mode"):
        tr.play_mode("playon")
    with pytest.raises(ValueError, match="team"):
        tr.agent_pos(1, "left", (0, 0, 0))
    with pytest.raises(ValueError, match="team"):
        tr.kick_off("Random")
    with pytest.raises(ValueError, match="3 numbers"):
        tr.ball((1, 2))
    with pytest.raises(ValueError, match=">= 0"):
        tr.score(-1, 0)


def test_parse_client_examples_from_the_spec() -> None:
    msg = (
        "(agent (unum 7) (team Left) (move -3.0 0.5 0.5 -90))(ball (pos 1 0 0.042) (vel 0 0 0))"
        "(time 0)(playMode PlayOn)(kill (unum 7) (team Right))(killsim)"
        "(agent (unum 1)(team Left) (move 1 2 0.4 270.0))(agent (team Left)(unum 3)(pos 1 2 3))"
        "(kickOff Left)(dropBall)(reqfullstate)(init)(getAck)(select)(repos)"
        "(score (right 2) (left 1))"
    )
    assert parse_trainer_message(msg) == [
        AgentCmd(7, "Left", move=(-3.0, 0.5, 0.5, -90.0)),
        BallCmd((1.0, 0.0, 0.042), (0.0, 0.0, 0.0)),
        TimeCmd(0.0),
        PlayModeCmd("PlayOn"),
        KillCmd(7, "Right"),
        KillSimCmd(),
        AgentCmd(1, "Left", move=(1.0, 2.0, 0.4, 270.0)),
        AgentCmd(3, "Left", pos=(1.0, 2.0, 3.0)),
        KickOffCmd("Left"),
        DropBallCmd(),
        ReqFullStateCmd(),
        UnknownCmd("init"),
        GetAckCmd(),
        SelectCmd(),
        ReposCmd(),
        ScoreCmd(1, 2),
    ]


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("(ball (pos 1 2))", "needs 3"),
        ("(ball (vel a b c))", "number"),
        ("(agent (unum 1) (team left) (pos 1 2 3))", "team must be"),
        ("(agent (unum x) (team Left))", "integer"),
        ("(agent (unum 1) (team Left) (move 1 2 3))", "needs 4"),
        ("(playMode Foo)", "unknown play mode"),
        ("(playMode)", "exactly one"),
        ("(kickOff Random)", "Left, Right or None"),
        ("(time soon)", "number"),
        ("(score (left 1))", "both"),
        ("(score (left -1) (right 0))", ">= 0"),
        ("(select (unum 1.5))", "integer"),
    ],
)
def test_malformed_commands_raise(text: str, match: str) -> None:
    msg = "(dropBall)" + text
    with pytest.raises(ProtocolError, match=match) as info:
        parse_trainer_message(msg)
    assert info.value.offset == len("(dropBall)")
    assert info.value.predicate == text[1:].split(" ")[0].rstrip(")")
    # Non-strict: the bad command is reported, the others survive (as the server ignores it).
    got = parse_trainer_message(msg + "(killsim)", strict=False)
    assert got[0] == DropBallCmd() and got[-1] == KillSimCmd()
    assert isinstance(got[1], InvalidCmd)


def test_structure_errors_always_raise() -> None:
    with pytest.raises(ProtocolError):
        parse_trainer_message("(ball (pos 1 2 3)", strict=False)
    assert parse_trainer_message("junk (killsim) ()") == [KillSimCmd()]


def test_parse_single_command() -> None:
    assert parse_trainer_command("(time 12.5)") == TimeCmd(12.5)
    assert parse_trainer_command(["playMode", "Goal_Left"]) == PlayModeCmd("Goal_Left")
    with pytest.raises(ProtocolError):
        parse_trainer_command("(time 1)(time 2)")
    with pytest.raises(ProtocolError):
        parse_trainer_command(["ball", ["pos", "1"]])


_f = st.floats(-1e5, 1e5, allow_nan=False)
_v3 = st.tuples(_f, _f, _f)
_team = st.sampled_from(["Left", "Right"])
_who = st.tuples(st.none() | st.integers(-1, 11), st.none() | _team)
_cmd = st.one_of(
    st.builds(BallCmd, st.none() | _v3, st.none() | _v3),
    st.builds(
        AgentCmd,
        st.none() | st.integers(1, 11),
        st.none() | _team,
        st.none() | _v3,
        st.none() | st.tuples(_f, _f, _f, _f),
        st.none() | _f,
        st.none() | _f,
        st.none() | _v3,
    ),
    st.builds(PlayModeCmd, st.sampled_from(PLAY_MODES)),
    st.builds(KickOffCmd, st.sampled_from(["Left", "Right", "None"])),
    st.builds(TimeCmd, st.floats(0, 1e4)),
    st.builds(ScoreCmd, st.integers(0, 99), st.integers(0, 99)),
    _who.map(lambda w: SelectCmd(*w)),
    _who.map(lambda w: KillCmd(*w)),
    _who.map(lambda w: ReposCmd(*w)),
    st.sampled_from([DropBallCmd(), ReqFullStateCmd(), KillSimCmd(), GetAckCmd()]),
    st.just(UnknownCmd("init")),
)


@settings(max_examples=150, deadline=None)
@given(st.lists(_cmd, max_size=6))
def test_format_parse_round_trip(cmds: list) -> None:
    text = format_trainer_commands(cmds)
    assert parse_trainer_message(text) == cmds
    assert all(format_trainer_command(c) in text for c in cmds)


def test_the_forks_rot_angles_and_orientations_convert_both_ways() -> None:
    """``(rot rx ry rz)`` sets the torso to ``Rx·Ry·Rz`` (measured on the SPL fork: the
    monitor's torso orientation equals :func:`quat_from_rot` to 1e-4 for five rotations)."""
    import numpy as np

    from robocup_gym.protocol.trainer import agent, quat_from_rot, rot_from_quat

    rng = np.random.default_rng(0)
    for _ in range(200):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        back = quat_from_rot(rot_from_quat(q))
        assert min(np.abs(back - q).max(), np.abs(back + q).max()) < 1e-12
    # about one axis: the angle itself
    np.testing.assert_allclose(
        quat_from_rot((30.0, 0.0, 0.0)), [0.9659258, 0.258819, 0, 0], atol=1e-6
    )
    assert rot_from_quat(quat_from_rot((10.0, -20.0, 30.0))) == pytest.approx((10.0, -20.0, 30.0))
    text = agent(1, "Left", move=(1.0, 2.0, 0.06, -90.0), rot=(10.0, -20.0, 30.5))
    assert text == "(agent (unum 1) (team Left) (move 1 2 0.06 -90) (rot 10 -20 30.5))"
    assert parse_trainer_command(text).rot == (10.0, -20.0, 30.5)

"""RCSSServerMJ's wire formats: perception messages into :class:`Perception` (with the league
robots' axes turned into SimSpark's torso axes), PD commands into text, and the RSMP monitor
stream into the ball's position."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robocup_gym.envs.observations import heading_frame, torso_axes
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.league import (
    LeagueMonitorReader,
    format_pd_commands,
    from_simspark_torso_quat,
    parse_league_perception,
    to_simspark_torso_quat,
)
from robocup_gym.types import PDCommand

MSG = (
    b"(time (now 1.02))(GS (t 0.0)(pm BeforeKickOff)(tl A)(sl 1)(sr 2))"
    b"(quat (n torso_quat) (q 0.836 -0.0 -0.548 -0.0))(pos (n torso_pos) (p 0.151 0.0 0.241))"
    b"(GYR (n torso_gyro) (rt 1.5 -26.22 -0.13))(ACC (n torso_acc) (a 6.88 -0.5 4.16))"
    b"(HJ (n q_hj1)(ax 3.5)(vx -1.0))(HJ (n q_hj2)(ax -20.52)(vx 14.93))"
    b"(TCH n lf val 1)"
    b"(See (B (pol 2.1 8.17 -2.67))(l_llf (pol 45.97 -32.21 -1.36))"
    b"(P (team B)(id 3)(head (pol 4.0 10.0 1.0))))"
)


def test_a_perception_is_parsed_in_the_librarys_units_and_axes():
    p = parse_league_perception(MSG)
    assert p.time == pytest.approx(1.02)
    assert p.game.play_mode == "BeforeKickOff" and (p.game.score_left, p.game.score_right) == (1, 2)
    assert p.joint_names == ("q_hj1", "q_hj2")
    np.testing.assert_allclose(p.joint_angles_deg, [3.5, -20.52])
    np.testing.assert_allclose(p.joint_velocities_deg_s, [-1.0, 14.93])
    # model axes (x forward, y left) -> SimSpark torso axes (x right, y forward)
    np.testing.assert_allclose(p.gyro, [26.22, 1.5, -0.13])
    np.testing.assert_allclose(p.accel, [0.5, 6.88, 4.16])
    np.testing.assert_allclose(p.raw_torso_pos, [0.151, 0.0, 0.241])
    assert p.touch == {"lf": True}
    np.testing.assert_allclose(p.vision.ball, [2.1, 8.17, -2.67])
    assert "l_llf" in p.vision.objects
    assert p.vision.players[0].team == "B" and p.vision.players[0].unum == 3
    np.testing.assert_allclose(p.vision.players[0].parts["head"], [4.0, 10.0, 1.0])
    ordered = parse_league_perception(MSG, ("q_hj2", "q_hj1"))
    np.testing.assert_allclose(ordered.joint_angles_deg, [-20.52, 3.5])


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (b"(GS (t 0.0))(GYR (n g) (rt 0 0 0))(ACC (n a) (a 0 0 9.8))", "without \\(time"),
        (b"(time (now 1))(GYR (n g) (rt 0 0))(ACC (n a) (a 0 0 9.8))", "GYR without \\(rt"),
        (b"(time (now 1))(GYR (n g) (rt 0 0 x))(ACC (n a) (a 0 0 9.8))", "malformed GYR"),
        (b"(time (now 1))(ACC (n a) (a 0 0 9.8))", "without GYR and ACC"),
        (b"(time (now 1)", "unclosed|truncated"),
        (b"(time (now 1))(GYR (n g) (rt 0 0 0))(ACC (n a) (a 0 0 9.8))(See (B (zz 1)))", "See"),
    ],
)
def test_malformed_perceptions_are_named(text, match):
    with pytest.raises(ProtocolError, match=match):
        parse_league_perception(text)


def test_missing_joints_are_named():
    with pytest.raises(ProtocolError, match="no HJ for q_llj4"):
        parse_league_perception(MSG, ("q_hj1", "q_llj4"))


def test_orientations_turn_into_simspark_torso_axes():
    # a league robot facing world +x (model x forward): SimSpark's forward axis (+y) is world +x
    q = to_simspark_torso_quat((1.0, 0.0, 0.0, 0.0))
    assert heading_frame(q) == pytest.approx((1.0, 0.0))
    axes = torso_axes(q)
    np.testing.assert_allclose(axes, [1, 0, 0, 0, 0, 1], atol=1e-12)
    # turned 90° left: facing +y
    h = math.radians(90) / 2
    c, s = heading_frame(to_simspark_torso_quat((math.cos(h), 0.0, 0.0, math.sin(h))))
    assert (c, s) == pytest.approx((0.0, 1.0))
    assert np.linalg.norm(q) == pytest.approx(1.0)
    # pitched forward 30° (about the model's +y, its left): SimSpark's forward axis dips 30°,
    # its up axis leans forward
    p = math.radians(30) / 2
    f = torso_axes(to_simspark_torso_quat((math.cos(p), 0.0, math.sin(p), 0.0)))
    np.testing.assert_allclose(
        f, [math.cos(2 * p), 0, -math.sin(2 * p), math.sin(2 * p), 0, math.cos(2 * p)], atol=1e-12
    )
    # rolled 20° to the right (about the model's +x, its forward): SimSpark's x (right) dips
    r = math.radians(20) / 2
    qs = to_simspark_torso_quat((math.cos(r), math.sin(r), 0.0, 0.0))
    w, x, y, z = qs
    right_z = 2 * (x * z - w * y)  # world z of the torso's x axis
    assert right_z == pytest.approx(-math.sin(2 * r))
    # and back
    rng = np.random.default_rng(0)
    for _ in range(20):
        g = rng.normal(size=4)
        g /= np.linalg.norm(g)
        np.testing.assert_allclose(
            from_simspark_torso_quat(to_simspark_torso_quat(g)), g, atol=1e-12
        )


def test_pd_commands_are_written_exactly():
    text = format_pd_commands(
        {"he1": PDCommand(30.0, 0.5, 20.0, 1.0, -0.25), "lle4": PDCommand(1e-3)}
    )
    assert text == b"(he1 30.0 0.5 20.0 1.0 -0.25)(lle4 0.001 0.0 0.0 0.0 0.0)(syn)"


def _slt(x: float, y: float, z: float) -> str:
    return f"(SLT 1 0 0 0 0 1 0 0 0 0 1 0 {x} {y} {z} 1)"


def test_the_monitor_stream_gives_the_ball():
    r = LeagueMonitorReader()
    assert r.ball_position() is None
    full = (
        f"((RSMP 1 0)((gt 1 0)1.50)((sg 1 0)full(nd TRF{_slt(0, 0, 0)}"
        f"(nd DSC(ball)(nd TRF{_slt(1.0, 2.0, 0.11)}(nd SMN (load StdUnitSphere)))))"
        f"(nd TRF{_slt(5, 0, 0)})))"
    )
    r.feed(full.encode())
    assert r.time == pytest.approx(1.5)
    np.testing.assert_allclose(r.ball_position(), [1.0, 2.0, 0.11])
    diff = f"((RSMP 1 0)((gt 1 0)1.54)((sg 1 0)diff(nd(nd(nd TRF{_slt(1.5, 2.0, 0.2)}(nd))))(nd)))"
    r.feed(diff.encode())
    np.testing.assert_allclose(r.ball_position(), [1.5, 2.0, 0.2])
    assert r.time == pytest.approx(1.54) and r.messages == 2
    with pytest.raises(ProtocolError, match="not an RSMP"):
        r.feed(b"(RSG 0 1)")
    with pytest.raises(ProtocolError, match="delta before any full scene"):
        LeagueMonitorReader().feed(diff.encode())

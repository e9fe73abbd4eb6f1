"""Server parts without the network: team rules, referee, world rebuilds, wire helpers."""

from __future__ import annotations

import socket

import numpy as np
import pytest

from robocup_gym.protocol.framing import FrameDecoder
from robocup_gym.server.wire import Connection, fast_joint_message, salvage
from robocup_gym.server.worldhost import WorldHost
from robocup_gym.sim import ENGINES
from robocup_gym.sim.referee import Referee, next_kickoff_side
from robocup_gym.sim.teams import InitError, Player, TeamRegistry
from robocup_gym.sim.vision import VisionConfig


# ---------------------------------------------------------------------------- team rules
def test_fc_portugal_team_composition_is_accepted():
    teams = TeamRegistry()
    for unum, t in enumerate((0, 1, 1, 1, 2, 3, 3, 3, 4, 4, 4), start=1):
        assert teams.register("FCPortugal", unum, t) == ("left", unum)
    with pytest.raises(InitError, match="already has 11"):
        teams.register("FCPortugal", 0, 0)


def test_type_limits_and_numbers():
    teams = TeamRegistry()
    for _ in range(7):
        teams.register("A", 0, 0)
    with pytest.raises(InitError, match="more than 7 robots of type 0"):
        teams.register("A", 0, 0)
    teams.register("A", 0, 1)
    teams.register("A", 0, 1)
    with pytest.raises(InitError, match="two most used"):
        teams.register("A", 0, 1)
    teams.register("A", 0, 2)
    teams.register("A", 0, 2)
    assert sorted(teams.members["left"]) == list(range(1, 12))
    with pytest.raises(InitError, match="already has 11"):
        teams.register("A", 0, 3)
    teams.release("left", 4)
    assert teams.register("A", 0, 3) == ("left", 4)  # the lowest free number
    assert teams.register("B", 3, 0) == ("right", 3)
    with pytest.raises(InitError, match="already taken"):
        teams.register("B", 3, 0)
    with pytest.raises(InitError, match="already"):
        teams.register("C", 1, 0)  # a third team
    with pytest.raises(InitError, match="outside"):
        teams.register("B", 12, 0)
    with pytest.raises(InitError, match="empty"):
        teams.register("", 1, 0)


def test_sideline_slots():
    teams = TeamRegistry()
    assert teams.next_slot("left") == (-14.2, 9.2, 0.4, 0.0)
    x, y, z, h = teams.next_slot("left")
    assert (x, round(y, 6), z, h) == (-14.2, 8.0, 0.4, 0.0)
    assert teams.next_slot("right") == (14.2, 9.2, 0.4, 180.0)


# ---------------------------------------------------------------------------- world host
@pytest.mark.parametrize("engine", ENGINES)
def test_rebuild_keeps_the_state_of_surviving_robots(engine):
    host = WorldHost(VisionConfig(noise=False), seed=3, engine=engine)
    host.change_robots([(10, 0)], [])
    w = host.world
    w.place_robot(0, -2.0, 1.0, z=0.4, heading_deg=30.0, joint_angles_deg={"he1": 20.0})
    w.set_team(0, "left", "A", 5)
    w.set_motor_targets(0, np.full(22, 0.5))
    w.place_ball((3.0, 1.0, 0.042), (1.0, 0.0, 0.0))
    w.time = 12.34
    torso = w.torso_position(0)
    angles = w.joint_angles_deg(0)
    host.change_robots([(11, 4), (12, 2)], [])
    w2 = host.world
    assert w2 is not w and w2.n_robots == 3
    assert host.index(10) == 0 and host.index(11) == 1 and host.index(12) == 2
    np.testing.assert_allclose(w2.torso_position(0), torso)
    np.testing.assert_allclose(w2.joint_angles_deg(0), angles)
    np.testing.assert_allclose(w2.motor_targets(0), 0.5)
    assert (w2.robots[0].team, w2.robots[0].team_name, w2.robots[0].unum) == ("left", "A", 5)
    np.testing.assert_allclose(w2.ball_position(), [3.0, 1.0, 0.042])
    np.testing.assert_allclose(w2.ball_velocity(), [1.0, 0.0, 0.0])
    assert w2.time == 12.34
    assert w2.robots[1].model.robot_type.has_toes
    np.testing.assert_allclose(w2.torso_position(1)[2], 1.5)  # the pre-init spot
    host.change_robots([], [10])
    assert host.world.n_robots == 2 and host.index(10) is None and host.index(11) == 0
    np.testing.assert_allclose(host.world.ball_position(), [3.0, 1.0, 0.042])


@pytest.mark.parametrize("engine", ENGINES)
def test_a_rebuild_does_not_change_a_moving_robots_future(engine):
    """A robot in motion goes on exactly as if no robot had joined (one far away does)."""
    rng = np.random.default_rng(0)
    commands = rng.uniform(-3.0, 3.0, (40, 22))
    hosts = [WorldHost(VisionConfig(noise=False), seed=3, engine=engine) for _ in range(2)]
    for host in hosts:
        host.change_robots([(10, 0)], [])
        host.world.place_robot(0, 5.0, 5.0, heading_deg=30.0)
        host.world.place_ball((-3.0, 0.0))
    for k, cmd in enumerate(commands):
        for h, host in enumerate(hosts):
            if k == 20 and h == 1:  # joins mid-motion, far from robot 10
                host.change_robots([(11, 2)], [])
            host.world.command(0, cmd)
            host.world.step()
    a, b = (host.world for host in hosts)
    assert b.n_robots == 2
    assert np.abs(a.joint_angles_deg(0)).max() > 10.0  # it did move
    np.testing.assert_allclose(b.torso_position(0), a.torso_position(0), atol=1e-9)
    np.testing.assert_allclose(b.joint_angles_deg(0), a.joint_angles_deg(0), atol=1e-7)
    np.testing.assert_allclose(b.torso_quat(0), a.torso_quat(0), atol=1e-9)


@pytest.mark.parametrize("engine", ENGINES)
def test_recover_restores_clocks_teams_and_homes(engine):
    host = WorldHost(seed=1, engine=engine)
    host.change_robots([(1, 0)], [])
    w = host.world
    w.set_team(0, "left", "A", 1)
    host.slots[0].home = (-14.2, 9.2, 0.4, 0.0)
    w.time, w.game.game_time, w.game.play_mode = 3.0, 2.0, "PlayOn"
    host.recover()
    assert host.world.time == 3.0 and host.world.game.play_mode == "PlayOn"
    assert host.world.robots[0].unum == 1
    np.testing.assert_allclose(host.world.torso_position(0)[:2], [-14.2, 9.2])
    assert host.divergences == 1


# ---------------------------------------------------------------------------- referee
@pytest.fixture
def game():
    host = WorldHost(VisionConfig(noise=False), seed=2)
    host.change_robots([(1, 0), (2, 0)], [])
    w = host.world
    w.set_team(0, "left", "A", 1)
    w.set_team(1, "right", "B", 1)
    w.place_robot(0, -5.0, 5.0, z=0.4)
    w.place_robot(1, 5.0, 5.0, z=0.4, heading_deg=180.0)
    ref = Referee(host)
    ref.teams.register("A", 1, 0)
    ref.teams.register("B", 1, 0)
    players = [Player(1, 0, "left", 1), Player(2, 1, "right", 1)]
    return host, ref, players


def _settle(host, ref, players, cycles):
    for _ in range(cycles):
        host.world.game.game_time += 0.02  # the clock runs as in World.step
        ref.update(players)


def test_goal_scores_and_restarts_with_kickoff(game):
    host, ref, players = game
    ref.set_play_mode("PlayOn")
    host.set_ball((15.1, 0.2, 0.042), (0, 0, 0))
    _settle(host, ref, players, 1)
    assert ref.play_mode == "Goal_Left"
    assert host.world.game.score_left == 1
    # what players beaming in the pause are told to expect
    assert next_kickoff_side(ref.play_mode, host.world.game.game_time) == "right"
    _settle(host, ref, players, 151)
    assert ref.play_mode == "KickOff_Right"
    assert next_kickoff_side(ref.play_mode, host.world.game.game_time) is None
    np.testing.assert_allclose(host.ball_state()[0][:2], [0, 0], atol=1e-6)


def test_ball_out_gives_kick_in_and_goal_kick(game):
    host, ref, players = game
    ref.set_play_mode("PlayOn")
    ref.last_touch = players[0]
    host.set_ball((3.0, -10.2, 0.042), (0, 0, 0))
    _settle(host, ref, players, 1)
    assert ref.play_mode == "KickIn_Right"
    _settle(host, ref, players, 60)  # after the 1 s pause the ball is held at the spot
    p = host.ball_state()[0]
    assert abs(p[1] + 9.958) < 1e-3
    ref.set_play_mode("PlayOn")
    ref.last_touch = players[0]  # over its own goal line: corner for the attackers
    host.set_ball((-15.2, 4.0, 0.042), (0, 0, 0))
    _settle(host, ref, players, 1)
    assert ref.play_mode == "corner_kick_right"
    _settle(host, ref, players, 60)
    np.testing.assert_allclose(host.ball_state()[0][:2], [-14.958, 5.483], atol=1e-3)
    ref.set_play_mode("PlayOn")
    ref.last_touch = players[0]
    host.set_ball((15.2, 4.0, 0.042), (0, 0, 0))
    _settle(host, ref, players, 1)
    assert ref.play_mode == "goal_kick_right"


def test_a_ball_off_the_field_that_nobody_touched_stays_in_play(game):
    """rcssserver3d awards no set piece for a ball that left the field without a toucher (a
    trainer parked it there), nor for one last touched by a player who has left the game."""
    host, ref, players = game
    ref.set_play_mode("PlayOn")
    host.set_ball((20.0, 10.0, 0.042), (0, 0, 0))
    _settle(host, ref, players, 5)
    assert ref.play_mode == "PlayOn"
    np.testing.assert_allclose(host.ball_state()[0][:2], [20.0, 10.0], atol=1e-6)
    ref.last_touch = players[0]
    _settle(host, ref, players[1:], 1)  # the toucher left
    assert ref.last_touch is None and ref.play_mode == "PlayOn"
    ref.last_touch = players[1]
    _settle(host, ref, players, 1)
    assert ref.play_mode == "corner_kick_left"  # the right team put it over its own goal line


def test_before_kickoff_and_half_time(game):
    host, ref, players = game
    host.teleport(0, (3.0, 0.0, 0.4))  # left robot in the right half
    host.set_ball((2.0, 2.0, 0.042), (0, 0, 0))
    _settle(host, ref, players, 1)
    assert host.world.torso_position(0)[0] < 0
    np.testing.assert_allclose(host.ball_state()[0][:2], [0, 0], atol=1e-6)
    assert next_kickoff_side(ref.play_mode, host.world.game.game_time) == "left"
    ref.kick_off("None")
    assert ref.play_mode == "KickOff_Left"
    host.world.game.game_time = 299.99
    _settle(host, ref, players, 1)
    assert ref.play_mode == "BeforeKickOff" and ref.half == 2
    assert next_kickoff_side(ref.play_mode, host.world.game.game_time) == "right"
    ref.kick_off("None")
    assert ref.play_mode == "KickOff_Right"
    host.world.game.game_time = 600.0
    _settle(host, ref, players, 1)
    assert ref.play_mode == "GameOver"


def test_drop_ball_clears_the_circle(game):
    host, ref, players = game
    host.teleport(1, (14.0, 0.5, 0.4))
    host.set_ball((14.5, 0.0, 0.042), (0, 0, 0))
    ref.players = players
    ref.drop_ball()
    p = host.ball_state()[0]
    assert (p[0], abs(p[1])) == (13.2, 3.0)  # out of the penalty area
    assert np.hypot(*(host.world.torso_position(1)[:2] - p[:2])) >= 2.0
    assert ref.play_mode == "PlayOn"


def test_rules_off_changes_nothing(game):
    host, _, players = game
    ref = Referee(host, rules=False)
    ref.set_play_mode("PlayOn")
    host.set_ball((15.5, 0.0, 0.042), (0, 0, 0))
    _settle(host, ref, players, 3)
    assert ref.play_mode == "PlayOn"


# ---------------------------------------------------------------------------- wire
def test_salvage_keeps_complete_expressions():
    assert salvage("(a 1))(b (c))(d") == [["a", "1"], ["b", ["c"]]]
    assert salvage(")))") == []
    assert salvage("(" * 100 + "x" + ")" * 100) != []


def test_fast_joint_message():
    assert fast_joint_message(b"(he1 0.50000)(rle3 -1e-3)(syn)") == (
        [("he1", "0.50000"), ("rle3", "-1e-3")],
        True,
    )
    assert fast_joint_message(b"(he1 0.5)") == ([("he1", "0.5")], False)
    for other in (b"(beam 1 2 3)", b"(he1 nan)", b"(he1 1 2)", b"(he1 1.5x)", b"(say hi)"):
        assert fast_joint_message(other) is None


def test_connection_never_blocks_and_keeps_frames_whole():
    a, b = socket.socketpair()
    try:
        a.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)
        conn = Connection(a, 1, "pair", "monitor")
        frame = b"\x00\x00\x40\x00" + b"x" * 0x4000
        sent = sum(conn.send(frame) for _ in range(200))  # nobody reads: must not block
        assert conn.frames_dropped > 0 and sent < 200
        # what arrives is a sequence of whole frames
        b.setblocking(False)
        decoder = FrameDecoder()
        for _ in range(10000):
            try:
                chunk = b.recv(1 << 20)
            except BlockingIOError:
                if conn._tail is None:
                    break
                conn._flush_tail()
                continue
            for got in decoder.feed(chunk):
                assert got == frame[4:]
        assert decoder.pending == 0 and conn._tail is None
    finally:
        a.close()
        b.close()

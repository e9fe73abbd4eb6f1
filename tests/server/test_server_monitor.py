"""Monitor port: the RSG/RDS stream RoboViz reads, and trainer commands."""

from __future__ import annotations

import socket
import time
from pathlib import Path

import numpy as np
import pytest

from robocup_gym.protocol.constants import PLAY_MODES
from robocup_gym.protocol.perceptors import parse_perception
from robocup_gym.protocol.scenegraph import SceneGraph, parse_delta_nodes, parse_scene_nodes
from robocup_gym.protocol.sexpr import parse
from robocup_gym.server.monitor import ENVIRONMENT_HEADER, STATIC_SCENE_DELTA, STATIC_SCENE_FULL

from .conftest import HOST

DATA = Path(__file__).resolve().parents[1] / "data" / "rcssserver3d"
MONITOR = [
    line
    for line in (DATA / "monitor_messages.txt").read_text(encoding="latin-1").split("\n")
    if line
]
"""Real rcssserver3d monitor frames: 3 full (header only, after scene, after init), 3 deltas."""


class MonitorView:
    """A RoboViz-like reader: keeps the scene graph and the game state."""

    def __init__(self) -> None:
        self.graph = SceneGraph()
        self.env: dict[str, list[str]] = {}
        self.full_frames = 0
        self.delta_frames = 0

    def feed(self, text: str) -> None:
        exprs = parse(text)
        assert len(exprs) == 3, text[:200]
        env, header, scene = exprs
        assert isinstance(env, list) and env and all(isinstance(e, list) for e in env)
        for item in env:
            self.env[item[0]] = item[1:]
        assert header in (["RSG", "0", "1"], ["RDS", "0", "1"])
        if header[0] == "RSG":
            self.graph = SceneGraph(parse_scene_nodes(scene))
            self.full_frames += 1
        else:
            self.graph.apply_delta(parse_delta_nodes(scene))
            self.delta_frames += 1

    def drain(self, client, first_timeout: float = 10.0) -> None:
        """Read one frame (waiting up to ``first_timeout``), then those that follow quickly
        (for at most 0.5 s: an idle server keeps sending at 25 Hz)."""
        self.feed(client.recv(first_timeout))
        end = time.monotonic() + 0.5
        while time.monotonic() < end:
            try:
                self.feed(client.recv(0.03))
            except TimeoutError:
                return

    @property
    def play_mode(self) -> str:
        return PLAY_MODES[int(self.env["play_mode"][0])]


def test_static_scene_matches_the_real_server():
    real = MONITOR[0]
    i = real.index("(RSG 0 1)")
    assert real.startswith("(" + ENVIRONMENT_HEADER)
    assert real[i + len("(RSG 0 1)(") :].startswith(STATIC_SCENE_FULL)
    delta = MONITOR[3]
    j = delta.index("(RDS 0 1)")
    assert delta[j + len("(RDS 0 1)(") :].startswith(STATIC_SCENE_DELTA)


def _drive(agent, monitor_client, view: MonitorView, cycles: int, message: str = "") -> str:
    """Step the agent ``cycles`` times (sync mode), reading every monitor frame; returns the last
    percept."""
    last = ""
    for _ in range(cycles):
        agent.send(message + "(syn)")
        last = agent.recv()
    view.drain(monitor_client)
    return last


def test_monitor_stream_and_trainer_commands(make_server, clients):
    server = make_server(ground_truth=True, monitor_interval=2)
    mon = clients.monitor(server)
    view = MonitorView()
    view.drain(mon)  # full frame on connect, then deltas
    assert view.full_frames == 1 and view.play_mode == "BeforeKickOff"
    for key in ("FieldLength", "FieldWidth", "GoalWidth", "play_modes", "time", "half"):
        assert key in view.env
    a = clients.agent(server)
    a.handshake("Alpha", 1)
    _drive(a, mon, view, 6)
    assert view.env["team_left"] == ["Alpha"]
    assert view.graph.agents() == {("left", 1): len(view.graph.nodes) - 1}
    np.testing.assert_allclose(view.graph.ball_position(), server.world.ball_position(), atol=0.01)

    # trainer commands, as FC Portugal and RobocupGym send them (the monitor is never read by
    # them; here it is)
    mon.send("(playMode PlayOn)")
    mon.send(
        "(agent (unum 1) (team Left) (move -3.0 0.5 0.4 -90))(ball (pos 1 2 0.042) (vel 0 0 0))"
    )
    mon.send("(time 10)(score (left 2) (right 1))")
    last = _drive(a, mon, view, 6)
    p = parse_perception(last)
    assert p.game.play_mode == "PlayOn"
    assert (p.game.score_left, p.game.score_right) == (2, 1)
    assert 10.0 < p.game.game_time < 10.3
    torso = server.world.torso_position(0)
    assert abs(torso[0] + 3.0) < 0.3 and abs(torso[1] - 0.5) < 0.3
    ball = view.graph.ball_position()
    assert abs(ball[0] - 1) < 0.05 and abs(ball[1] - 2) < 0.05
    assert view.play_mode == "PlayOn" and view.env["score_left"] == ["2"]
    # the agent's torso in the scene graph follows the robot (RDS updates by position)
    node = view.graph.nodes[view.graph.agents()[("left", 1)]]
    torso_world = node.children[0].slt
    assert abs(torso_world[0, 3] - server.world.torso_position(0)[0]) < 0.05

    # (reqfullstate) → the next frame is RSG
    full_before = view.full_frames
    mon.send("(reqfullstate)")
    _drive(a, mon, view, 4)
    assert view.full_frames == full_before + 1

    # kickOff / dropBall / kill
    mon.send("(kickOff Left)")
    _drive(a, mon, view, 2)
    assert view.play_mode in ("KickOff_Left", "PlayOn")
    mon.send("(kill (unum 1) (team Left))")
    mon.send("(select)")  # nothing to select any more: harmless
    agent_sock = a.sock
    agent_sock.settimeout(0.5)
    a.send("(syn)")
    got = a.recv()  # the percept computed before the kill
    with pytest.raises(TimeoutError):
        while True:  # no percepts after the robot was removed (connection stays open)
            a.send("(syn)")
            got = a.recv(timeout=0.5)
    assert got
    assert server.world.n_robots == 0

    # (killsim) stops the server
    mon.send("(killsim)")
    deadline = time.monotonic() + 10
    while not server.stopped and time.monotonic() < deadline:
        time.sleep(0.02)
    assert server.stopped


def test_slow_monitor_loses_frames_not_the_game(make_server, clients):
    server = make_server(monitor_interval=1)
    slow = socket.socket()
    slow.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    slow.connect((HOST, server.monitor_port))  # never reads
    try:
        a = clients.agent(server)
        a.handshake("Alpha", 1)
        # keep the server's send buffer small so that it fills after a few frames
        server.monitors[0].conn.sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)
        for _ in range(100):
            a.send("(he1 0.3)(syn)")
            parse_perception(a.recv())
        monitor = server.monitors[0]
        assert monitor.conn.frames_dropped > 0
        assert monitor.conn.alive
    finally:
        slow.close()


def test_robot_types_in_the_scene(make_server, clients):
    server = make_server()
    mon = clients.monitor(server)
    view = MonitorView()
    agent = clients.agent(server)
    agent.handshake("Alpha", 5, 3)
    _drive(agent, mon, view, 2)
    models = [n.model for _, n, _ in view.graph.walk() if n.is_mesh]
    assert "models/naobody3.obj" in models and "models/rshank3.obj" in models
    materials = [n.materials for _, n, _ in view.graph.walk() if n.is_mesh]
    assert ("matNum5", "matLeft", "matType3", "naowhite") in materials


def _robot_signature(frame: str) -> list:
    nodes = parse_scene_nodes(parse(frame)[2])
    graph = SceneGraph([nodes[-1]])
    out = []
    for path, node, _ in graph.walk():
        scale = None if node.scale is None else tuple(np.round(node.scale, 6))
        out.append((len(path), node.kind, node.model, node.materials, scale, node.visible))
    return out


def test_robot_subtree_matches_the_real_server():
    """Same nodes, meshes, materials and scales as rcssserver3d for a left #1 of type 0."""
    from robocup_gym.server.monitor import MonitorStream, RobotView
    from robocup_gym.server.worldhost import WorldHost

    host = WorldHost()
    host.change_robots([(1, 0)], [])
    view = RobotView(key=1, robot_index=0, robot_type=0, side="left", unum=1)
    frame = MonitorStream().full_frame(host.world, [view], 1, {"left": "Probe"})
    assert _robot_signature(frame) == _robot_signature(MONITOR[2])
    # the delta of the real server has the same shape as ours
    ours = MonitorStream()
    ours.full_frame(host.world, [view], 1, {"left": "Probe"})
    host.world.step()
    delta = ours.delta_frame(host.world, [view], 1, {"left": "Probe"})
    shape = [n.kind for n in parse_delta_nodes(parse(delta)[2])]
    real = [n.kind for n in parse_delta_nodes(parse(MONITOR[3])[2])]
    assert shape == real


def test_the_frames_carry_how_long_a_team_may_not_score_after_its_pass_mode():
    """rcssserver3d's ``(pass_mode_score_wait_left s)``: in play, in full and delta frames,
    while the team's last pass-mode cycle is less than 10 s ago and it has not cleared it."""
    from robocup_gym.server.monitor import MonitorStream
    from robocup_gym.server.worldhost import WorldHost
    from robocup_gym.sim.kick_rules import KickRules

    host = WorldHost()
    game = host.world.game
    stream = MonitorStream()
    kicks = KickRules()
    stream.kick_rules = kicks
    kicks.in_pass_mode("left", 12.0, np.zeros(3))
    game.play_mode = "pass_left"
    assert "pass_mode_score_wait" not in stream.full_frame(host.world, [], 1, {})
    game.play_mode, game.game_time = "PlayOn", 14.5
    assert "(pass_mode_score_wait_left 7.5)" in stream.full_frame(host.world, [], 1, {})
    game.game_time = 21.98
    delta = stream.delta_frame(host.world, [], 1, {})
    assert "(pass_mode_score_wait_left 0.02" in delta and "wait_right" not in delta
    game.game_time = 22.0
    assert "pass_mode_score_wait" not in stream.delta_frame(host.world, [], 1, {})
    kicks.in_pass_mode("right", 30.0, np.zeros(3))
    kicks.pass_cleared["right"] = True  # two team-mates played it outside the circle
    game.game_time = 31.0
    assert "pass_mode_score_wait" not in stream.delta_frame(host.world, [], 1, {})

"""Agents over the network: handshake, sync mode, percepts, say/hear, robustness."""

from __future__ import annotations

import random
import re
import socket
import struct
import threading
import time
from itertools import pairwise

import pytest

from robocup_gym.protocol.perceptors import parse_perception
from robocup_gym.server import PortInUseError, SimServer
from robocup_gym.server.agent import GRACE_PERCEPTS

from .conftest import HOST, run_agents, step_all

HJ_ORDER = ["hj1", "hj2", *(f"raj{i}" for i in range(1, 5)), *(f"laj{i}" for i in range(1, 5))]
HJ_ORDER += [*(f"rlj{i}" for i in range(1, 7)), *(f"llj{i}" for i in range(1, 7))]


def _time(msg: str) -> float:
    return float(re.match(r"\(time \(now ([-0-9.]+)\)\)", msg).group(1))


def test_two_agents_two_teams_sync(make_server):
    server = make_server(ground_truth=True)

    def message(i: int, k: int) -> str:
        return "(beam -2 1 0)" if k == 0 else "(he1 0.5)(say Hi!)"

    out = run_agents(server, [("Alpha", 7, 0), ("Beta", 0, 0)], 10, message)
    # the first team to init is left (the threads race for it)
    sides = [re.search(r"\(team (left|right)\)", m[2]).group(1) for m in out]
    assert sorted(sides) == ["left", "right"]
    for i, (unum, team) in enumerate([(7, "Alpha"), (1, "Beta")]):
        side = sides[i]
        msgs = out[i]
        assert len(msgs) == 12
        for m in msgs[:2]:
            assert parse_perception(m).joint_names[:2] == ("hj1", "hj2")
        # the GS of the first percept computed after init carries unum and side, exactly once
        gs = f"(GS (unum {unum}) (team {side}) (sl 0) (sr 0) (t 0.00) (pm BeforeKickOff))"
        assert gs in msgs[2]
        assert sum("(unum" in m for m in msgs) == 1
        seen_vision = 0
        for m in msgs:
            # RobocupGym's regexes: hj1/hj2 adjacent, joints in model order, ACC/GYR format
            assert re.search(r"\(HJ \(n hj1\) \(ax [-0-9.]+\)\)\(HJ \(n hj2\) \(ax [-0-9.]+\)\)", m)
            pos = [m.index(f"(HJ (n {n}) ") for n in HJ_ORDER]
            assert pos == sorted(pos)
            assert re.search(r"\(ACC \(n torso\) \(a [-0-9.]+ [-0-9.]+ [-0-9.]+\)", m)
            assert re.search(r"\(GYR \(n torso\) \(rt [-0-9.]+ [-0-9.]+ [-0-9.]+\)", m)
            p = parse_perception(m)
            assert p.game.play_mode == "BeforeKickOff"
            if p.vision is not None:
                seen_vision += 1
                assert p.vision.my_pos is not None and p.vision.ball_pos is not None
        assert 3 <= seen_vision <= 5  # every third cycle
        # a message said in cycle n is heard in the percept computed at the end of cycle n
        for m in msgs[4:]:
            assert f"(hear {team} " in m and " self Hi!)" in m
        # sync mode: exactly one percept per cycle, 20 ms apart
        times = [_time(m) for m in msgs]
        assert [round(t1 - t0, 2) for t0, t1 in pairwise(times)] == [0.02] * 11
    assert server.referee.teams.names == {sides[0]: "Alpha", sides[1]: "Beta"}


def test_fc_portugal_handshake_without_syn(make_server, clients):
    """FC Portugal: scene → recv, init → recv (no syn), then three (syn) must bring the side."""
    server = make_server()
    a = clients.agent(server)
    a.send("(scene rsg/agent/nao/nao_hetero.rsg 1)")
    a.recv()
    a.send("(init (unum 3) (teamname FCPortugal))")
    a.recv()
    got = []
    for _ in range(3):
        a.send("(syn)")
        got.append(a.recv())
    assert any("(unum 3) (team left)" in m for m in got)
    assert GRACE_PERCEPTS == 1


def test_init_rules(make_server, clients):
    server = make_server()
    # sides: the first team name that initialises is left, the second right (kept for good)
    assert "(unum 4) (team left)" in "".join(run_agents(server, [("A", 4, 0)], 1)[0])
    assert "(unum 1) (team right)" in "".join(run_agents(server, [("B", 0, 2)], 1)[0])
    # refused: a number that is taken (by whoever came first), a third team; the refused robot
    # leaves the world and its connection is closed. The holder of A 3 stays in the game (and
    # keeps the sync cycles going) for as long as the second A 3 tries.
    holder = clients.agent(server)
    holder.handshake("A", 3)
    trying = threading.Event()
    trying.set()

    def keep_stepping() -> None:
        while trying.is_set():
            holder.send("(syn)")
            holder.recv()

    stepper = threading.Thread(target=keep_stepping, daemon=True)
    stepper.start()
    try:
        with pytest.raises(ConnectionError):
            run_agents(server, [("A", 3, 1)], 5)
    finally:
        trying.clear()
        stepper.join(15)
    assert not stepper.is_alive()
    holder.close()
    with pytest.raises(ConnectionError):
        run_agents(server, [("C", 1, 0)], 3)
    assert "(unum 1) (team right)" in "".join(run_agents(server, [("B", 0, 4)], 2)[0])
    assert server.referee.teams.names == {"left": "A", "right": "B"}


def test_never_scene_client_does_not_freeze_sync(make_server, clients):
    server = make_server()
    silent = socket.create_connection((HOST, server.agent_port))
    try:
        a = clients.agent(server, timeout=5.0)
        a.handshake("Alpha", 1)
        for msgs in step_all([a], "", 20):
            parse_perception(msgs[0])
    finally:
        silent.close()


def test_disconnect_mid_sync_drops_agent(make_server):
    server = make_server()

    def message(i: int, k: int) -> str | None:
        # Beta closes while the server waits for its (syn): dropped, Alpha goes on
        return None if (i == 1 and k == 3) else "(he1 0.2)"

    out = run_agents(server, [("Alpha", 1, 0), ("Beta", 1, 0)], 25, message)
    times = [_time(m) for m in out[0]]
    assert [round(t1 - t0, 2) for t0, t1 in pairwise(times)] == [0.02] * 26
    assert len(out[1]) == 5
    beta = server.referee.teams.side_of("Beta")
    assert server.referee.teams.members[beta] == {}  # Beta's number is free again


def test_unknown_and_malformed_messages_are_ignored(make_server, clients):
    server = make_server()
    a = clients.agent(server)
    a.send("(init (unum 1) (teamname X))(syn)")  # before scene: ignored, no reply
    a.send("(scene rsg/agent/soccerbot058/soccerbot.rsg)")  # unknown scene: ignored
    a.send("(scene rsg/agent/nao/nao_hetero.rsg 9)")  # bad type: ignored
    with pytest.raises(TimeoutError):
        a.recv(timeout=0.3)
    a.handshake("Alpha", 1)
    for junk in [
        "(he1 1",
        ")))(he1 2)",
        "(foo 1 2 3)(he1 nan)(lle7 1)(beam 1)(say)(say (x))",
        "(he1 1e999)(he2 0.5)",
        "\x00\xff garbage",
        "",
        "(" * 200 + ")" * 199,
    ]:
        a.send(junk)  # its own frame: a broken frame must not swallow the next one
        a.send("(syn)")
        parse_perception(a.recv())
    assert server.world.n_robots == 1


def test_garbage_and_fuzz_keep_the_server_serving(make_server, clients):
    server = make_server()
    a = clients.agent(server)
    a.handshake("Alpha", 1)
    rng = random.Random(7)
    # random bytes on both ports (closed or dropped by the server, never a crash)
    for port in (server.agent_port, server.monitor_port):
        for _ in range(4):
            s = socket.create_connection((HOST, port))
            s.sendall(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 300))))
            s.close()
    # a frame announcing 2 GiB, then valid-looking frames with random S-expression soup
    s = socket.create_connection((HOST, server.agent_port))
    s.sendall(struct.pack(">I", 1 << 31) + b"(scene")
    atoms = ["(", ")", "scene", "init", "beam", "he1", "say", "syn", "1", "-3.5", "nan", "x"]
    fuzz = []
    for _ in range(3):
        f = socket.create_connection((HOST, server.agent_port))
        fuzz.append(f)
        for _ in range(30):
            text = " ".join(rng.choice(atoms) for _ in range(rng.randrange(1, 20)))
            data = text.encode()
            f.sendall(struct.pack(">I", len(data)) + data)
    m = socket.create_connection((HOST, server.monitor_port))
    for _ in range(30):
        text = " ".join(rng.choice([*atoms, "ball", "pos", "agent", "playMode"]) for _ in range(8))
        data = text.encode()
        m.sendall(struct.pack(">I", len(data)) + data)
    try:
        for msgs in step_all([a], "(he1 0.1)", 30):
            parse_perception(msgs[0])
    finally:
        for sock in [s, m, *fuzz]:
            sock.close()
    assert not server.stopped


def test_port_in_use_names_the_port():
    blocker = socket.socket()
    blocker.bind((HOST, 0))
    blocker.listen()
    port = blocker.getsockname()[1]
    try:
        server = SimServer(port, 0, HOST)
        with pytest.raises(PortInUseError, match=f"agent port {port} is already in use"):
            server.bind()
        server = SimServer(0, port, HOST)
        with pytest.raises(PortInUseError, match=f"monitor port {port}"):
            server.bind()
    finally:
        blocker.close()


def test_real_time_mode_runs_on_the_wall_clock(make_server, clients):
    server = make_server(sync=False, real_time=True)
    a = clients.agent(server)
    a.send("(scene rsg/agent/nao/nao_hetero.rsg 0)")
    a.recv()
    t_wall = time.monotonic()
    first = _time(a.recv())
    for _ in range(25):
        last = _time(a.recv())
    wall = time.monotonic() - t_wall
    assert round(last - first, 2) == 0.5
    assert wall > 0.4  # 25 cycles of at least 20 ms (a loaded machine may be slower)


def test_robocupgym_naive_client_gets_one_whole_percept_per_recv(make_server):
    """RobocupGym sends, then does one recv(2**20) without stripping the length prefix."""
    server = make_server(ground_truth=True)
    s = socket.create_connection((HOST, server.agent_port))
    s.settimeout(10)
    try:
        handshake = [
            "(scene rsg/agent/nao/nao_hetero.rsg 0)(syn)",
            "(init (unum 1)(teamname wits_test))(syn)",
            "(syn)",
            "(beam -10 0 0)(syn)(syn)",
        ]
        steps = ["(he1 0)(syn)"] * 10 + ["(he1 0.3)(rle3 -1.2)(syn)"] * 10
        seen = []
        for text in handshake + steps:
            data = text.encode()
            s.sendall(struct.pack(">I", len(data)) + data)
            got = s.recv(2**20)
            (n,) = struct.unpack(">I", got[:4])
            assert len(got) == 4 + n, "exactly one whole frame per recv"
            msg = got[4:].decode("unicode_escape")
            assert re.search(r"\(HJ \(n hj1\) \(ax (.*?)\)\)\(HJ \(n hj2\) \(ax (.*?)\)\)", msg)
            seen.append(msg)
        assert sum(bool(re.search(r"\(mypos [-0-9.]+ [-0-9.]+ [-0-9.]+\)", m)) for m in seen) >= 6
        assert re.search(r"\(t ([-0-9.]+)\)", msg)
    finally:
        s.close()


def test_full_teams_of_eleven_in_sync_mode(make_server):
    """Up to 11 agents per team, any mix of robot types (the World is rebuilt as they join)."""
    server = make_server()
    specs = [("Home", 0, i % 5) for i in range(11)] + [("Away", 0, (i + 2) % 5) for i in range(11)]

    def message(i: int, k: int) -> str:
        return f"(beam {-1 - (i % 11)} {i % 11 - 5} 0)" if k == 0 else "(lae1 1.0)"

    out = run_agents(server, specs, 4, message, timeout=60.0)
    unums: dict[str, set[int]] = {"left": set(), "right": set()}
    for msgs in out:
        assert len(msgs) == 6
        gs = re.search(r"\(GS \(unum (\d+)\) \(team (left|right)\)", "".join(msgs))
        unums[gs.group(2)].add(int(gs.group(1)))
        p = parse_perception(msgs[-1])
        assert len(p.joint_names) in (22, 24)  # type 4 has toes
    assert unums == {"left": set(range(1, 12)), "right": set(range(1, 12))}


@pytest.mark.parametrize("lines", [True, False])
def test_field_lines_can_be_left_out_as_the_spl_fork_does(make_server, lines):
    """Upstream rcssserver3d 0.7.3 sends field lines in See; the SPL fork sends none, and
    ``field_lines=False`` (``--no-field-lines``) gives its percepts."""
    server = make_server(field_lines=lines)
    (msgs,) = run_agents(server, [("A", 1, 0)], 9, lambda i, k: "(beam -1 0 0)" if k == 0 else "")
    seen = [parse_perception(m).vision for m in msgs]
    seen = [v for v in seen if v is not None]
    assert seen and all("F1R" in v.objects or "G1R" in v.objects for v in seen)
    assert all((len(v.lines) > 0) == lines for v in seen), [len(v.lines) for v in seen]

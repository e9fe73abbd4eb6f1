"""``robocup-gym team``: a team on a server, each player its own connection, playing from its
own perceptors."""

from __future__ import annotations

import os
import re
import select
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from _waits import wait_until

pytest.importorskip("pettingzoo")

from robocup_gym.protocol import trainer as trainer_cmds
from robocup_gym.protocol.framing import (
    FrameDecoder,
    connect,
    decode_payload,
    recv_frame,
    send_frame,
)
from robocup_gym.server.bench import start_server_process, stop_server_process
from robocup_gym.soccer.match import make_team
from robocup_gym.soccer.remote import RemotePlayer, ServerTeam
from robocup_gym.types import AgentCommand

DATA = Path(__file__).resolve().parents[1] / "data" / "rcssserver3d"


@pytest.fixture
def server():
    """``robocup-gym serve`` in sync mode, as fast as the agents go, with the See ground-truth
    extensions on (the test compares the players' estimates with them; the players never read
    them)."""
    proc, agent_port, monitor_port = start_server_process(
        "--sync", "--no-real-time", "--ground-truth", "--seed", "5"
    )
    try:
        yield proc, agent_port, monitor_port
    finally:
        stop_server_process(proc)


def _kick_off(monitor_port: int, when) -> None:
    """Send the kick-off through the trainer port once ``when()`` says both teams are in."""
    deadline = time.monotonic() + 60.0
    while not when() and time.monotonic() < deadline:
        time.sleep(0.05)
    sock = connect("127.0.0.1", monitor_port)
    send_frame(sock, trainer_cmds.kick_off("Left"))
    time.sleep(0.5)
    sock.close()


def test_two_teams_play_on_serve_from_their_own_perceptors(server):
    """The scripted team against the standing one, 2 a side, 20 s of game time: each team gets
    its side, every player places itself from what it sees within decimetres of where the
    server says it is, and the scripted team goes for the ball."""
    _, agent_port, monitor_port = server
    results, teams, errors = {}, {}, []
    truth: dict[str, list] = {"A": [], "B": []}

    def play(spec: str, name: str) -> None:
        try:
            with ServerTeam(make_team(spec), port=agent_port, name=name, players=2) as t:
                teams[name] = t
                perceive = [p.perceive for p in t.players]

                def watched(k):
                    def run():
                        p = perceive[k]()
                        v = p.vision
                        if v is not None and v.my_pos is not None and p.ground_truth is not None:
                            s = -1.0 if t.players[k].side == "right" else 1.0
                            head = np.asarray(v.my_pos[:2]) * s  # team frame → world
                            ball = np.asarray(v.ball_pos[:2]) * s
                            truth[name].append((k, head, p.ground_truth.torso_pos[:2].copy(), ball))
                        return p

                    return run

                for k, pl in enumerate(t.players):
                    pl.perceive = watched(k)
                results[name] = t.play(seconds=20.0)
        except Exception as exc:  # reported below, on the test's thread
            errors.append(exc)

    threads = [
        threading.Thread(target=play, args=("scripted", "A")),
        threading.Thread(target=play, args=("standing", "B")),
    ]
    threads[0].start()
    wait_until(lambda: "A" in teams or errors, timeout=60.0, what="A's side (left) before B joins")
    threads[1].start()
    _kick_off(monitor_port, lambda: len(teams) == 2 or errors)
    for t in threads:
        t.join(timeout=300)
    assert not errors, errors
    a, b = results["A"], results["B"]
    assert (a.side, b.side) == ("left", "right")
    assert a.end == b.end == "time" and a.game_time >= 20.0
    assert a.goals_for == b.goals_against and a.goals_against == b.goals_for
    for name in ("A", "B"):
        # the torso estimate against the server's head position (the head sits above the
        # torso, a few centimetres off when the robot leans)
        errs = [float(np.hypot(*(head - est))) for _, head, est, _ in truth[name]]
        assert len(errs) > 200
        assert np.median(errs) < 0.15, (name, np.median(errs))
    # the scripted team's nearer player came within half a metre of the ball
    nearest = min(float(np.hypot(*(head - ball))) for _, head, _, ball in truth["A"])
    assert nearest < 0.5, nearest


def _team_cli(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "robocup_gym.cli", "team", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
    )


def test_the_team_command_plays_and_prints_json_last(server):
    _, agent_port, monitor_port = server
    proc = _team_cli(
        "standing", "--port", str(agent_port), "--players", "1", "--seconds", "3", "--seed", "4"
    )
    try:
        assert "waiting for the kick-off" in proc.stdout.readline()
        _kick_off(monitor_port, lambda: True)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err
    import json

    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["team"] == "RoboCupGym" and summary["side"] == "left"
    assert summary["end"] == "time" and summary["game_time"] >= 3.0
    assert summary["goals_for"] == summary["goals_against"] == 0


def test_a_server_that_dies_mid_game_is_one_line_and_a_failure():
    proc, agent_port, _ = start_server_process("--sync", "--no-real-time")
    team = _team_cli("standing", "--port", str(agent_port), "--players", "2", "--timeout", "3")
    try:
        assert "waiting for the kick-off" in team.stdout.readline()
        stop_server_process(proc)
        _out, err = team.communicate(timeout=60)
    finally:
        stop_server_process(proc)
        if team.poll() is None:
            team.kill()
            team.communicate()
    assert team.returncode == 1
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "the server went away" in lines[0], err


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["nosuch"], "unknown team 'nosuch'"),
        (["pretrained:penalty-striker"], "was trained on penalty"),
        (["scripted", "--port", "1", "--timeout", "0.5"], "no server at 127.0.0.1:1"),
        (["scripted", "--players", "12"], "a team has 1-11 players"),
    ],
)
def test_the_team_command_refuses_what_it_cannot_play(args, message):
    proc = _team_cli(*args)
    _out, err = proc.communicate(timeout=120)
    assert proc.returncode == 1
    assert message in err and "Traceback" not in err, err


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"port": "3100"}, "port must be a port number 1-65535, got '3100'"),
        ({"port": 70000}, "port must be a port number 1-65535, got 70000"),
        ({"players": "two"}, "a team has 1-11 players, got 'two'"),
        ({"players": 2, "robot_types": [0, "1"]}, r"give 2 robot types of 0-4, got \[0, '1'\]"),
    ],
)
def test_a_team_refuses_options_it_cannot_play_before_connecting(options, message):
    with pytest.raises(ValueError, match=message):
        ServerTeam("scripted", **options)


def test_a_learnt_team_plays_on_its_players_observations(server):
    """A policy team with the privileged part (as ``robocup-gym train game-1v1`` learns one)
    gets, every decision, an observation of the size the in-process game gives, filled from the
    player's estimate."""
    from robocup_gym.soccer import game_v1
    from robocup_gym.soccer.learnt import PolicyTeam

    _, agent_port, monitor_port = server
    env = game_v1.parallel_env(left_types=(0,), right_types=(0,), actions="skills", privileged=True)
    size = env.observation_space("left_1").shape[0]
    env.close()
    seen = []

    def act(x: np.ndarray) -> np.ndarray:
        seen.append(x.copy())
        return np.tile([0.5, 0.0, 0.0, -1.0], (len(x), 1))  # walk forward

    team = PolicyTeam(act, size, "walker", {"privileged": True}, "soccer/game-1v1")
    with ServerTeam(team, port=agent_port, name="L", players=1) as t:
        threading.Thread(target=_kick_off, args=(monitor_port, lambda: True)).start()
        result = t.play(seconds=4.0)
    assert result.end == "time" and result.falls == 0
    assert len(seen) >= 15 and all(x.shape == (1, size) for x in seen)
    assert all(np.isfinite(x).all() and np.abs(x).max() <= 1.0 for x in seen)
    # the privileged part's own x (its 10 values follow 2 n joints, 6 IMU, 12 FRP, 5 ball,
    # 12 goals and 6 game values; the last 2 are the opponent's) grows as it walks forward
    k = 2 * 22 + 6 + 12 + 5 + 12 + 6
    xs = [float(x[0, k]) for x in seen]
    assert xs[-1] > xs[0] + 0.5 / 15.0, xs


def test_a_team_plays_on_a_real_rcssserver3d(real_rcssserver3d):
    """Where a real rcssserver3d is installed (``RCSSSERVER3D`` or on ``PATH``): a player of
    the standing team connects, beams to its place, stands through the kick-off and 5 s of
    play without falling, and places itself where it beamed."""
    from robocup_gym.backends.process import ServerProcess

    server = ServerProcess(real_rcssserver3d, sync=True, real_time=False)
    server.start()
    try:
        with ServerTeam(make_team("standing"), port=server.agent_port, name="R", players=1) as t:
            threading.Thread(target=_kick_off, args=(server.monitor_port, lambda: True)).start()
            result = t.play(seconds=5.0)
            fix = t.players[0].estimator.localiser.fix
    finally:
        server.stop()
    assert result.end == "time" and result.side == "left" and result.falls == 0
    # the goalkeeper's place of the kick-off formation, (-14, 0) (told to stand, the walk
    # steps on the spot and turns a little: the heading is not checked)
    assert fix is not None and fix.landmarks >= 2
    assert abs(fix.x + 14.0) < 0.3 and abs(fix.y) < 0.3


def test_a_full_team_joins_a_real_rcssserver3d(real_rcssserver3d):
    """Eleven players join a real rcssserver3d, each told its side and number. (Robots that
    enter the world together lie inside one another at the centre spot until their ``init``
    places them; on that heap the real server's physics step takes seconds, and 11 scenes sent
    together did not join within a minute.)"""
    from robocup_gym.backends.process import ServerProcess

    server = ServerProcess(real_rcssserver3d, sync=True, real_time=False)
    server.start()
    try:
        with ServerTeam(
            make_team("standing"), port=server.agent_port, name="Full", players=11, timeout=30.0
        ) as t:
            told = [(p.side, p.unum) for p in t.players]
            for _ in range(20):  # and the server goes on cycling with all of them
                for p in t.players:
                    p.perceive()
                for p in t.players:
                    p.send(AgentCommand())
            times = {p.last.time for p in t.players}
    finally:
        server.stop()
    assert told == [("left", k) for k in range(1, 12)]
    assert len(times) == 1


def test_a_player_takes_its_side_from_a_percept_it_skips():
    """The server says a player's side and number once, after ``init``; when that percept
    comes with a newer one behind it (a sync-mode server does not wait for a player in its first
    cycles), the player acts on the newer one and still knows its side. (Percepts captured
    from a real rcssserver3d: the third is the one that tells.)"""
    percepts = (DATA / "perceptor_messages.txt").read_text().splitlines()
    assert "(unum 1) (team left)" in percepts[2] and "(unum" not in percepts[3]
    assert percepts[3].startswith("(time (now 6.800))")
    listener = socket.create_server(("127.0.0.1", 0))
    got: list[str] = []
    sent = threading.Event()

    def fake_server() -> None:
        conn, _ = listener.accept()
        # each frame goes out as it is sent (Nagle's algorithm would hold the second back until
        # the first is acknowledged, which the client may delay)
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        dec = FrameDecoder()
        got.append(decode_payload(recv_frame(conn, dec, 5.0)))  # scene
        send_frame(conn, percepts[0])
        got.append(decode_payload(recv_frame(conn, dec, 5.0)))  # init
        send_frame(conn, percepts[2])
        send_frame(conn, percepts[3])
        sent.set()
        got.append(decode_payload(recv_frame(conn, dec, 5.0)))
        conn.close()

    thread = threading.Thread(target=fake_server)
    thread.start()
    try:
        player = RemotePlayer("127.0.0.1", listener.getsockname()[1], "T", 1, 0, timeout=5.0)
        player.handshake_step()  # answers the first percept with init
        assert sent.wait(5.0)  # both later percepts are in the socket
        player.handshake_step()
        thread.join(5.0)
        player.close()
    finally:
        listener.close()
    assert got[0].startswith("(scene") and got[1].startswith("(init (unum 1)")
    assert player.last.time == pytest.approx(6.80)  # the newer: "(time (now 6.800))"
    assert (player.side, player.unum, player.stage) == ("left", 1, "ready")


def test_a_team_joins_with_every_player_on_the_same_cycle():
    """A sync-mode server sends the next percept once every player has answered this one, and
    the team answers all its players together: so it has joined only when every player has
    answered the same cycle, even when one player's percept of that cycle comes late. Each next
    player connects while the server waits for the others' answers (so it joins in a fixed
    cycle). (A fake server in sync mode; percepts captured from a real rcssserver3d.)"""
    percepts = (DATA / "perceptor_messages.txt").read_text().splitlines()
    plain, told = percepts[3], percepts[2]

    def at(text: str, t: float, unum: int | None = None) -> str:
        text = re.sub(r"\(time \(now [0-9.]+\)\)", f"(time (now {t:.3f}))", text)
        return text if unum is None else text.replace("(unum 1)", f"(unum {unum})")

    listener = socket.create_server(("127.0.0.1", 0))
    listener.settimeout(5.0)
    got: dict[int, list[str]] = {1: [], 2: []}
    pending_first: list[bool] = []

    def fake_server() -> None:
        conns, decs = {}, {}

        def join(k: int) -> None:
            conns[k], _ = listener.accept()
            conns[k].setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)  # as a server does
            decs[k] = FrameDecoder()
            reply(k)  # scene

        def reply(k: int) -> None:
            got[k].append(decode_payload(recv_frame(conns[k], decs[k], 5.0)))

        join(1)
        send_frame(conns[1], at(plain, 1.00))
        reply(1)  # init
        send_frame(conns[1], at(told, 1.02, 1))
        reply(1)
        # player 2 connects once the next cycle's percept has come (not while the server runs
        # the cycle: its scene would land in one cycle or the next with the machine's load) ...
        pending_first.append(bool(select.select([listener], [], [], 0.3)[0]))
        send_frame(conns[1], at(plain, 1.04))  # the next cycle: the server waits for player 1
        # ... and before player 1 answers it
        ready = select.select([listener, conns[1]], [], [], 5.0)[0]
        pending_first.append(listener in ready)
        join(2)
        reply(1)
        for k in (1, 2):
            send_frame(conns[k], at(plain, 1.06))
        for k in (1, 2):
            reply(k)  # player 2: init
        send_frame(conns[2], at(told, 1.08, 2))  # player 2 is told first ...
        time.sleep(0.3)
        send_frame(conns[1], at(plain, 1.08))  # ... player 1's percept of that cycle comes late
        for k in (1, 2):
            reply(k)
        for k in (1, 2):
            send_frame(conns[k], at(plain, 1.10))
        for k in (1, 2):
            reply(k)
        for c in conns.values():
            c.close()

    thread = threading.Thread(target=fake_server)
    thread.start()
    try:
        team = ServerTeam(
            make_team("standing"), port=listener.getsockname()[1], players=2, timeout=5.0
        )
        joined = [(p.side, p.unum, p.last.time) for p in team.players]
        for p in team.players:  # the team's first cycle: one percept waiting for each
            p.perceive()
        for p in team.players:
            p.send(AgentCommand())
        thread.join(5.0)
        team.close()
    finally:
        listener.close()
    assert pending_first == [False, True]
    assert joined == [("left", 1, pytest.approx(1.08)), ("left", 2, pytest.approx(1.08))]
    # player 1: scene, init, 5 cycles answered; player 2: scene, init, 2 cycles
    assert [len(got[k]) for k in (1, 2)] == [7, 4]


def test_the_join_benchmark_reports_joins_and_failures(run_benchmark):
    """``benchmarks/team_joins.py`` joins a team to ``serve`` (the real server left out here)
    and reports the join times and failures, JSON last."""
    env = {k: v for k, v in os.environ.items() if k != "RCSSSERVER3D"}
    res, lines = run_benchmark("team_joins.py", "--players", 3, "--runs", 1, env=env)
    assert res["serve_failures"] == 0 and res["serve_join_s_median"] > 0.0
    assert "real_failures" not in res and lines[-1].startswith("serve: 1/1 joins of 3 players")

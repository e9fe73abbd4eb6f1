"""``benchmarks/team_code.py``'s relay for the SPL fork: a team agent behind it gets percepts as
upstream rcssserver3d 0.7.3 writes them (GS without the fork's ``(k …)(ti …)``), and what the
agent sends reaches the server unchanged."""

from __future__ import annotations

import socket
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import team_code

from robocup_gym.protocol.framing import FrameDecoder, encode_frame, recv_frame

FORK = (
    b"(time (now 1.00))(GS (unum 1) (team left) (sl 0) (sr 0) (t 0.000) (pm BeforeKickOff) "
    b"(k left) (ti ((1 penalty_none 0.000)) ()))(GYR (n torso) (rt 0.1 0 0))"
)
UPSTREAM = (
    b"(time (now 1.00))(GS (unum 1) (team left) (sl 0) (sr 0) (t 0.000) (pm BeforeKickOff))"
    b"(GYR (n torso) (rt 0.1 0 0))"
)


def test_the_forks_gs_entries_are_removed_and_nothing_else():
    assert team_code.strip_fork_gs(FORK) == UPSTREAM
    assert team_code.strip_fork_gs(UPSTREAM) == UPSTREAM
    assert team_code.strip_fork_gs(b"(time (now 1))") == b"(time (now 1))"
    short = b"(GS (sl 0) (sr 0) (t 0.000) (pm BeforeKickOff) (k left) (ti () ()))(HJ (n a))"
    assert (
        team_code.strip_fork_gs(short)
        == b"(GS (sl 0) (sr 0) (t 0.000) (pm BeforeKickOff))(HJ (n a))"
    )


def test_the_relay_rewrites_percepts_and_passes_commands():
    server = socket.create_server(("127.0.0.1", 0))
    relay = team_code._ForkRelay(server.getsockname()[1])
    agent = socket.create_connection(("127.0.0.1", relay.port), timeout=10)
    theirs, _ = server.accept()
    theirs.settimeout(10)
    try:
        agent.sendall(encode_frame(b"(scene rsg/agent/nao/nao_hetero.rsg 0)"))
        assert recv_frame(theirs, FrameDecoder(), 10) == b"(scene rsg/agent/nao/nao_hetero.rsg 0)"
        theirs.sendall(encode_frame(FORK) + encode_frame(FORK))
        decoder = FrameDecoder()
        assert recv_frame(agent, decoder, 10) == UPSTREAM
        assert recv_frame(agent, decoder, 10) == UPSTREAM
    finally:
        agent.close()
        theirs.close()
        server.close()
        relay.stop()

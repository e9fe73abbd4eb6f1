"""Fuzzing the server's message handling in-process: nothing a client sends may raise."""

from __future__ import annotations

import logging
import socket

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robocup_gym.server import SimServer
from robocup_gym.server.agent import AgentState
from robocup_gym.server.server import MonitorState
from robocup_gym.server.wire import Connection, agent_actions, salvage, trainer_commands

ATOMS = [
    "(", ")", " ", "scene", "rsg/agent/nao/nao_hetero.rsg", "init", "unum", "teamname", "beam",
    "say", "pass", "syn", "he1", "rle7", "lae3", "ball", "pos", "vel", "agent", "team", "Left",
    "Right", "move", "playMode", "PlayOn", "Goal_Left", "kickOff", "None", "dropBall", "time",
    "score", "left", "right", "select", "kill", "repos", "reqfullstate", "getAck", "0", "1",
    "-1", "12", "3.5", "-1e9", "1e400", "nan", "inf", "x", "\x00", "\xff", '"',
]  # fmt: skip

messages = st.one_of(
    st.binary(max_size=200),
    st.lists(st.sampled_from(ATOMS), max_size=40).map(lambda xs: " ".join(xs).encode("latin-1")),
)


@settings(max_examples=300, deadline=None)
@given(messages)
def test_parsers_never_raise(data):
    agent_actions(data)
    trainer_commands(data)
    salvage(data.decode("latin-1"))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(messages, min_size=1, max_size=6), st.lists(messages, max_size=4))
def test_server_survives_any_agent_and_trainer_message(agent_msgs, trainer_msgs):
    crashes: list[logging.LogRecord] = []
    handler = logging.Handler()
    handler.emit = lambda record: crashes.append(record) if record.exc_info else None
    logging.getLogger("robocup_gym.server").addHandler(handler)
    server = SimServer(0, 0, "127.0.0.1", sync=True, real_time=False, seed=0)
    pairs = [socket.socketpair(), socket.socketpair()]
    try:
        host = server.world_host
        host.change_robots([(1, 0)], [])
        agent = AgentState(Connection(pairs[0][0], 1, "fuzz", "agent"), robot_type=0)
        agent.has_robot = True
        bodiless = AgentState(Connection(pairs[1][0], 2, "fuzz", "agent"))
        monitor = MonitorState(Connection(socket.socketpair()[0], 3, "fuzz", "monitor"))
        server.agents = [agent, bodiless]
        server.monitors = [monitor]
        for data in agent_msgs:
            server._agent_frame(agent, data)
            server._agent_frame(bodiless, data)
        monitor.conn.inbox = list(trainer_msgs)
        server._process_monitors()
        for _ in range(2):
            server._physics()
            server._end_cycle(True)
            server.cycle += 1
        assert server.world.n_robots in (0, 1, 2)
        assert not crashes, [r.getMessage() for r in crashes]
    finally:
        logging.getLogger("robocup_gym.server").removeHandler(handler)
        server._stop.set()
        for a in server.agents:
            a.conn.close()
        for m in server.monitors:
            m.conn.close()
        for pair in pairs:
            for s in pair:
                s.close()

"""Fuzzing the server's message handling in-process: nothing a client sends may raise."""

from __future__ import annotations

import logging
import socket

import pytest
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


_STEPS = {
    "scene": "(scene rsg/agent/nao/nao_hetero.rsg 0)",
    "init": "(init (unum 0) (teamname Fuzz))",
    "syn": "(syn)",
    "beam": "(beam -3 1 0)",
    "say": "(say hello)",
    "joints": "(he1 1.0)(lle3 -0.5)",
}


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.lists(st.sampled_from(sorted(_STEPS)), min_size=1, max_size=7),
    st.lists(st.booleans(), min_size=7, max_size=7),
)
def test_any_handshake_order_never_hangs_the_server(order, with_syn):
    """Any order of scene / init / syn / beam / say / joints, each message with or without a
    trailing ``(syn)`` (what clients written for the real server do while they wait): once the
    agent has a robot, a ``(syn)`` always brings a percept, and a second agent can still join
    and play beside it (the server neither hangs nor dies)."""
    import threading

    from robocup_gym.server.client import AgentClient

    with (
        SimServer(0, 0, "127.0.0.1", sync=True, real_time=False, seed=0) as server,
        AgentClient("127.0.0.1", server.agent_port, timeout=5.0) as a,
    ):
        for step, syn in zip(order, with_syn, strict=False):
            a.send(_STEPS[step] + ("(syn)" if syn else ""))
        stop = threading.Event()
        errors: list[BaseException] = []

        def keep_syncing() -> None:  # a robot holds a sync-mode server until it answers
            try:
                while not stop.is_set():
                    a.send("(syn)")
                    a.recv(timeout=5.0)
            except BaseException as exc:
                if not stop.is_set():
                    errors.append(exc)

        if "scene" in order:
            a.send("(syn)")
            while not a.recv(timeout=5.0).startswith("(time"):
                pass  # percepts already owed come first; any one means no hang
            thread = threading.Thread(target=keep_syncing, daemon=True)
            thread.start()
        try:
            with AgentClient("127.0.0.1", server.agent_port, timeout=5.0) as b:
                b.handshake("Other", 0, 0)
                for _ in range(3):
                    b.send("(syn)")
                    assert b.recv(timeout=5.0).startswith("(time")
        finally:
            stop.set()
        assert not errors, errors


@settings(max_examples=20, deadline=None)
@given(
    engine=st.sampled_from(["ode", "mujoco", "bullet"]),
    decimals=st.sampled_from([2, 3, 5]),
    robot_types=st.lists(st.integers(-1, 6), max_size=4).map(tuple),
    type_limits=st.booleans(),
    rules=st.booleans(),
    vision_noise=st.booleans(),
    view_cone_deg=st.sampled_from([120.0, 360.0]),
)
def test_server_options_are_taken_or_refused_in_one_clear_error(
    engine, decimals, robot_types, type_limits, rules, vision_noise, view_cone_deg
):
    """Every combination of serve's options either builds a server that serves a percept or is
    refused with a ValueError that names the bad option."""
    from robocup_gym.server.client import AgentClient

    options = dict(
        engine=engine,
        decimals=decimals,
        robot_types=robot_types,
        type_limits=type_limits,
        rules=rules,
        vision_noise=vision_noise,
        view_cone_deg=view_cone_deg,
    )
    bad = (
        engine == "bullet"
        or decimals not in (2, 3)
        or not robot_types
        or any(t not in range(5) for t in robot_types)
    )
    if bad:
        with pytest.raises(ValueError, match=r"engine|decimals|robot_types"):
            SimServer(0, 0, "127.0.0.1", sync=True, real_time=False, **options)
        return
    with (
        SimServer(0, 0, "127.0.0.1", sync=True, real_time=False, **options) as server,
        AgentClient("127.0.0.1", server.agent_port, timeout=5.0) as a,
    ):
        percepts = a.handshake("Opt", 1, robot_types[0])
        text = percepts[-1]
        assert text.startswith("(time") and f"(now 0.{'0' * decimals}" not in text[:5]

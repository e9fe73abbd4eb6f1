"""Bad input the server must survive *and say so*: every ignored or corrected command gets a log
line, a malformed message never swallows an intact ``(syn)``, bad ports are refused in one line,
a rejected player's robot leaves the world, and memory stays flat while agents come and go."""

from __future__ import annotations

import gc
import logging
import subprocess
import sys

import numpy as np
import pytest
from _waits import wait_until

from robocup_gym.protocol.perceptors import parse_perception
from robocup_gym.server import SimServer
from robocup_gym.server.client import AgentClient, MonitorClient
from robocup_gym.server.wire import salvage

from .conftest import HOST


@pytest.fixture
def sync_server():
    server = SimServer(0, 0, HOST, sync=True, real_time=False, seed=0)
    server.start_in_thread()
    yield server
    server.stop()


@pytest.fixture
def warnings_of_the_server(caplog):
    logger = logging.getLogger("robocup_gym.server")
    old = logger.level
    logger.setLevel(logging.INFO)
    caplog.set_level(logging.INFO, logger="robocup_gym.server")
    yield caplog
    logger.setLevel(old)


def test_salvage_keeps_the_complete_parts_of_an_unfinished_expression():
    assert salvage("(rle3 1.0)(lle3 2.0(syn)") == [["rle3", "1.0"], ["syn"]]
    assert salvage("(a (b 1) (c 2") == [["b", "1"]]
    assert salvage("(a 1)(b") == [["a", "1"]]


def test_an_unbalanced_message_does_not_swallow_its_syn(sync_server, warnings_of_the_server):
    """``(rle3 1.0)(lle3 2.0(syn)``: the intact ``(syn)`` counts (the server does not stall),
    the intact ``(rle3 1.0)`` is applied, the cut-off ``(lle3 2.0`` is dropped, all logged."""
    with AgentClient(HOST, sync_server.agent_port, timeout=5.0) as a:
        a.handshake("Syn", 1)
        a.send("(syn)")
        a.recv()
        a.send("(rle3 1.0)(lle3 2.0(syn)")
        a.recv()  # a stall would time out here
        for _ in range(6):
            a.send("(syn)")
            p = parse_perception(a.recv())
    assert p.joint("rlj3") > 5.0  # rle3 moved at 1 rad/s
    assert abs(p.joint("llj3")) < 8.0  # not the 16° that (lle3 2.0) for 7 cycles would give
    assert "malformed message (unbalanced parentheses)" in warnings_of_the_server.text


@pytest.mark.parametrize(
    "message, expected",
    [
        ("(rle3 1e30)", "rle3: velocity 1e+30 rad/s is beyond the joint's maximum speed"),
        ("(rle3 -1e30)(lae1 0.5)(say hi)", "rle3: velocity -1e+30 rad/s is beyond"),
        ("(beam nan 0 0)", "beam (nan, 0.0, 0.0) ignored: not finite"),
        ("(rle3 abc)", "rle3: 'abc' is not a number; read as 0 rad/s"),
        ("(rle3 1e999)", "ignored non-finite velocity for rle3"),
        ("(xx9 1.0)", "ignored xx9"),
    ],
)
def test_every_ignored_or_corrected_agent_command_is_logged(
    sync_server, warnings_of_the_server, message, expected
):
    with AgentClient(HOST, sync_server.agent_port, timeout=5.0) as a:
        a.handshake("Log", 1)
        a.send(message + "(syn)")
        a.recv()
        a.send("(syn)")
        a.recv()  # the server goes on
    assert expected in warnings_of_the_server.text


@pytest.mark.parametrize(
    "command, expected",
    [
        ("(ball (pos nan 0 0))", "ball command ignored: not finite"),
        ("(ball (pos 0 0 0.1)(vel inf 0 0))", "ball command ignored: not finite"),
        ("(agent (unum 1)(team Left)(move nan 0 0.4 0))", "agent move (nan, 0.0, 0.4, 0.0)"),
        ("(agent (unum 1)(team Left)(pos 0 nan 0.4))", "agent pos (0.0, nan, 0.4) ignored"),
        ("(time -5)", "time -5.0 ignored: the game time must be finite and >= 0"),
        ("(nosuchcommand 1)", "unknown trainer command 'nosuchcommand' ignored"),
    ],
)
def test_every_ignored_trainer_command_is_logged(
    sync_server, warnings_of_the_server, command, expected
):
    with (
        AgentClient(HOST, sync_server.agent_port, timeout=5.0) as a,
        MonitorClient(HOST, sync_server.monitor_port, timeout=5.0) as m,
    ):
        a.handshake("Log", 1)
        m.send(command)
        for _ in range(4):  # monitor input is read every second cycle
            a.send("(syn)")
            a.recv()
    assert expected in warnings_of_the_server.text


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"agent_port": 70000}, r"agent port 70000 is not a port number"),
        ({"monitor_port": -1}, r"monitor port -1 is not a port number"),
        ({"agent_port": 3300, "monitor_port": 3300}, r"both 3300; they must differ"),
        ({"sync_timeout": 0.0}, r"sync_timeout must be a number of seconds > 0"),
    ],
)
def test_bad_server_settings_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SimServer(**kwargs)


@pytest.mark.parametrize(
    "args, expected",
    [
        (["--agent-port", "70000"], "argument --agent-port: 70000 is not a port number"),
        (["--agent-port", "-1"], "argument --agent-port: -1 is not a port number"),
        (["--agent-port", "3300", "--monitor-port", "3300"], "need two different ports"),
        (["--sync-timeout", "-2"], "must be a finite number of seconds > 0"),
        (["--monitor-interval", "0"], "0 must be a whole number > 0"),
        (["--nosuch"], "unrecognized arguments: --nosuch"),
    ],
)
def test_serve_refuses_bad_options_in_one_line(args, expected):
    res = subprocess.run(
        [sys.executable, "-m", "robocup_gym.cli", "serve", *args],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("robocup-gym serve: error:"), res.stderr
    assert expected in lines[0]


def test_serve_has_the_options_the_docs_name():
    """``robocup-gym serve`` and ``python -m robocup_gym.server`` are one parser."""
    res = subprocess.run(
        [sys.executable, "-m", "robocup_gym.cli", "serve", "--help"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 0
    for option in (
        "--sync-timeout",
        "--seed",
        "--verbose",
        "--no-rules",
        "--monitor-interval",
        "--ground-truth",
        "--no-sync",
        "--full-vision",
        "--no-vision-noise",
    ):
        assert option in res.stdout


def test_a_rejected_player_leaves_the_world_and_is_told_so(sync_server, warnings_of_the_server):
    """A 12th player of a team is refused: its robot is removed and its connection closed; the
    eleven go on."""
    import threading
    import time

    from .conftest import run_agents

    done: dict = {}

    def twelfth() -> None:
        # the eleven are in first (however long their joining takes on a loaded machine)
        teams = sync_server.referee.teams

        def eleven_in() -> bool:
            side = teams.side_of("Full")
            return side is not None and len(teams.members[side]) == 11

        wait_until(eleven_in, timeout=30.0, what="the eleven to join")
        try:
            with AgentClient(HOST, sync_server.agent_port, timeout=5.0) as extra:
                extra.send("(scene rsg/agent/nao/nao_hetero.rsg 3)(syn)")
                extra.recv()
                extra.send("(init (unum 0)(teamname Full))(syn)")
                for _ in range(5):
                    extra.recv()
                    extra.send("(syn)")
                done["closed"] = False
        except (ConnectionError, OSError, TimeoutError) as exc:
            done["closed"] = type(exc).__name__
            # the eleven play on; the refused robot goes at the next step (wait for it: on a
            # loaded machine a step can take longer than any fixed sleep)
            deadline = time.monotonic() + 10.0
            while sync_server.world.n_robots != 11 and time.monotonic() < deadline:
                time.sleep(0.02)
            done["robots"] = sync_server.world.n_robots

    t = threading.Thread(target=twelfth, daemon=True)
    t.start()
    results = run_agents(sync_server, [("Full", u, u % 5) for u in range(1, 12)], steps=1500)
    t.join(10)
    assert all(len(r) == 1502 for r in results)  # the eleven were never held up
    assert done.get("closed") not in (None, False), done
    assert "init rejected" in warnings_of_the_server.text
    assert "its robot is removed and the connection closed" in warnings_of_the_server.text
    assert done["robots"] == 11


def _rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096 / 2**20


@pytest.mark.skipif(sys.platform != "linux", reason="reads /proc")
def test_memory_stays_flat_while_agents_come_and_go(sync_server):
    """Hundreds of agents join (every robot type), play a few cycles and leave: nothing of them
    stays behind (no agent, robot or world is retained)."""
    from robocup_gym.sim.memory import release_free_memory

    def visit(i: int) -> None:
        with AgentClient(HOST, sync_server.agent_port, timeout=10.0) as a:
            a.handshake("Visitors", 0, i % 5)
            for _ in range(2):
                a.send("(rle3 1.0)(syn)")
                a.recv()

    samples = []
    for i in range(200):
        visit(i)
        if i % 25 == 24:
            gc.collect()
            release_free_memory()  # what is still in use, not the allocator's free lists
            samples.append(_rss_mb())
    assert len(sync_server.agents) <= 1 and sync_server.world.n_robots <= 1
    growth = np.median(samples[-3:]) - np.median(samples[1:4])
    assert growth < 15.0, samples  # before: +0.6 MB per visit, ~100 MB here


@pytest.mark.skipif(sys.platform != "linux", reason="reads /proc")
def test_environments_created_and_closed_keep_memory_flat():
    import gymnasium as gym

    import robocup_gym.envs  # noqa: F401

    samples = []
    for i in range(300):
        env = gym.make("RobocupGym/VelocityKick-v0")
        env.reset(seed=i)
        env.step(np.zeros(env.action_space.shape))
        env.close()
        del env
        if i % 50 == 49:
            gc.collect()
            samples.append(_rss_mb())
    # the resident size as a user sees it (no trimming here): flat after the first worlds
    assert samples[-1] - samples[1] < 20.0, samples  # before: +0.3 MB per env, ~75 MB here


def test_percepts_are_built_one_by_one_when_building_them_together_fails(
    sync_server, warnings_of_the_server, monkeypatch
):
    """A failure of the batched perception (every robot's percept in one ``perceive_all``) is
    logged and the percepts are built robot by robot: every agent still gets each cycle's."""
    from .conftest import run_agents

    def broken(*args, **kwargs):
        raise RuntimeError("broken perceive_all")

    # on the class: the server builds a new world each time robots join
    monkeypatch.setattr(type(sync_server.world), "perceive_all", broken)
    results = run_agents(sync_server, [("Both", 1, 0), ("Both", 2, 1)], steps=20)
    assert all(len(r) == 22 for r in results)
    assert all("(HJ (n raj1)" in r[-1] for r in results)
    assert "percepts could not be built together" in warnings_of_the_server.text
    assert "broken perceive_all" in warnings_of_the_server.text

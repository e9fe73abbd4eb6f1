"""Fixtures of the server tests: in-process servers on OS-chosen ports, clients, clean-up."""

from __future__ import annotations

import logging
import threading

import pytest

from robocup_gym.server import SimServer
from robocup_gym.server.client import AgentClient, MonitorClient

HOST = "127.0.0.1"


@pytest.fixture
def clients():
    """``clients.agent(server)`` / ``clients.monitor(server)`` → connected clients, closed after
    the test."""
    opened: list = []

    class Factory:
        @staticmethod
        def agent(server: SimServer, timeout: float = 10.0) -> AgentClient:
            c = AgentClient(HOST, server.agent_port, timeout=timeout)
            opened.append(c)
            return c

        @staticmethod
        def monitor(server: SimServer, timeout: float = 10.0) -> MonitorClient:
            c = MonitorClient(HOST, server.monitor_port, timeout=timeout)
            opened.append(c)
            return c

    yield Factory
    for c in opened:
        c.close()


@pytest.fixture(autouse=True)
def _quiet_server_log():
    # the tests send bad input on purpose and the physics may diverge now and then while the world
    # is being tuned; the server logs that and goes on, which is what is checked here, so only
    # errors are shown
    logger = logging.getLogger("robocup_gym.server")
    old = logger.level
    logger.setLevel(logging.ERROR)
    yield
    logger.setLevel(old)


def run_agents(server, specs, steps: int, message=None, timeout: float = 30.0):
    """Run one thread per agent, as real agents are separate processes: connect, ``scene`` →
    receive, ``init`` → receive (each with ``(syn)``), then ``steps`` times send
    ``message(agent index, step)`` + ``(syn)`` and receive, then close (in sync mode the others
    then go on without it).

    Args:
        specs: ``(team, unum, robot type)`` per agent.
        message: ``f(i, k) -> str`` (default: nothing but ``(syn)``); returning ``None`` closes
            the connection at that step without a percept.

    Returns:
        Per agent: all percepts received, handshake ones first.
    """
    results: list[list[str]] = [[] for _ in specs]
    errors: list[BaseException] = []

    def worker(i: int, team: str, unum: int, robot_type: int) -> None:
        try:
            with AgentClient(HOST, server.agent_port, timeout=timeout) as c:
                results[i].extend(c.handshake(team, unum, robot_type))
                for k in range(steps):
                    text = "" if message is None else message(i, k)
                    if text is None:
                        return
                    c.send(text + "(syn)")
                    results[i].append(c.recv())
        except BaseException as exc:  # reported in the test's thread
            errors.append(exc)

    threads = [
        threading.Thread(target=worker, args=(i, *spec), daemon=True)
        for i, spec in enumerate(specs)
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout + 5)
    assert not [t for t in threads if t.is_alive()], "agent threads hung"
    if errors:
        raise errors[0]
    return results


def step_all(agents: list[AgentClient], message: str = "", n: int = 1) -> list[list[str]]:
    """``n`` sync cycles: every agent sends ``message`` + ``(syn)`` and receives one percept."""
    out: list[list[str]] = []
    for _ in range(n):
        for a in agents:
            a.send(message + "(syn)")
        out.append([a.recv() for a in agents])
    return out

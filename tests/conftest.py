"""Fixtures shared by the test folders: an in-process ``robocup-gym serve`` on OS-chosen ports."""

from __future__ import annotations

import threading

import pytest

from robocup_gym.server import SimServer

HOST = "127.0.0.1"


@pytest.fixture
def make_server():
    """``make_server(**options)`` → a started :class:`SimServer` on free loopback ports
    (sync mode, real time off unless overridden); stopped after the test, even on failure."""
    servers: list[SimServer] = []

    def factory(**options) -> SimServer:
        opts = {"sync": True, "real_time": False, "seed": 1}
        opts.update(options)
        server = SimServer(0, 0, HOST, **opts)
        servers.append(server)
        server.start_in_thread()
        return server

    yield factory
    for server in servers:
        server.stop()
        assert server.stopped, "server thread did not stop"
    leftover = [t for t in threading.enumerate() if t.name == "robocup-gym-serve"]
    assert not leftover, f"server threads still running: {leftover}"

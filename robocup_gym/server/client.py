"""Minimal blocking clients of the server's two ports (benchmarks, tests, scripts).

:class:`AgentClient` speaks the agent protocol like FC Portugal's ``Server_Comm`` (one frame per
message, a blocking receive per percept); :class:`MonitorClient` reads monitor frames and sends
trainer commands. Both work against a real rcssserver3d too.
"""

from __future__ import annotations

from robocup_gym.protocol.connection import Connection


class _Client:
    def __init__(self, host: str, port: int, timeout: float = 10.0, retries_s: float = 5.0):
        self.conn = Connection.open(host, port, what=self.what, timeout=timeout, retry_s=retries_s)
        self.sock = self.conn.sock
        self.timeout = timeout

    what = "server"

    def send(self, text: str | bytes) -> None:
        """Send one message (one frame)."""
        self.conn.send(text)

    def recv(self, timeout: float | None = None) -> str:
        """Block for the next message and return its text.

        Raises:
            TimeoutError: nothing complete within ``timeout`` (default: the client's timeout).
            ConnectionError: the server closed the connection.
        """
        return self.conn.recv_text(timeout or self.timeout)

    def close(self) -> None:
        self.conn.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class AgentClient(_Client):
    """An agent connection: ``scene``, ``init``, then one message per received percept."""

    what = "agent"

    def handshake(
        self,
        team: str,
        unum: int = 0,
        robot_type: int = 0,
        *,
        syn: bool = True,
    ) -> list[str]:
        """``scene`` → receive, ``init`` → receive (each with ``(syn)`` when ``syn``); returns the
        two percepts."""
        tail = "(syn)" if syn else ""
        self.send(f"(scene rsg/agent/nao/nao_hetero.rsg {robot_type}){tail}")
        first = self.recv()
        self.send(f"(init (unum {unum}) (teamname {team})){tail}")
        second = self.recv()
        return [first, second]


class MonitorClient(_Client):
    """A monitor/trainer connection."""

    what = "monitor"

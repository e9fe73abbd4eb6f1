"""A tiny scripted rcssserver3d stand-in that replays messages captured from the real server
(``tests/data/rcssserver3d``), for the backend's client logic without any simulation.

Agent port: after ``scene`` it sends nothing until a ``(syn)`` arrives (the real server stalls
~2 s unless the client keeps sending ``(syn)``), then one recorded percept per message it
receives (3-decimal SPL-fork format; the one after ``init`` is followed by the one carrying
``(unum 1) (team left)``). Monitor port: the recorded header and full scene on connect, the full
scene after ``init``, then the recorded deltas, one per cycle and before that cycle's percept.
"""

from __future__ import annotations

import contextlib
import socket
import threading
from pathlib import Path

from robocup_gym.protocol.framing import FrameDecoder, encode_frame

DATA = Path(__file__).resolve().parents[1] / "data" / "rcssserver3d"


def fixture_lines(name: str) -> list[str]:
    return [line for line in (DATA / name).read_text().splitlines() if line.strip()]


class MockRcss:
    def __init__(self) -> None:
        self.percepts = fixture_lines("perceptor_messages.txt")
        self.monitor_msgs = fixture_lines("monitor_messages.txt")
        self.agent_listener = socket.create_server(("127.0.0.1", 0))
        self.monitor_listener = socket.create_server(("127.0.0.1", 0))
        self.agent_port = self.agent_listener.getsockname()[1]
        self.monitor_port = self.monitor_listener.getsockname()[1]
        self.received: list[str] = []
        """Every agent message, in order."""
        self.trainer: list[str] = []
        self.syn_before_first_percept = 0
        self.errors: list[BaseException] = []
        self._stop = threading.Event()
        self._monitor: socket.socket | None = None
        self._monitor_ready = threading.Event()
        self._threads = [
            threading.Thread(target=self._run_agent, daemon=True, name="mock-rcss-agent"),
            threading.Thread(target=self._run_monitor, daemon=True, name="mock-rcss-monitor"),
        ]
        for t in self._threads:
            t.start()

    # -------------------------------------------------------------- monitor
    def _run_monitor(self) -> None:
        try:
            self.monitor_listener.settimeout(10)
            conn, _ = self.monitor_listener.accept()
            self._monitor = conn
            conn.sendall(encode_frame(self.monitor_msgs[0]) + encode_frame(self.monitor_msgs[1]))
            self._monitor_ready.set()
            dec = FrameDecoder()
            conn.settimeout(0.2)
            while not self._stop.is_set():
                try:
                    data = conn.recv(65536)
                except TimeoutError:
                    continue
                except OSError:
                    return
                if not data:
                    return
                self.trainer += [f.decode("latin-1") for f in dec.feed(data)]
        except BaseException as exc:  # reported by the test
            if not self._stop.is_set():
                self.errors.append(exc)

    def _send_monitor(self, text: str) -> None:
        if self._monitor is not None:
            self._monitor.sendall(encode_frame(text))

    # -------------------------------------------------------------- agent
    def _run_agent(self) -> None:
        try:
            self.agent_listener.settimeout(10)
            conn, _ = self.agent_listener.accept()
            self._monitor_ready.wait(10)
            dec = FrameDecoder()
            conn.settimeout(0.2)
            have_scene = False
            sent = 0
            deltas = self.monitor_msgs[3:]
            cycle = 0
            while not self._stop.is_set():
                try:
                    data = conn.recv(65536)
                except TimeoutError:
                    continue
                if not data:
                    return
                for frame in dec.feed(data):
                    msg = frame.decode("latin-1")
                    self.received.append(msg)
                    if not have_scene:
                        have_scene = msg.startswith("(scene ")
                        continue
                    if sent == 0:
                        if "(syn)" not in msg:
                            continue  # stall like the real server until a (syn)
                        self.syn_before_first_percept += 1
                    if msg.startswith("(init "):
                        self._send_monitor(self.monitor_msgs[2])  # materials changed: full
                    elif sent >= 2:
                        self._send_monitor(deltas[cycle % len(deltas)])
                        cycle += 1
                    k = (
                        min(sent, len(self.percepts) - 1)
                        if sent < 3
                        else 3 + (sent - 3) % (len(self.percepts) - 3)
                    )
                    conn.sendall(encode_frame(self.percepts[k]))
                    sent += 1
        except BaseException as exc:
            if not self._stop.is_set():
                self.errors.append(exc)

    def stop(self) -> None:
        self._stop.set()
        for s in (self.agent_listener, self.monitor_listener, self._monitor):
            if s is not None:
                with contextlib.suppress(OSError):
                    s.close()
        for t in self._threads:
            t.join(5)

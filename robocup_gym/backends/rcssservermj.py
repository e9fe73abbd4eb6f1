"""A real RCSSServerMJ (``rcssservermj``, the ``rcsssmj`` package) as a child process, and a
minimal agent connection to it.

:class:`RcssServerMJProcess` starts ``python -m rcsssmj`` with this interpreter (so it uses the
same ``rcsssmj`` and MuJoCo as the in-process world) in sync mode, real time off and without its
viewer, on two ports the OS reports free (retried on new ones if a port was taken meanwhile), in a
private working folder (the server writes ``console.log`` into its working directory). The child
gets SIGINT when this process dies (Linux), and :meth:`~RcssServerMJProcess.stop` ends it
(SIGINT, then SIGKILL after a grace period). :class:`LeagueAgentLink` speaks the agent protocol:
4-byte length-prefixed messages, ``(init <robot> <team> <number>)``, then one message of joint
commands per perception.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

from robocup_gym.backends.base import BackendError
from robocup_gym.backends.process import ChildProcess, _death_signal_preexec, free_ports
from robocup_gym.protocol.connection import Connection
from robocup_gym.protocol.league import format_pd_commands
from robocup_gym.sim.engines.rcsssmj.join import SERVER_ENVIRONMENT

__all__ = ["LeagueAgentLink", "RcssServerMJProcess", "format_pd_commands"]


LOOP_GRACE_S = 0.2
"""Seconds between the server's "simulation update loop" log line and a player's join, when no
monitor connection confirms the first step (its loop steps within milliseconds)."""

_FULL_SCENE = re.compile(rb"\(sg 1 0\)\s*full")
_FULL_SCENE_WITHIN = 4096
"""Bytes of a monitor message searched for its scene kind (it follows the time and game state)."""
_SCENE_FRAMES_KEPT = 1000
"""Most deltas kept after a full scene (the server sends a full one every 250 cycles, so at
most 125 deltas come between)."""


class RcssServerMJProcess(ChildProcess):
    """One ``rcssservermj`` child process (see the module docstring).

    Args:
        startup_timeout: Seconds to wait for the agent port to accept.
        stop_grace_s: Seconds between SIGINT and SIGKILL in :meth:`stop`.
        monitor: Keep a monitor connection (:meth:`take_monitor`), which also tells that the
            simulation has stepped. ``False``: none (the server then does no monitor work, the
            fastest it runs: for speed measurements); readiness is then the server's log line
            that its loop runs, plus :data:`LOOP_GRACE_S`.

    Raises:
        robocup_gym.robot.league.RcsssmjUnavailableError: ``rcsssmj`` is not installed.
        BackendError: the server did not start (with the end of its output).
    """

    def __init__(
        self, *, startup_timeout: float = 30.0, stop_grace_s: float = 5.0, monitor: bool = True
    ) -> None:
        from robocup_gym.robot.league import league_robot_names

        league_robot_names()  # raises the clear error without rcsssmj
        self.stop_grace_s = float(stop_grace_s)
        self.folder = tempfile.mkdtemp(prefix="robocup_gym_rcssservermj_")
        self.proc: subprocess.Popen | None = None
        self._monitor: Connection | None = None
        self._scene: list[bytes] = []
        self._taken: Connection | None = None
        self.agent_port = self.monitor_port = 0
        last = ""
        for _ in range(3):
            self.agent_port, self.monitor_port = free_ports(2)
            self._spawn()
            ready = (
                self._wait_until_stepping(startup_timeout)
                if monitor
                else self._wait_for_loop(startup_timeout)
            )
            if ready:
                return
            last = self.log_tail()
            self.stop()
        raise BackendError(f"rcssservermj did not start. Its output ends with:\n{last}")

    def _wait_until_stepping(self, timeout: float) -> bool:
        """Whether the server's simulation has stepped within ``timeout`` s: its first monitor
        message (sent after a step) says so. rcsssmj 0.2.1 crashes when a player joins before
        its first step, so a port that accepts is not enough (and a probe on the agent port
        would leave an agent connection behind).

        The monitor connection stays open (:meth:`take_monitor`; drained meanwhile): rcsssmj
        0.2.1 closes a monitor's socket when the monitor hangs up, while its simulation thread
        may be sending to it, and then stops with ``Bad file descriptor`` (about one start in
        eight when the probe hung up at once)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and self.proc is not None:
            if self.proc.poll() is not None:
                return False
            try:
                conn = Connection.open("127.0.0.1", self.monitor_port, what="monitor", timeout=1.0)
            except OSError:
                time.sleep(0.05)
                continue
            try:
                first = conn.recv(max(0.5, deadline - time.monotonic()))
            except (OSError, TimeoutError):  # (ConnectionError is an OSError)
                conn.close()
                time.sleep(0.05)
                continue
            self._monitor = conn
            self._scene = [first]
            self._drain_stop = threading.Event()
            self._drainer = threading.Thread(target=self._drain, daemon=True)
            self._drainer.start()
            return True
        return False

    def _wait_for_loop(self, timeout: float) -> bool:
        """Whether, within ``timeout`` s, the server has logged that its simulation loop runs
        (its first step follows at once; :data:`LOOP_GRACE_S` later a player can join)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and self.proc is not None:
            if self.proc.poll() is not None:
                return False
            if "simulation update loop" in self.log_tail(4000):
                # (logged after "Listening for agent connections": the port is open)
                time.sleep(LOOP_GRACE_S)
                return True
            time.sleep(0.02)
        return False

    def _drain(self) -> None:
        """Read the monitor stream until :meth:`take_monitor` or :meth:`stop` (so the server
        never blocks on a full socket), keeping the newest full scene and the deltas after it
        (whoever takes the monitor needs them: the server sends the next full one only every
        250 cycles)."""
        conn = self._monitor
        while not self._drain_stop.is_set():
            try:
                frames = conn.available(0.05)  # a partial frame stays in the decoder
            except OSError:
                return
            for frame in frames:
                self._keep(frame)

    def _keep(self, frame: bytes) -> None:
        if _FULL_SCENE.search(frame[:_FULL_SCENE_WITHIN]):
            self._scene = [frame]
        elif self._scene and len(self._scene) < _SCENE_FRAMES_KEPT:
            self._scene.append(frame)

    def take_monitor(self) -> tuple[Connection, list[bytes]]:
        """The open monitor connection (from the start-up check; its decoder holds any partly
        received message) and the messages read so far that the scene needs
        (the newest full scene and the deltas after it), for the caller to read and to send
        monitor commands on; the caller must keep it open while the server runs (see
        :meth:`_wait_until_stepping`): :meth:`stop` closes it.

        Raises:
            BackendError: it was taken already.
        """
        if self._monitor is None:
            raise BackendError("the monitor connection was taken already")
        self._drain_stop.set()
        self._drainer.join()
        conn, self._monitor = self._monitor, None
        self._taken = conn
        scene, self._scene = self._scene, []
        return conn, scene

    def _spawn(self) -> None:
        log = open(os.path.join(self.folder, "server.out"), "wb")  # noqa: SIM115
        cmd = [sys.executable, "-m", "rcsssmj", "--host", "127.0.0.1"]
        cmd += ["--aport", str(self.agent_port), "--mport", str(self.monitor_port)]
        cmd += ["--sync", "--no-realtime", "--no-render"]
        try:
            self.proc = subprocess.Popen(
                cmd,
                cwd=self.folder,
                env={**os.environ, **SERVER_ENVIRONMENT},  # a join the same in every process
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=subprocess.STDOUT,
                start_new_session=True,
                preexec_fn=_death_signal_preexec(signal.SIGINT),
                close_fds=True,
            )
        finally:
            log.close()

    def log_tail(self, chars: int = 2000) -> str:
        """The end of the server's output."""
        try:
            with open(os.path.join(self.folder, "server.out"), "rb") as f:
                return f.read()[-chars:].decode("utf-8", "replace")
        except OSError:
            return ""

    def stop(self) -> None:
        """SIGINT, wait ``stop_grace_s``, SIGKILL if needed; then close the monitor
        connection. Idempotent."""
        proc, self.proc = self.proc, None
        if proc is not None and proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                proc.send_signal(signal.SIGINT)
            try:
                proc.wait(self.stop_grace_s)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(5)
        if self._monitor is not None:
            self._drain_stop.set()
            self._drainer.join()
            self._monitor.close()
            self._monitor = None
        if self._taken is not None:
            self._taken.close()
            self._taken = None

    def close(self) -> None:
        """:meth:`stop` and remove the working folder."""
        self.stop()
        shutil.rmtree(self.folder, ignore_errors=True)

    def __enter__(self) -> RcssServerMJProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        with contextlib.suppress(Exception):
            self.close()


class LeagueAgentLink:
    """One agent connection to an RCSSServerMJ: ``init``, then perceptions and commands.

    Args:
        port: The server's agent port.
        robot, team, number: What the ``init`` message asks for.
        timeout: Seconds a receive may take.
    """

    def __init__(
        self, port: int, robot: str, team: str, number: int, *, timeout: float = 20.0
    ) -> None:
        self.timeout = float(timeout)
        self.conn = Connection.open("127.0.0.1", port, what="agent", timeout=timeout)
        self.sock = self.conn.sock
        self.send(f"(init {robot} {team} {int(number)})".encode())

    def send(self, payload: bytes) -> None:
        self.conn.send(payload)

    def recv(self) -> bytes:
        """The next message (a perception), as bytes."""
        return bytes(self.conn.recv())

    def close(self) -> None:
        self.conn.close()

    def __enter__(self) -> LeagueAgentLink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

"""The real rcssserver3d (SimSpark) server as a backend, driven over TCP in agent sync mode.

Two ways to get a server:

* **launch mode** (default): the backend starts its own ``rcssserver3d`` per environment — found
  through the ``RCSSSERVER3D`` environment variable or ``rcssserver3d`` on ``PATH`` — in sync
  mode with real-time mode off, with a configuration generated in a temporary folder and on
  ports the OS reports free (:mod:`robocup_gym.backends.process`), and stops it on
  :meth:`~Rcssserver3dBackend.close`, on garbage collection, at interpreter exit and when the
  Python process dies;
* **connect mode**: ``host``/``agent_port``/``monitor_port`` name a server that is already
  running (a real rcssserver3d in sync mode, or ``robocup-gym serve --sync``).

The backend is one agent (``scene`` → ``init``, then one ``(…)(syn)`` message per cycle) plus one
monitor connection. The monitor connection sends the trainer commands of an episode reset and
reads the monitor stream, which is where the **ground truth** comes from (ball and torso poses of
the scene graph; see ``docs/rcssserver3d.md`` for its rate and precision).

Episode resets (the robot held in the air while its joints are driven to the start pose, then
placed with the ball by one trainer frame) are :mod:`robocup_gym.backends.rcssserver3d_reset`.
"""

from __future__ import annotations

import contextlib
import logging
import math
import subprocess
import time
import weakref
from collections.abc import Mapping, Sequence
from dataclasses import asdict
from typing import Any

import numpy as np

from robocup_gym.backends.base import (
    Backend,
    BackendDivergedError,
    BackendError,
)
from robocup_gym.backends.process import ServerProcess, ServerStartError, wait_for_port
from robocup_gym.backends.rcssserver3d_monitor import (
    FROZEN_CLOCK_MODES,
    TIME_TOLERANCE_S,
    GroundTruthSnapshot,
    MonitorTracker,
)
from robocup_gym.backends.rcssserver3d_reset import ResetStats, ServerReset
from robocup_gym.protocol import trainer as tc
from robocup_gym.protocol.connection import Connection
from robocup_gym.protocol.constants import DEFAULT_AGENT_PORT, DEFAULT_MONITOR_PORT
from robocup_gym.protocol.effectors import format_command, format_init, format_scene
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.perceptors import parse_perception
from robocup_gym.robot.nao import NaoModel, nao_model
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.sim.rotations import matrix_to_quat
from robocup_gym.types import AgentCommand, GroundTruth, Perception, is_integer

__all__ = ["GroundTruthSnapshot", "Rcssserver3dBackend", "ResetStats"]

log = logging.getLogger("robocup_gym.backends.rcssserver3d")


# ------------------------------------------------------------------------------------------
# the backend
# ------------------------------------------------------------------------------------------


def _release(links: list[Connection], server: ServerProcess | None) -> None:
    """Close the connections and stop the server (used by close() and the finalizer)."""
    for link in links:
        link.close()
    if server is not None:
        server.stop()


class Rcssserver3dBackend(ServerReset, Backend):
    """One learning robot in a real rcssserver3d (or any server speaking its protocol).

    Args:
        robot_type: Nao type 0–4 (``(scene rsg/agent/nao/nao_hetero.rsg <type>)``).
        seed: Accepted for the interface; the real server's randomness (vision noise) cannot be
            seeded from a client.
        vision: Accepted for the interface; the server sends ``See`` every third cycle anyway
            and it is passed on in :attr:`Perception.vision`.
        host: Server address. Giving ``host`` or a port selects **connect mode** (defaults
            3100/3200 for ports not given); otherwise the backend launches its own server.
        agent_port, monitor_port: Ports of a running server (connect mode).
        binary: rcssserver3d executable for launch mode (default: ``$RCSSSERVER3D``, then
            ``rcssserver3d`` on ``PATH``).
        script_template: ``rcssserver3d.rb`` to generate the launch configuration from (default:
            the one installed next to the binary).
        server_args: Extra command-line arguments of a launched server.
        monitor_interval: Cycles between monitor frames (ground-truth update interval). Default
            1 in launch mode (the backend configures ``$monitorStep = 0.02``), 2 in connect mode
            (rcssserver3d's default 0.04 s); set 1 for a server sending every cycle.
        team: Team name of the learning robot.
        unum: Uniform number to ask for (0 = the server assigns one).
        timeout: Seconds to wait for any single message before giving up.
        startup_timeout: Seconds for a launched server to accept connections and for the first
            percept to arrive.
        reset_tolerance_deg: A joint counts as at its start angle within this, degrees.
        reset_max_cycles: Most cycles spent driving the joints in one reset.
        reset_gain: Fraction of the remaining joint error corrected per cycle (1 = dead-beat).
        hover_height: How high above its standing height the robot is held while the joints
            move, m (keeps the legs off the ground and the ball).
        monitor_wait: Seconds a step waits for the monitor frame that belongs to its percept.
        reset_timeout: Seconds a reset waits, after its trainer commands, to see them take
            effect in the monitor stream (wall-clock time: never a count of polled cycles).
        syn_interval: Seconds between the ``(syn)`` sent while waiting for the first percept.
    """

    name = "rcssserver3d"
    deterministic = False

    def __init__(
        self,
        *,
        robot_type: int = 0,
        seed: int | None = None,
        vision: bool = False,
        host: str | None = None,
        agent_port: int | None = None,
        monitor_port: int | None = None,
        binary: str | None = None,
        script_template: str | None = None,
        server_args: Sequence[str] = (),
        monitor_interval: int | None = None,
        team: str = "RobocupGym",
        unum: int = 0,
        timeout: float = 10.0,
        startup_timeout: float = 30.0,
        reset_tolerance_deg: float = 0.05,
        reset_max_cycles: int = 200,
        reset_gain: float = 1.0,
        hover_height: float = 0.3,
        monitor_wait: float = 0.05,
        syn_interval: float = 0.01,
        reset_timeout: float = 2.0,
    ) -> None:
        super().__init__(robot_type=robot_type, seed=seed, vision=vision)
        self._model = nao_model(self.robot_type)  # validates the type
        n = len(self._model.joints)
        self._n = n
        self._vmax = self._model.max_speeds.astype(float)
        self._ranges = self._model.ranges_deg.astype(float)
        self._perceptor_names = tuple(self._model.perceptor_names)
        self._pins_reported: set[str] = set()
        self.team = str(team)
        self.requested_unum = int(unum)
        format_init(self.requested_unum, self.team)  # validates both
        self.timeout = float(timeout)
        self.startup_timeout = float(startup_timeout)
        self.reset_tolerance_deg = float(reset_tolerance_deg)
        self.reset_max_cycles = int(reset_max_cycles)
        self.reset_gain = float(reset_gain)
        self.hover_height = float(hover_height)
        self._rot: bool | None = None
        self.monitor_wait = float(monitor_wait)
        self.syn_interval = float(syn_interval)
        self.reset_timeout = float(reset_timeout)
        if not 0 < self.reset_gain <= 1.0:
            raise ValueError(f"reset_gain must be in (0, 1], got {reset_gain}")
        self.connect_mode = host is not None or agent_port is not None or monitor_port is not None
        if monitor_interval is None:
            monitor_interval = 2 if self.connect_mode else 1
        if int(monitor_interval) < 1:
            raise ValueError(f"monitor_interval must be >= 1, got {monitor_interval}")
        self.monitor_interval = int(monitor_interval)

        self.unum: int | None = None
        """Uniform number the server assigned (from the one-time ``GS (unum …)``)."""
        self.side: str | None = None
        """``"left"`` or ``"right"``."""
        self.server: ServerProcess | None = None
        self.host = host or "127.0.0.1"
        for what, port in (("agent_port", agent_port), ("monitor_port", monitor_port)):
            if port is not None and not (is_integer(port) and 1 <= port <= 65535):
                raise ValueError(f"{what} must be a port number 1-65535, got {port!r}")
        self.agent_port = int(agent_port) if agent_port is not None else DEFAULT_AGENT_PORT
        self.monitor_port = int(monitor_port) if monitor_port is not None else DEFAULT_MONITOR_PORT
        self.last_reset: ResetStats | None = None
        """Statistics of the latest :meth:`reset_episode`."""
        self.resets = 0
        self.respawns = 0
        """New robots the resets asked for (one whose joint sat on a stop, see :meth:`_respawn`)."""
        self._targets = np.zeros(n)
        """Motor velocity targets in force (rad/s, sticky as on the server)."""
        self._tracker = MonitorTracker()
        self._agent: Connection | None = None
        self._monitor: Connection | None = None
        self._links: list[Connection] = []
        self._last: Perception | None = None
        self._closed = False
        self._broken = False
        """A connection broke (set by :meth:`_connection_lost`; cleared by a relaunch)."""
        self._warned_async = False
        self._stand_cache: dict[tuple[float, ...], float] = {}
        self._finalizer = weakref.finalize(self, _release, self._links, None)
        self._launch = (binary, script_template, tuple(server_args))
        try:
            self._open(binary, script_template, server_args)
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ connection
    def _open(
        self, binary: str | None, script_template: str | None, server_args: Sequence[str]
    ) -> None:
        if self.connect_mode:
            self._connect(None, timeout=min(self.startup_timeout, 5.0))
        else:
            attempts = 3
            for attempt in range(1, attempts + 1):
                server = ServerProcess(
                    binary,
                    host=self.host,
                    sync=True,
                    real_time=False,
                    monitor_step=CYCLE_S * self.monitor_interval,
                    extra_args=server_args,
                    script_template=script_template,
                )
                self.server = server
                self._finalizer.detach()
                self._finalizer = weakref.finalize(self, _release, self._links, server)
                self.agent_port, self.monitor_port = server.start()
                # registered again, after the server's own exit-time finalizer: finalizers run
                # newest first at exit, so an environment nobody closed closes its connections
                # before the server gets SIGINT (else the server, still serving a connected
                # agent, ignored SIGINT and was killed 5 s later)
                self._finalizer.detach()
                self._finalizer = weakref.finalize(self, _release, self._links, server)
                try:
                    self._connect(server, timeout=self.startup_timeout)
                    break
                except ServerStartError as exc:
                    # e.g. another process took an OS-chosen port before the server bound it
                    self._close_links()
                    server.stop()
                    if attempt == attempts:
                        raise
                    log.warning("rcssserver3d did not start (%s); retrying on new ports", exc)
        self._handshake()

    def _relaunch_if_dead(self) -> None:
        """Launch mode: a server that exited or was killed (its step raised a clear
        :class:`BackendError`) is replaced by a new one here, so that the environment resets and
        goes on; connect mode cannot restart someone else's server."""
        if self.connect_mode or self.server is None:
            return
        proc = self.server.proc
        if self._broken and self.server.running and proc is not None:
            # a killed server closes its sockets a moment before it can be reaped
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(2.0)
        if self.server.running and not self._broken:
            return
        log.warning(
            "rcssserver3d (pid %s) is gone or its connection broke (exit code %s); starting a "
            "new one",
            self.server.pid,
            proc.returncode if proc is not None else None,
        )
        self._broken = False
        self._close_links()
        self.server.stop()
        self.server = None
        self.unum = self.side = None
        self._tracker = MonitorTracker()
        self._targets[:] = 0.0
        self._last = None
        self._open(*self._launch)

    def _respawn(self) -> None:
        """A new robot: the agent connection is closed (the server removes its robot) and
        opened again with the same uniform number (``scene``, ``init``). A new robot has every
        joint at 0 and every motor at rest, which no command can give a robot whose joint sits
        on a stop (the server ignores that joint's commands)."""
        old = self._agent
        if old is not None:
            self._links.remove(old)
            old.close()
        unum = self.unum
        self.unum = self.side = None
        self._targets[:] = 0.0
        self._tracker = MonitorTracker()  # the scene changes: follow the new robot's nodes
        assert self._monitor is not None
        self._monitor.send(tc.reqfullstate(), self.timeout)
        self._agent = Connection(
            wait_for_port(self.host, self.agent_port, self.startup_timeout, self.server), "agent"
        )
        self._links.append(self._agent)
        requested, self.requested_unum = self.requested_unum, unum or self.requested_unum
        try:
            self._handshake()
        finally:
            self.requested_unum = requested
        self.respawns += 1

    def _connect(self, server: ServerProcess | None, timeout: float) -> None:
        # The monitor port doubles as the readiness probe (a throw-away agent connection would
        # stall a real server in sync mode); it is the connection we keep.
        self._monitor = Connection(
            wait_for_port(self.host, self.monitor_port, timeout, server), "monitor"
        )
        self._links.append(self._monitor)
        self._agent = Connection(
            wait_for_port(self.host, self.agent_port, timeout, server), "agent"
        )
        self._links.append(self._agent)

    def _close_links(self) -> None:
        for link in self._links:
            link.close()
        self._links.clear()
        self._agent = self._monitor = None

    def _handshake(self) -> None:
        agent = self._agent
        assert agent is not None
        # scene -> first percept. The real server stalls ~2 s here unless the client keeps
        # sending (syn) (fixture README); (syn) before the robot exists is ignored.
        agent.send(format_scene(self.robot_type), self.timeout)
        deadline = time.monotonic() + self.startup_timeout
        while True:
            frames = agent.available(self.syn_interval)
            if frames:
                p = self._parse_many(frames)
                break
            if time.monotonic() > deadline:
                self._fail(f"no percept within {self.startup_timeout:.1f} s after scene")
            self._check_server()
            agent.send("(syn)", self.timeout)
        # init -> percepts until the one-time GS (unum …)(team …) arrives
        agent.send(format_init(self.requested_unum, self.team) + "(syn)", self.timeout)
        p = self._recv_percept()
        for _ in range(20):
            if self.unum is not None:
                break
            agent.send("(syn)", self.timeout)
            p = self._recv_percept()
        # the (syn) sent while waiting may have run a cycle more than we received: drain
        extra = agent.available(0.05)
        if extra:
            p = self._parse_many(extra)
        if self.unum is None or self.side is None:
            self._fail(
                f"the server did not give team {self.team!r} a side and uniform number (third "
                f"team, number {self.requested_unum} taken, team full or robot-type limits?)"
            )
        self._tracker.set_agent(self.side, self.unum)
        for k in range(50):
            self._pump_monitor(0.0)
            if self._tracker.has_agent and self._tracker.newest() is not None:
                break
            if k == 5:  # the full frame after init did not show the robot: ask again
                assert self._monitor is not None
                self._monitor.send(tc.reqfullstate(), self.timeout)
            p = self._exchange("(syn)", wait=False)
        else:
            self._fail("the monitor stream never showed the robot (is the monitor port right?)")
        p.ground_truth = self._ground_truth(p)
        self._last = p
        log.info(
            "connected to %s:%d/%d as %s #%d (robot type %d)",
            self.host,
            self.agent_port,
            self.monitor_port,
            self.side,
            self.unum,
            self.robot_type,
        )

    # ------------------------------------------------------------------ messages
    def _note(self, p: Perception) -> None:
        if p.game.unum is not None and p.game.team_side is not None:
            self.unum = int(p.game.unum)
            self.side = p.game.team_side.lower()

    def _parse(self, frame: bytes) -> Perception:
        try:
            p = parse_perception(frame, self.robot_type)
        except ProtocolError as exc:
            raise BackendError(f"malformed percept from the server: {exc}") from exc
        self._note(p)
        return p

    def _parse_many(self, frames: list[bytes]) -> Perception:
        p = None
        for f in frames:
            p = self._parse(f)
        assert p is not None
        return p

    def _recv_percept(self) -> Perception:
        assert self._agent is not None
        try:
            frame = self._agent.recv(self.timeout)
        except TimeoutError:
            self._check_server()
            self._fail(
                f"no percept within {self.timeout:.1f} s (is the server in sync mode and not "
                "waiting for another agent?)"
            )
        except ConnectionError as exc:
            self._connection_lost(exc)
        return self._parse(frame)

    def _check_server(self) -> None:
        if self.server is not None:
            try:
                self.server.check_alive()
            except ServerStartError as exc:
                raise BackendError(str(exc)) from None

    def _connection_lost(self, exc: ConnectionError) -> None:
        """A connection to the server broke: remember it (the next reset replaces a launched
        server, see :meth:`_relaunch_if_dead`) and raise the clear error."""
        self._broken = True
        self._check_server()
        self._fail(str(exc))

    def _fail(self, what: str) -> None:
        where = f"rcssserver3d at {self.host}:{self.agent_port}/{self.monitor_port}"
        tail = ""
        if self.server is not None:
            out = self.server.log_tail(1500).strip()
            if out:
                tail = f"\nServer output ends with:\n{out}"
        raise BackendError(f"{where}: {what}{tail}")

    def _pump_monitor(self, timeout: float) -> int:
        """Apply every monitor frame that arrives within ``timeout`` s; returns how many."""
        mon = self._monitor
        if mon is None:
            return 0
        try:
            frames = mon.available(timeout)
        except ConnectionError as exc:
            self._connection_lost(exc)
        tracker = self._tracker
        for f in frames:
            tracker.feed(f)
        if tracker.need_full and not tracker.full_requested:
            # out of step (a full frame was missed): ask for one, once until it comes
            tracker.full_requested = True
            mon.send(tc.reqfullstate(), self.timeout)
        return len(frames)

    def _sync_monitor(self, p: Perception) -> None:
        """Read the monitor until the frame for ``p``'s cycle is there (or briefly, if none)."""
        self._pump_monitor(0.0)
        pm = p.game.play_mode
        if pm in FROZEN_CLOCK_MODES or self.monitor_wait <= 0:
            return
        need = p.game.game_time - (self.monitor_interval - 1) * CYCLE_S - TIME_TOLERANCE_S
        deadline = time.monotonic() + self.monitor_wait
        while True:
            newest = self._tracker.newest()
            if newest is not None and newest.game_time >= need:
                return
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return
            self._pump_monitor(remaining)

    def _ground_truth(self, p: Perception) -> GroundTruth | None:
        s = self._tracker.select(p.game.game_time, p.game.play_mode not in FROZEN_CLOCK_MODES)
        if s is None or s.torso is None:
            return None
        rot = s.torso[:3, :3]
        return GroundTruth(
            ball_pos=s.ball_pos.copy(),
            ball_vel=s.ball_vel.copy(),
            torso_pos=s.torso[:3, 3].copy(),
            torso_quat=matrix_to_quat(rot),
            torso_vel=s.torso_vel.copy(),
            torso_ang_vel=rot @ np.radians(np.asarray(p.gyro, dtype=float)),
        )

    def _exchange(
        self, message: str, trainer: str | None = None, *, wait: bool = True
    ) -> Perception:
        """One cycle: [trainer frame,] agent message (must end with (syn)) → percept."""
        if self._closed:
            raise BackendError("the backend is closed")
        assert self._agent is not None and self._monitor is not None
        try:
            if trainer:
                self._monitor.send(trainer, self.timeout)
            self._agent.send(message, self.timeout)
        except ConnectionError as exc:
            self._connection_lost(exc)
        p = self._recv_percept()
        if wait:
            self._sync_monitor(p)
        else:
            self._pump_monitor(0.0)
        return p

    def _command_text(self, command: AgentCommand) -> str:
        vel = command.joint_velocities
        names = self._model.effector_names
        if isinstance(vel, Mapping):
            for name, v in vel.items():
                try:
                    i = names.index(name)
                except ValueError:
                    i = None
                if i is not None and math.isfinite(float(v)):
                    self._targets[i] = float(np.clip(float(v), -self._vmax[i], self._vmax[i]))
        else:
            arr = np.asarray(vel, dtype=float)
            if arr.shape == (self._n,):
                ok = np.isfinite(arr)
                self._targets[ok] = np.clip(arr[ok], -self._vmax[ok], self._vmax[ok])
        return format_command(command, self.robot_type, sync=True, decimals=4)

    def _velocity_text(self, v: np.ndarray) -> str:
        self._targets[:] = v
        return (
            "".join(
                f"({name} {value:.4f})"
                for name, value in zip(self._model.effector_names, v.tolist(), strict=True)
            )
            + "(syn)"
        )

    # ------------------------------------------------------------------ Backend API
    @property
    def robot_model(self) -> NaoModel:
        return self._model

    @property
    def last_perception(self) -> Perception | None:
        """The latest perception (with ground truth)."""
        return self._last

    def step(self, command: AgentCommand) -> Perception:
        p = self._exchange(self._command_text(command))
        last = self._last
        if not self._warned_async and last is not None and p.time - last.time > 1.5 * CYCLE_S:
            self._warned_async = True
            log.warning(
                "percepts are %.2f s apart (expected 0.02): the server does not seem to run in "
                "sync mode, so observations lag behind commands",
                p.time - last.time,
            )
        p.ground_truth = self._ground_truth(p)
        self._last = p
        if not (
            np.isfinite(p.joint_angles_deg).all()
            and np.isfinite(p.gyro).all()
            and np.isfinite(p.accel).all()
        ):
            raise BackendDivergedError(
                f"rcssserver3d sent non-finite sensor values at t = {p.time:.2f} s "
                "(its physics blew up)"
            )
        return p

    def close(self) -> None:
        """Close both connections and stop a launched server (SIGINT). Idempotent."""
        if self._closed:
            return
        self._closed = True
        self._finalizer()  # closes links, stops the server; runs once
        self._agent = self._monitor = None

    def describe(self) -> dict[str, Any]:
        d = super().describe()
        d.update(
            mode="connect" if self.connect_mode else "launch",
            host=self.host,
            agent_port=self.agent_port,
            monitor_port=self.monitor_port,
            monitor_interval=self.monitor_interval,
            team=self.team,
            side=self.side,
            unum=self.unum,
            server=None if self.server is None else self.server.describe(),
            last_reset=None if self.last_reset is None else asdict(self.last_reset),
        )
        return d

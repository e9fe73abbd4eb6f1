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

Episode reset (:meth:`~Rcssserver3dBackend.reset_episode`): the real server cannot set joint
angles, so the robot is held in the air (trainer ``move`` to the start x/y/heading,
``hover_height`` above its standing height) while every joint is driven to its start angle at the
fastest speed the server allows (a dead-beat velocity controller that accounts for the one-cycle
command delay, clipped to each joint's maximum speed); then one trainer frame puts the robot down
at its standing height, places the ball, sets the play mode and game time 0, and the backend
steps until the monitor and the percept show the new state. Cycles and milliseconds of every
reset are in :attr:`~Rcssserver3dBackend.last_reset`.

A joint that sits on one of its stops cannot be driven off it: rcssserver3d takes a joint's new
velocity only while the joint is strictly inside its limits and otherwise keeps the old one
(reference §8.3), so a joint that the last command pushed onto a stop (a hip yaw after a fall, say)
stays there for as long as that robot lives. The reset notices such a joint (on a stop, not moving
although commanded, for :data:`PINNED_CYCLES` cycles), stops waiting for it, reports it in
:attr:`ResetStats.pinned` and logs a warning once per joint.
"""

from __future__ import annotations

import contextlib
import logging
import math
import subprocess
import time
import weakref
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from robocup_gym.backends.base import (
    Backend,
    BackendDivergedError,
    BackendError,
    EpisodeSetup,
    RobotPose,
)
from robocup_gym.backends.process import ServerProcess, ServerStartError, wait_for_port
from robocup_gym.backends.rcssserver3d_monitor import (
    TIME_TOLERANCE_S,
    GroundTruthSnapshot,
    MonitorTracker,
)
from robocup_gym.protocol import trainer as tc
from robocup_gym.protocol.connection import Connection
from robocup_gym.protocol.constants import DEFAULT_AGENT_PORT, DEFAULT_MONITOR_PORT, PLAY_MODES
from robocup_gym.protocol.effectors import format_command, format_init, format_scene
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.perceptors import parse_perception
from robocup_gym.robot.nao import NaoModel, nao_model
from robocup_gym.sim.kinematics import resting_torso_height
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.sim.rotations import matrix_to_quat
from robocup_gym.types import AgentCommand, GroundTruth, Perception

__all__ = ["GroundTruthSnapshot", "Rcssserver3dBackend", "ResetStats"]

log = logging.getLogger("robocup_gym.backends.rcssserver3d")

FROZEN_CLOCK_MODES = frozenset({"BeforeKickOff", "GameOver"})
"""Play modes in which the game clock stands still (ground truth then cannot be matched by time)."""
RESET_PLAY_MODE = "BeforeKickOff"
"""The play mode while a reset drives the joints: the game is paused, so the referee's
self-collision rule (reference §9.7) releases every frozen joint and freezes none, and the
episode starts without what the last one left frozen or barred from freezing for 3 s."""


# ------------------------------------------------------------------------------------------
# the backend
# ------------------------------------------------------------------------------------------


WAKE_RAD_S = 1e-4
"""Joint velocity sent with the reset's placement frame, rad/s: the smallest non-zero value of
the 4-decimal wire format, to wake the robot's bodies (see ``reset_episode``)."""
PINNED_CYCLES = 5
"""Cycles a joint must sit on a stop without moving, although commanded, to count as pinned."""
_STOP_TOLERANCE_DEG = 0.011
"""How close to a stop a perceived angle must be to count as on it (``HJ`` has 2 decimals)."""


@dataclass
class ResetStats:
    """How one :meth:`Rcssserver3dBackend.reset_episode` went."""

    cycles: int
    """Server cycles the reset took in all."""
    joint_cycles: int
    """Cycles spent driving the joints to the start pose (robot held in the air)."""
    settle_cycles: int
    """Cycles after the final trainer frame until the new state was visible."""
    ms: float
    """Wall-clock duration, ms."""
    max_joint_error_deg: float
    """Largest |start angle − perceived angle| in the returned perception, degrees."""
    converged: bool
    """Every joint the server lets move (all but :attr:`pinned`) reached the tolerance within
    ``reset_max_cycles``."""
    pinned: tuple[str, ...] = ()
    """Joints (perceptor names) that sit on a stop the server will not let them leave (see
    the module docstring); the reset did not wait for them."""


def _release(links: list[Connection], server: ServerProcess | None) -> None:
    """Close the connections and stop the server (used by close() and the finalizer)."""
    for link in links:
        link.close()
    if server is not None:
        server.stop()


class Rcssserver3dBackend(Backend):
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

    def _place(self, start: EpisodeSetup) -> tuple[Perception, int]:
        """Start an episode through trainer commands (see the module docstring).

        Unlike the embedded world this runs server cycles: the joints are driven to their start
        angles as fast as the joint speed limits allow (robot held in the air), then the robot and
        ball are placed and the play mode and game time set. The cycles the placement takes to
        show count as settle cycles. :attr:`last_reset` has the cycles and milliseconds. ``seed``
        is ignored (the server cannot be seeded).
        """
        pose, ball_pos, ball_vel, play_mode = (
            start.pose,
            start.ball_pos,
            start.ball_vel,
            start.play_mode,
        )
        if play_mode not in PLAY_MODES:
            raise ValueError(f"unknown play mode {play_mode!r}; valid: {', '.join(PLAY_MODES)}")
        if self._closed:
            raise BackendError("the backend is closed")
        self._relaunch_if_dead()
        t0 = time.perf_counter()
        if pose.quat is not None and not self.places_any_orientation:
            raise BackendError(
                "this rcssserver3d places robots upright only (the trainer's move sets a "
                "position and a heading, and it ignores the SPL fork's (rot …)); a start pose "
                "with a full orientation (quat) needs the SPL fork or an in-process engine"
            )
        target = self._start_angles(pose.joint_angles_deg)
        # a joint on a stop from the last episode cannot be driven off it: start with a new robot
        q = np.asarray(self._last.joint_angles_deg, dtype=float) if self._last else target
        lo, hi = self._ranges[:, 0], self._ranges[:, 1]
        on_stop = (q >= hi - _STOP_TOLERANCE_DEG) | (q <= lo + _STOP_TOLERANCE_DEG)
        respawned = bool((on_stop & (np.abs(target - q) > self.reset_tolerance_deg)).any())
        if respawned:
            self._respawn()
        z = float(pose.z) if pose.z is not None else self._standing_z(target)
        # held upright while the joints move: high enough that the feet of the upright robot
        # clear the ground even when the start is lower (a robot lying down)
        hover_z = max(z, self._standing_z(target)) + self.hover_height
        yaw = float(pose.heading_deg) - 90.0  # the trainer's move takes the model's raw yaw
        team = self._team
        assert self.unum is not None
        hover = tc.agent_move(self.unum, team, (pose.x, pose.y, hover_z), yaw)
        # the joints are driven with the game paused: the referee then starts no foul and frees
        # every joint its self-collision rule froze (in the last episode, or as the joints pass
        # through the body now), so that an episode starts as fresh as in-process; the episode's
        # play mode comes with the placement
        first = tc.play_mode(RESET_PLAY_MODE) + hover
        bpos = [float(v) for v in ball_pos]
        bvel = [float(v) for v in ball_vel]
        if len(bpos) != 3 or len(bvel) != 3:
            raise ValueError("ball_pos and ball_vel need 3 numbers (x, y, z)")

        # 1. hold the robot in the air, drive the joints to the start angles
        p = self._last
        assert p is not None
        tol = self.reset_tolerance_deg
        gain = self.reset_gain
        hovered = False
        joint_cycles = 0
        stuck = np.zeros(self._n, dtype=int)  # cycles on a stop without moving, commanded
        q_before = None
        while True:
            q = np.asarray(p.joint_angles_deg, dtype=float)
            q = np.where(np.isfinite(q), q, target)  # never command from a NaN reading
            # the command sent last acts in the server's next physics step, before ours does
            predicted = q + np.degrees(self._targets * CYCLE_S)
            err = target - predicted
            # a joint on a stop that should leave it: wait until it moves or counts as pinned
            off = target - q
            on_stop = (q >= hi - _STOP_TOLERANCE_DEG) | (q <= lo + _STOP_TOLERANCE_DEG)
            on_stop &= np.abs(off) > tol
            if q_before is not None:  # (the controller below keeps commanding it off the stop)
                still = np.abs(q - q_before) < _STOP_TOLERANCE_DEG
                stuck = np.where(on_stop & still, stuck + 1, 0)
            q_before = q
            pinned = stuck >= PINNED_CYCLES
            if pinned.any() and not respawned:
                # a joint that the last episode's command drove onto a stop during the first
                # cycles: a new robot, and the drive starts again (once)
                self._respawn()
                respawned = True
                p, joint_cycles, hovered, q_before = self._last, 0, False, None
                stuck[:] = 0
                continue
            done = bool(np.abs(np.where(pinned, 0.0, err)).max() <= tol)
            done = done and not (on_stop & ~pinned).any()
            # done once the joints are there with their motors at rest (the last command 0), as
            # the in-process engines place a robot
            if (done and hovered and not self._targets.any()) or (
                joint_cycles >= self.reset_max_cycles
            ):
                break
            v = np.clip(gain * np.radians(err) / CYCLE_S, -self._vmax, self._vmax)
            if done:
                v[:] = 0.0
            p = self._exchange(
                self._velocity_text(v), first if joint_cycles == 0 else hover, wait=False
            )
            joint_cycles += 1
            s = self._tracker.newest()
            if (
                s is not None
                and s.torso is not None
                and s.torso[2, 3] > hover_z - 0.5 * self.hover_height
            ):
                hovered = True
        if not done:
            log.warning(
                "reset: joints not at their start angles after %d cycles (largest error %.1f deg)",
                joint_cycles,
                float(np.abs(err).max()),
            )

        # 2. put robot and ball in place, clock and play mode; stop the joints
        if pose.quat is None:
            place = tc.agent_move(self.unum, team, (pose.x, pose.y, z), yaw)
        else:  # the fork's rot turns the robot (joints as driven) about its torso centre
            rot = tc.rot_from_quat(pose.quat)
            place = tc.agent(self.unum, team, move=(pose.x, pose.y, z, yaw), rot=rot)
        # a ball that starts moving is put down at rest, and given its velocity in the last
        # cycle of the reset (below), so that it has not rolled on by the first observation
        moving = any(bvel)
        rest = [0.0, 0.0, 0.0]
        final = (
            tc.play_mode(play_mode)
            + place
            + tc.ball(bpos, rest if moving else bvel)
            + tc.set_time(0.0)
        )
        # the two cycles after the placement get the smallest non-zero joint velocities the wire
        # carries (1e-4 rad/s: 2e-6 rad a cycle): a non-zero command wakes the joint's body, so
        # the robot is awake once it is put down, as the in-process engines place it, instead of
        # hanging asleep where the hover's idle cycles and the move left it (ODE's auto-disable).
        # Measured on rcssserver3d 0.7.3: a wake in the placement's own cycle or the next is
        # undone by the move; in the second it holds (both feet then carry ~22.5 N, as
        # in-process)
        zero = self._velocity_text(np.zeros(self._n))
        p = self._exchange(zero, final, wait=False)
        wake = self._velocity_text(np.full(self._n, WAKE_RAD_S))
        p = self._exchange(wake, wait=False)
        p = self._exchange(wake, wait=False)
        settle = 3
        deadline = time.monotonic() + self.reset_timeout
        while not self._reset_visible(p, pose, z):
            # wait (a little) for the monitor frame of this very cycle before running another:
            # the wait is bounded by the wall clock, never by how many cycles were polled
            self._sync_monitor(p)
            if self._reset_visible(p, pose, z):
                break
            if time.monotonic() > deadline:
                self._fail(
                    f"the reset did not show within {self.reset_timeout:.1f} s ({settle} cycles) "
                    "after the trainer commands (is the monitor port that of the same server?)"
                )
            p = self._exchange(self._velocity_text(np.zeros(self._n)), wait=False)
            settle += 1
        if moving:
            # a trainer command takes effect after the physics of the cycle it arrives in: the
            # ball leaves its start with its velocity in the first step, as in-process
            p = self._exchange(self._velocity_text(np.zeros(self._n)), tc.ball(bpos, bvel))
            settle += 1
        self._tracker.restart_velocities(
            bvel, p.game.game_time, p.game.play_mode not in FROZEN_CLOCK_MODES
        )
        p.ground_truth = self._ground_truth(p)
        self._last = p
        ms = (time.perf_counter() - t0) * 1e3
        off_now = np.abs(target - np.asarray(p.joint_angles_deg, dtype=float))
        err_now = float(off_now.max())
        # a joint counted as pinned that did leave its stop in the end (a slow release) is not
        pinned &= off_now > tol
        pinned_names = tuple(n for n, k in zip(self._perceptor_names, pinned, strict=True) if k)
        new_pins = set(pinned_names) - self._pins_reported
        if new_pins:
            self._pins_reported |= new_pins
            log.warning(
                "reset: %s sit(s) on a joint stop; rcssserver3d ignores velocity commands for a "
                "joint that is not strictly inside its limits (reference §8.3), so it stays there",
                ", ".join(sorted(new_pins)),
            )
        converged = done
        self.last_reset = ResetStats(
            cycles=joint_cycles + settle,
            joint_cycles=joint_cycles,
            settle_cycles=settle,
            ms=ms,
            max_joint_error_deg=err_now,
            converged=converged,
            pinned=pinned_names,
        )
        self.resets += 1
        log.debug("reset %d: %s", self.resets, self.last_reset)
        return p, settle

    @property
    def _team(self) -> str:
        """The side as the trainer's commands name it (``Left``/``Right``)."""
        return "Left" if self.side == "left" else "Right"

    @property
    def places_any_orientation(self) -> bool:
        """Whether this server's trainer turns robots (the SPL fork's ``(rot rx ry rz)``;
        upstream 0.7.3 ignores it): found out once, by turning the robot while it is held in
        the air and reading its orientation back from the monitor stream (a few cycles)."""
        if self._rot is None:
            self._rot = self._probe_rot()
        return self._rot

    def _probe_rot(self) -> bool:
        self._relaunch_if_dead()
        assert self.unum is not None
        team = self._team
        zero = self._velocity_text(np.zeros(self._n))
        high = (0.0, 0.0, 1.5)
        p = self._exchange(
            zero, tc.agent(self.unum, team, pos=high, rot=(0.0, 40.0, 0.0)), wait=False
        )
        for _ in range(3):
            p = self._exchange(zero, wait=False)
        self._sync_monitor(p)
        s = self._tracker.newest()
        if s is None or s.torso is None:
            raise BackendError("no monitor frame shows the robot (is the monitor port right?)")
        up_z = float(s.torso[2, 2])  # world z of the torso's up axis: cos 40° when turned
        self._exchange(zero, tc.agent_move(self.unum, team, high, -90.0), wait=False)
        return up_z < math.cos(math.radians(20.0))

    def _reset_visible(self, p: Perception, pose: RobotPose, z: float) -> bool:
        """Has the final trainer frame taken effect in the cycle ``p`` describes?"""
        running = p.game.play_mode not in FROZEN_CLOCK_MODES
        s = self._tracker.select(p.game.game_time, running)
        if s is None or s.torso is None:
            return False
        if (
            running
            and abs(s.game_time - p.game.game_time)
            > (self.monitor_interval - 1) * CYCLE_S + TIME_TOLERANCE_S
        ):
            return False  # the frame is not the percept's cycle
        tx, ty, tz = s.torso[:3, 3]
        return bool(tz < z + 0.5 * self.hover_height and math.hypot(tx - pose.x, ty - pose.y) < 0.1)

    def _start_angles(self, given: np.ndarray | Mapping[str, float] | None) -> np.ndarray:
        out = np.zeros(self._n)
        if given is None:
            pass
        elif isinstance(given, Mapping):
            index = {}
            for i, j in enumerate(self._model.joints):
                for alias in (j.effector, j.perceptor, j.nao_name, j.manual_name):
                    index[alias] = i
            for name, v in given.items():
                if name not in index:
                    raise KeyError(
                        f"unknown joint {name!r} for robot type {self.robot_type}; valid effector "
                        f"names: {', '.join(self._model.effector_names)}"
                    )
                out[index[name]] = float(v)
        else:
            arr = np.asarray(given, dtype=float)
            if arr.shape != (self._n,):
                raise ValueError(f"joint_angles_deg must have shape ({self._n},), got {arr.shape}")
            out[:] = arr
        if not np.isfinite(out).all():
            raise ValueError("joint_angles_deg must be finite")
        # keep targets strictly inside the stops (the server ignores commands at a stop), and
        # farther from a stop than the tolerance, so that a joint left on that stop is clearly
        # not at its target (it is either driven off the stop or counted as pinned)
        margin = max(0.05, 2.0 * self.reset_tolerance_deg)
        return np.clip(out, self._ranges[:, 0] + margin, self._ranges[:, 1] - margin)

    def _standing_z(self, angles_deg: np.ndarray) -> float:
        """Torso-centre height at which the lowest point of the upright robot in this pose
        touches the ground."""
        key = tuple(np.round(angles_deg, 2).tolist())
        z = self._stand_cache.get(key)
        if z is None:
            z = resting_torso_height(self.robot_type, np.asarray(angles_deg, float))
            if len(self._stand_cache) > 256:
                self._stand_cache.clear()
            self._stand_cache[key] = z
        return z

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

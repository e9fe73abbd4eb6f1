"""The server loop: the embedded world behind the rcssserver3d 0.7.3 protocol.

One thread, one ``selectors`` loop, non-blocking sockets. Every cycle follows rcssserver3d's order
(wire reference §2):

1. **read** – accept connections, read every socket, realise every complete frame: hinge targets,
   ``say`` and ``syn`` at once, ``scene``/``init``/``beam``/``pass`` are kept for step 3; in sync
   mode repeat until every agent that is waited for has sent ``(syn)``; on monitor cycles (every
   2nd) apply trainer commands;
2. **send** the percept computed at the end of the previous cycle to every agent (one frame, one
   ``send``);
3. **physics** – robots added/removed (World rebuild), ``init``, ``beam``, ``pass``, joint
   velocities, one 20 ms World step (``dead_time_cycles=0``: SimSpark's one-cycle dead time comes
   from this order), the referee;
4. **end** – close dead connections, compute each agent's percept, send a monitor frame on monitor
   cycles.

In real-time mode each cycle lasts at least 20 ms of wall time (the server skips lost time instead
of catching up); meanwhile arriving bytes are buffered. With real time off cycles run back to back.

Differences from the real server that make it more robust: a connection without robot is never
waited for in sync mode (the real server freezes), the sync grace period counts percepts instead of
cycles, an optional sync time-out drops silent agents, oversized frames close the connection,
monitors and agents that do not read lose frames instead of stalling anything.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import math
import selectors
import signal
import socket
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import ClassVar

import numpy as np

from robocup_gym.protocol.constants import DEFAULT_AGENT_PORT, DEFAULT_MONITOR_PORT
from robocup_gym.protocol.framing import encode_frame
from robocup_gym.protocol.perceptor_format import format_perception
from robocup_gym.robot.types import TYPE_NUMBERS
from robocup_gym.server.agent import AgentState
from robocup_gym.server.agent_messages import AgentMessages
from robocup_gym.server.monitor import MonitorStream, RobotView
from robocup_gym.server.trainer_commands import TrainerCommands
from robocup_gym.server.wire import Connection
from robocup_gym.server.worldhost import WorldHost
from robocup_gym.sim import ENGINES, SimulationDivergedError
from robocup_gym.sim.memory import tune_allocator
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.sim.referee import BEAM_MODES, Referee, Rules
from robocup_gym.sim.teams import Player
from robocup_gym.sim.vision import VisionConfig

log = logging.getLogger("robocup_gym.server")

_POLL_S = 0.25
"""Longest single wait in select (so a stop request or a sync time-out is noticed quickly)."""


class PortInUseError(OSError):
    """The agent or monitor port cannot be bound (the message names the port)."""


class MonitorState:
    """One monitor connection."""

    def __init__(self, conn: Connection) -> None:
        self.conn = conn
        self.needs_full = True


class SimServer(AgentMessages, TrainerCommands):
    """rcssserver3d-compatible server around the embedded world (SimSpark's step on ODE by
    default, or the MuJoCo approximation).

    Args:
        agent_port: TCP port for agents (0 = any free port; see :attr:`agent_port` after binding).
        monitor_port: TCP port for monitors/trainers (0 = any free port).
        host: address to bind (``"0.0.0.0"`` = all interfaces, as rcssserver3d).
        sync: sync mode: each cycle waits for ``(syn)`` from every agent (wire reference §6).
        real_time: make each cycle last at least 20 ms of wall time.
        ground_truth: add ``mypos``/``myorien``/``ballpos`` to ``See`` (FC Portugal's "cheats",
            needed by RobocupGym).
        vision_noise: vision noise, calibration offset and beam noise (rcssserver3d: on).
        view_cone_deg: vision opening (120; 360 = "full vision").
        field_lines: field lines in ``See`` (``L``), as upstream rcssserver3d 0.7.3; the SPL
            fork sends none (``False`` with ``decimals=3`` gives the fork's percepts).
        rules: the automatic referee: ``True`` every rule, ``False`` none (play modes only by
            trainer command), or a mapping that switches single rules
            (:class:`robocup_gym.sim.referee.Rules`).
        monitor_interval: cycles per monitor frame (2 = 25 Hz as rcssserver3d; 1 = 50 Hz).
        sync_timeout: seconds a sync-mode cycle waits for a silent agent before closing its
            connection (``None`` = wait forever, as rcssserver3d).
        seed: random seed (noise, coin toss) for reproducible runs.
        physics: :class:`~robocup_gym.sim.physics.PhysicsConfig` of the MuJoCo world (only with
            ``engine="mujoco"``).
        engine: ``"ode"`` (SimSpark's own step: the physics of rcssserver3d, the default) or
            ``"mujoco"`` (the fast approximation).
        decimals: digits after the point in percepts: 2 as upstream rcssserver3d 0.7.3, 3 as
            the SPL fork.
        robot_types: robot types agents may load (``scene``/``init`` of another is refused).
        type_limits: the league's per-team robot-type rules (off: e.g. eleven robots of type 0).
    """

    def __init__(
        self,
        agent_port: int = DEFAULT_AGENT_PORT,
        monitor_port: int = DEFAULT_MONITOR_PORT,
        host: str = "0.0.0.0",
        sync: bool = False,
        real_time: bool = True,
        *,
        ground_truth: bool = False,
        vision_noise: bool = True,
        view_cone_deg: float = 120.0,
        field_lines: bool = True,
        rules: bool | Mapping[str, bool] = True,
        monitor_interval: int = 2,
        sync_timeout: float | None = None,
        seed: int | None = None,
        physics: object | None = None,
        decimals: int = 2,
        robot_types: Sequence[int] = TYPE_NUMBERS,
        type_limits: bool = True,
        engine: str = "ode",
    ) -> None:
        if engine not in ENGINES:
            raise ValueError(f"unknown engine {engine!r}; engines: {', '.join(ENGINES)}")
        if monitor_interval < 1:
            raise ValueError(f"monitor_interval must be >= 1, got {monitor_interval}")
        for what, port in (("agent", agent_port), ("monitor", monitor_port)):
            if not 0 <= int(port) <= 65535:
                raise ValueError(
                    f"{what} port {port} is not a port number (0-65535; 0 = a free port)"
                )
        if int(agent_port) == int(monitor_port) != 0:
            raise ValueError(
                f"agent and monitor port are both {agent_port}; they must differ (or be 0)"
            )
        if sync_timeout is not None and not (0 < sync_timeout < math.inf):
            raise ValueError(f"sync_timeout must be a number of seconds > 0, got {sync_timeout}")
        if decimals not in (2, 3):
            raise ValueError(
                f"decimals must be 2 (rcssserver3d 0.7.3) or 3 (SPL fork), got {decimals}"
            )
        bad_types = sorted(set(robot_types) - {0, 1, 2, 3, 4})
        if bad_types or not robot_types:
            raise ValueError(
                f"robot_types must be a non-empty subset of 0–4, got {list(robot_types)}"
            )
        self.decimals = int(decimals)
        tune_allocator()  # worlds come and go with the agents: keep the process from growing
        self.host_address = host
        self.requested_ports = (int(agent_port), int(monitor_port))
        self.sync = bool(sync)
        self.real_time = bool(real_time)
        self.monitor_interval = int(monitor_interval)
        self.sync_timeout = sync_timeout
        vision = VisionConfig(
            noise=vision_noise,
            view_cone_deg=float(view_cone_deg),
            ground_truth=ground_truth,
            lines=bool(field_lines),
        )
        self.engine = engine
        # the referee off (rules=False) is the self-collision rule off too
        self.world_host = WorldHost(
            vision, physics, seed, engine=engine, self_collisions=Rules.of(rules).any
        )
        self.referee = Referee(
            self.world_host,
            rules=rules,
            rng=self.world_host.rng,
            robot_types=robot_types,
            type_limits=type_limits,
        )
        self.stream = MonitorStream()
        self.stream.fouls = self.referee.fouls
        self.stream.kick_rules = self.referee.kicks
        self.agents: list[AgentState] = []
        self.monitors: list[MonitorState] = []
        self.cycle = 0
        self.selected: tuple[str, int] | None = None
        self._full_requested = False
        self._next_cid = 1
        self._sel: selectors.BaseSelector | None = None
        self._agent_listener: socket.socket | None = None
        self._monitor_listener: socket.socket | None = None
        self._wake_r: socket.socket | None = None
        self._wake_w: socket.socket | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._running = threading.Event()
        self._done = threading.Event()
        self.agent_port = 0
        self.monitor_port = 0
        self.on_cycle: Callable[[SimServer], None] | None = None
        """Optional hook called at the end of every cycle (tests, tools)."""

    # ------------------------------------------------------------------ lifecycle
    @property
    def world(self):
        """The current world (:func:`robocup_gym.sim.make_world`; replaced when robots
        change)."""
        return self.world_host.world

    def bind(self) -> tuple[int, int]:
        """Open both listening sockets; returns the bound (agent port, monitor port).

        Raises:
            PortInUseError: naming the port that is taken.
            OSError: other bind problems (address not available, permission, …).
        """
        if self._sel is not None:
            return self.agent_port, self.monitor_port
        agent_port, monitor_port = self.requested_ports
        agent = self._listen(agent_port, "agent")
        try:
            monitor = self._listen(monitor_port, "monitor")
        except BaseException:
            agent.close()
            raise
        self._agent_listener, self._monitor_listener = agent, monitor
        self.agent_port = agent.getsockname()[1]
        self.monitor_port = monitor.getsockname()[1]
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        sel = selectors.DefaultSelector()
        sel.register(agent, selectors.EVENT_READ, ("listen", "agent"))
        sel.register(monitor, selectors.EVENT_READ, ("listen", "monitor"))
        sel.register(self._wake_r, selectors.EVENT_READ, ("wake", None))
        self._sel = sel
        log.info(
            "listening on %s: agents port %d, monitors port %d",
            self.host_address,
            self.agent_port,
            self.monitor_port,
        )
        return self.agent_port, self.monitor_port

    def _listen(self, port: int, what: str) -> socket.socket:
        family = socket.AF_INET6 if ":" in self.host_address else socket.AF_INET
        s = socket.socket(family, socket.SOCK_STREAM)
        try:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            s.bind((self.host_address, port))
            s.listen(socket.SOMAXCONN)
            s.setblocking(False)
        except OSError as exc:
            s.close()
            if exc.errno == errno.EADDRINUSE:
                raise PortInUseError(
                    exc.errno,
                    f"{what} port {port} is already in use (is another rcssserver3d or "
                    f"robocup-gym serve running?); choose another with --{what}-port",
                ) from None
            raise OSError(
                exc.errno, f"cannot listen on {self.host_address}:{port} ({what} port): {exc}"
            ) from None
        return s

    def run(self) -> None:
        """Serve until :meth:`stop` / :meth:`request_stop` / ``(killsim)``; closes everything."""
        self.bind()
        self._running.set()
        next_t = time.monotonic()
        try:
            while not self._stop.is_set():
                self._cycle()
                if (self.real_time or self._idle()) and not self._stop.is_set():
                    next_t += CYCLE_S
                    now = time.monotonic()
                    if next_t <= now:
                        next_t = now  # behind: skip the lost time, never catch up
                    else:
                        self._wait_until(next_t)
        finally:
            self._shutdown()

    def _idle(self) -> bool:
        """No robot in the world: cycles are paced at real time even with real time off (the
        real server spins at full CPU then; nothing is gained by it)."""
        return not any(a.has_robot and not a.killed for a in self.agents)

    def start_in_thread(self) -> tuple[int, int]:
        """Bind and run in a daemon thread; returns the bound (agent port, monitor port)."""
        ports = self.bind()
        self._thread = threading.Thread(
            target=self._thread_main, name="robocup-gym-serve", daemon=True
        )
        self._thread.start()
        self._running.wait(5.0)
        return ports

    def _thread_main(self) -> None:
        try:
            self.run()
        except Exception:  # pragma: no cover - logged for the test that started us
            log.exception("server thread crashed")

    def request_stop(self) -> None:
        """Ask the loop to stop (thread- and signal-safe)."""
        self._stop.set()
        w = self._wake_w
        if w is not None:
            with contextlib.suppress(OSError):
                w.send(b"x")

    def stop(self, timeout: float = 10.0) -> None:
        """Stop the server and wait for its thread; closes all sockets."""
        self.request_stop()
        if self._thread is not None:
            self._thread.join(timeout)
            if self._thread.is_alive():  # pragma: no cover
                log.error("server thread did not stop within %.1f s", timeout)
            self._thread = None
        elif not self._running.is_set():
            self._shutdown()

    @property
    def stopped(self) -> bool:
        return self._done.is_set()

    def __enter__(self) -> SimServer:
        self.start_in_thread()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _shutdown(self) -> None:
        if self._done.is_set():
            return
        for a in self.agents:
            a.conn.close()
        for m in self.monitors:
            m.conn.close()
        for s in (self._agent_listener, self._monitor_listener, self._wake_r, self._wake_w):
            if s is not None:
                with contextlib.suppress(OSError):
                    s.close()
        if self._sel is not None:
            self._sel.close()
        self.agents.clear()
        self.monitors.clear()
        self._done.set()
        log.info("server stopped after %d cycles", self.cycle)

    # ------------------------------------------------------------------ I/O
    def _poll(self, timeout: float) -> None:
        sel = self._sel
        assert sel is not None
        for key, _ in sel.select(timeout):
            kind, obj = key.data
            if kind == "conn":
                self._receive(obj)
            elif kind == "listen":
                self._accept(key.fileobj, obj)  # type: ignore[arg-type]
            else:  # wake-up
                try:
                    while self._wake_r.recv(4096):  # type: ignore[union-attr]
                        pass
                except OSError:
                    pass

    def _receive(self, conn: Connection) -> None:
        """Read what ``conn`` has; a connection that closed leaves the selector."""
        conn.receive()
        if not conn.alive:
            self._unregister(conn)

    def _unregister(self, conn: Connection) -> None:
        if self._sel is None:
            return
        with contextlib.suppress(KeyError, ValueError):
            self._sel.unregister(conn.sock)  # type: ignore[union-attr]

    def _accept(self, listener: socket.socket, what: str) -> None:
        for _ in range(64):
            try:
                sock, addr = listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:  # e.g. EMFILE: leave the rest in the backlog
                log.warning("accept on the %s port failed: %s", what, exc)
                return
            conn = Connection(sock, self._next_cid, addr, what)
            self._next_cid += 1
            self._sel.register(sock, selectors.EVENT_READ, ("conn", conn))  # type: ignore[union-attr]
            if what == "agent":
                self.agents.append(AgentState(conn))
            else:
                self.monitors.append(MonitorState(conn))
            log.info("%r connected", conn)
            # what came with the connection is read now, not at the next poll: a read phase that
            # ends with this poll (the last awaited (syn) in the same batch) takes a scene or a
            # trainer command sent before that (syn) in every case, not only when the server
            # happened to see the connection a poll earlier
            self._receive(conn)

    def _wait_until(self, deadline: float) -> None:
        while not self._stop.is_set():
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return
            self._poll(min(remaining, _POLL_S))

    # ------------------------------------------------------------------ the cycle
    def _cycle(self) -> None:
        monitor_cycle = self.cycle % self.monitor_interval == 0
        self._read_phase(monitor_cycle)
        if self._stop.is_set():
            return
        self._send_percepts()
        self._physics()
        self._end_cycle(monitor_cycle)
        self.cycle += 1
        if self.on_cycle is not None:
            self.on_cycle(self)

    def _read_phase(self, monitor_cycle: bool) -> None:
        self._poll(0)
        self._process_agents()
        if self.sync:
            started = time.monotonic()
            while not self._stop.is_set() and not self._all_synced():
                if self.sync_timeout is not None and time.monotonic() - started > self.sync_timeout:
                    for a in self.agents:
                        if a.waited_for and not a.synced:
                            log.warning(
                                "%r sent no (syn) for %.1f s: closing the connection",
                                a.conn,
                                self.sync_timeout,
                            )
                            a.conn.alive = False
                            self._unregister(a.conn)
                    break
                self._poll(_POLL_S)
                self._process_agents()
        # the monitor port is read on monitor cycles only, as on rcssserver3d (SimSpark runs a
        # control node's StartCycle once its own clock, stepped by the monitor step, has caught
        # up): a trainer command sent in any other cycle takes effect a cycle later
        if monitor_cycle:
            self._process_monitors()

    def _all_synced(self) -> bool:
        return all(a.synced for a in self.agents if a.waited_for)

    _limits_cache: ClassVar[dict[int, dict[str, float]]] = {}

    # ------------------------------------------------------------------ send / physics / end
    def _send_percepts(self) -> None:
        for a in self.agents:
            frame = a.percept
            if frame is not None:
                a.percept = None
                if a.conn.alive:
                    a.conn.send(frame)
                    a.percepts_sent += 1

    def _players(self) -> list[Player]:
        out = []
        host = self.world_host
        for a in self.agents:
            if a.side is None or not a.has_robot or a.killed:
                continue
            i = host.index(a.key)
            if i is not None:
                out.append(Player(a.key, i, a.side, a.unum))  # type: ignore[arg-type]
        return out

    def _physics(self) -> None:
        host = self.world_host
        # 1. robots created (scene) and removed (disconnect, kill)
        remove = []
        for a in self.agents:
            if a.has_robot and (not a.conn.alive or a.killed):
                remove.append(a.key)
        add = [
            (a.key, a.scene_type) for a in self.agents if a.scene_type is not None and a.conn.alive
        ]
        if add or remove:
            for a in self.agents:
                if a.key in remove:
                    self._release(a)
                    a.has_robot = False
            try:
                added = set(host.change_robots(add, remove))
            except Exception:
                log.exception("could not rebuild the world; robots unchanged")
                added = set()
            for a in self.agents:
                if a.scene_type is not None:
                    if a.key in added:
                        a.has_robot = True
                        a.percepts_sent = 0
                        a.ever_synced = False
                        log.info("%r: robot of type %d created", a.conn, a.scene_type)
                    else:
                        a.robot_type = None
        world = self.world
        # 2. init, beam, pass
        for a in self.agents:
            if a.init is not None and a.has_robot and not a.killed:
                self._init(a, *a.init)
        play_mode = world.game.play_mode
        players = None
        for a in self.agents:
            if a.beam is not None and a.side is not None and play_mode in BEAM_MODES:
                i = host.index(a.key)
                if i is not None:
                    x, y, rot = a.beam
                    try:
                        world.beam(i, x, y, rot)
                    except (ValueError, OverflowError) as exc:
                        a.conn.warn("beam %r ignored: %s", a.beam, exc)
            if a.want_pass and a.side is not None:
                players = players or self._players()
                self.referee.players = players
                i = host.index(a.key)
                if i is not None:
                    self.referee.request_pass(
                        Player(a.key, i, a.side, a.unum),  # type: ignore[arg-type]
                        host.ball_touchers(),
                    )
        # 3. joint velocities
        for a in self.agents:
            if a.joints and a.has_robot and not a.killed:
                i = host.index(a.key)
                if i is not None:
                    try:
                        world.command(i, _joint_command(a.joints, world.robots[i].effector_names))
                    except (KeyError, ValueError) as exc:
                        a.conn.warn("joint command ignored: %s", exc)
            a.clear_actions()
        # 4. one 20 ms step and the referee
        try:
            world.step()
            if not host.sane():
                raise SimulationDivergedError(
                    f"simulation diverged at cycle {world.cycle} (t = {world.time:.2f} s): "
                    "positions out of bounds"
                )
        except SimulationDivergedError as exc:
            n = host.divergences + 1
            if n <= 5 or n % 100 == 0:
                log.error("%s -- world reset, the game goes on (divergence #%d)", exc, n)
            host.recover()
        except Exception:
            log.exception("physics step failed -- world reset, the game goes on")
            host.recover()
        try:
            self.referee.update(self._players())
        except Exception:
            log.exception("referee failed this cycle")

    def _end_cycle(self, monitor_cycle: bool) -> None:
        # close dead connections (a robot is removed at the next physics step)
        for a in self.agents:
            if not a.conn.alive and not a.conn.closed:
                self._unregister(a.conn)
                a.conn.close()
        self.agents = [a for a in self.agents if a.conn.alive or a.has_robot]
        for m in self.monitors:
            if not m.conn.alive and not m.conn.closed:
                self._unregister(m.conn)
                m.conn.close()
        # a trainer that sent its commands and closed at once: they wait for the next monitor
        # cycle, as rcssserver3d reads a monitor's data and its end together
        self.monitors = [m for m in self.monitors if m.conn.alive or m.conn.inbox]
        # percepts for the next cycle
        world = self.world
        host = self.world_host
        receivers = []
        for a in self.agents:
            a.synced = False
            if not a.has_robot or a.killed or not a.conn.alive:
                continue
            i = host.index(a.key)
            if i is not None:
                receivers.append((a, i))
        try:  # every robot's perception at once (their visions computed together)
            perceptions = world.perceive_all([i for _, i in receivers], ground_truth=False)
        except Exception:
            log.exception("percepts could not be built together; building them one by one")
            perceptions = None
        for k, (a, i) in enumerate(receivers):
            try:
                p = world.perceive(i, ground_truth=False) if perceptions is None else perceptions[k]
                text = format_perception(p, self.decimals)
            except Exception:
                log.exception("%r: percept could not be built", a.conn)
                continue
            if text:
                a.percept = encode_frame(text)
        if monitor_cycle and self.monitors:
            self._send_monitor_frames()

    def _robot_views(self) -> list[RobotView]:
        host = self.world_host
        views = []
        for a in self.agents:
            if not a.conn.alive and not a.has_robot:
                continue
            i = host.index(a.key) if a.has_robot and not a.killed else None
            views.append(
                RobotView(
                    key=a.key,
                    robot_index=i,
                    robot_type=a.robot_type or 0,
                    side=a.side if i is not None else None,
                    unum=a.unum if i is not None else None,
                    selected=self.selected is not None and self.selected == (a.side, a.unum),
                )
            )
        return views

    def _send_monitor_frames(self) -> None:
        views = self._robot_views()
        world = self.world
        half = self.referee.half
        teams = self.referee.teams.names
        stream = self.stream
        if self._full_requested or stream.needs_full(views):
            self._full_requested = False
            frame = encode_frame(stream.full_frame(world, views, half, teams))
            for m in self.monitors:
                m.conn.send(frame)
                m.needs_full = False
            return
        old = [m for m in self.monitors if not m.needs_full]
        new = [m for m in self.monitors if m.needs_full]
        if old:
            frame = encode_frame(stream.delta_frame(world, views, half, teams))
            for m in old:
                m.conn.send(frame)
        if new:
            frame = encode_frame(stream.full_frame(world, views, half, teams))
            for m in new:
                if m.conn.send(frame):
                    m.needs_full = False


def _joint_command(
    joints: dict[str, float], names: tuple[str, ...]
) -> dict[str, float] | np.ndarray:
    """The joint velocities for :meth:`World.command`: when every joint is commanded (the usual
    case), the same numbers as an array in the robot's effector order (much cheaper to check than
    the mapping); otherwise the mapping itself."""
    if len(joints) != len(names):
        return joints
    try:
        return np.array([joints[n] for n in names], dtype=float)
    except KeyError:
        return joints


def serve(
    agent_port: int = DEFAULT_AGENT_PORT,
    monitor_port: int = DEFAULT_MONITOR_PORT,
    host: str = "0.0.0.0",
    sync: bool = False,
    real_time: bool = True,
    **options: object,
) -> None:
    """Run the server in the foreground until Ctrl-C, SIGTERM or ``(killsim)``.

    Prints where it listens. Extra keyword options are those of :class:`SimServer`
    (``ground_truth``, ``vision_noise``, ``view_cone_deg``, ``field_lines``, ``rules``,
    ``monitor_interval``,
    ``sync_timeout``, ``seed``).

    Raises:
        PortInUseError: if a port is taken (the message names it).
    """
    server = SimServer(agent_port, monitor_port, host, sync, real_time, **options)  # type: ignore[arg-type]
    a_port, m_port = server.bind()
    mode = ", ".join(
        [
            "sync mode" if server.sync else "real-time agents (no sync)",
            "real time" if server.real_time else "as fast as possible",
            {"ode": "SimSpark's physics on ODE", "mujoco": "MuJoCo engine"}[server.engine],
        ]
    )
    print(
        f"robocup-gym serve: agents on {host}:{a_port}, monitors on {host}:{m_port} ({mode}); "
        "Ctrl-C to stop",
        flush=True,
    )
    installed: list[tuple[int, object]] = []
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            installed.append((sig, signal.getsignal(sig)))
            signal.signal(sig, lambda *_: server.request_stop())
    try:
        server.run()
    finally:
        for sig, old in installed:
            signal.signal(sig, old)  # type: ignore[arg-type]
    print(f"robocup-gym serve: stopped after {server.cycle} cycles", flush=True)

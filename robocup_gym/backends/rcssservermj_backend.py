"""A real RCSSServerMJ (``rcssservermj``) behind the :class:`Backend` interface:
``backend="rcssservermj"`` with a league robot (``robot="T1"``), so any task runs on the league's
real server too.

The backend starts its own server (:class:`~robocup_gym.backends.rcssservermj.RcssServerMJProcess`:
sync mode, real time off, no viewer, OS-chosen ports, ended with its parent) or connects to a
running one (``port=``/``monitor_port=``; it must run in sync mode). It joins as one agent and
keeps a monitor connection, through which it places the robot and the ball
(``(agent (unum …) (team …) (move3d x y z qw qx qy qz))``, ``(ball (pos …) (vel …))``) and
reads the ball's position (the RSMP stream, every second cycle, 4 decimals).

What differs from the in-process backend (``"rcsssmj"``), both stepping the same simulation:

* **Start angles**: the server's placement sets every joint to 0, so episodes start there;
  other start angles are refused (the league robots' task defaults are all 0).
* **Ground truth** comes from what the server sends: the torso's pose from the agent's
  ``pos``/``quat`` perceptors (3 decimals), its velocity by differences over one cycle, the
  ball from the monitor frame of the perception's cycle, or in a cycle without one (the server
  sends one every second cycle) the cycle before, and its velocity by differences between
  frames. Frames the server sent after the perception (it steps on as soon as it has the
  answer) are never used, so what an episode sees does not depend on thread timing. The
  in-process backend has the exact state.
* **Reset timing**: a monitor command is applied after the physics of the second or third
  server step after it is sent (the server's monitor thread reads it before or after its agent
  thread reads the answer), and the perception after that still shows the sensors from
  before; the reset places the robot 1 m higher first, then where asked (at a cycle chosen so
  that the placement shows in a cycle with a monitor frame, again if the server took the
  command a cycle late), and returns the first perception that shows it there: the state one
  limp 20 ms step after the placement, as the in-process backend's reset (a few cycles).
* **Repeatability**: the server's MuJoCo keeps its solver's warm start across placements, so
  a reset does not repeat an episode bit for bit (the ball rests 0.1 mm higher or lower);
  environments on this backend have ``spec.nondeterministic`` set.
"""

from __future__ import annotations

import math
import time
from collections import Counter, deque
from typing import Any

import numpy as np

from robocup_gym.backends.base import Backend, BackendError, EpisodeSetup
from robocup_gym.backends.league_backend import _model_quat, league_ball, league_pose, pd_commands
from robocup_gym.protocol.connection import Connection
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.league import (
    LeagueMonitorReader,
    LeaguePerception,
    format_pd_commands,
    parse_league_perception,
    to_simspark_torso_quat,
)
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.types import AgentCommand, GroundTruth, PDCommand, Perception

__all__ = ["RcssServerMJBackend"]

_RESET_ATTEMPTS = 8
"""Placements a reset tries before it settles for one limp step more (measured under a 4-process
CPU load: 146 of 150 resets placed once, none needed more than 4)."""
_FRAMES_KEPT = 8
_PLACE_TOLERANCE_M = 0.01
"""How close the perceived torso and the monitor's ball must be to the requested placement for
the reset to count as done, m (one 20 ms limp step moves them by millimetres)."""


def _perception_cycle(t: float) -> int:
    """The server cycle of a perception's time: the server truncates it to 2 decimals, so a
    cycle's time 1.44 s can print as 1.43 (cycles are 20 ms: an odd last digit is one below)."""
    return round(t / CYCLE_S + 0.25)


class RcssServerMJBackend(Backend):
    """One league robot on a real ``rcssservermj`` (see the module docstring).

    Args:
        robot: The robot model (``"T1"``, ``"K1"``).
        team: Team name the agent joins with.
        port, monitor_port: A running server's agent and monitor ports (both or neither);
            ``None``: start a private server.
        host: The running server's host.
        timeout: Seconds a message from the server may take.
        reset_cycles: Most cycles a reset waits for the placement to show.
        seed, vision, robot_type: Accepted for the common interface (the league's perceptions
            have no noise and always include ``See``; ``robot_type`` must be 0).

    Raises:
        robocup_gym.robot.league.RcsssmjUnavailableError: no ``rcsssmj`` to start a server with.
        BackendError: the server did not start or refused the agent.
    """

    name = "rcssservermj"
    deterministic = False

    def __init__(
        self,
        *,
        robot: str = "T1",
        team: str = "RobocupGym",
        port: int | None = None,
        monitor_port: int | None = None,
        host: str = "127.0.0.1",
        timeout: float = 20.0,
        reset_cycles: int = 10,
        seed: int | None = None,
        vision: bool = False,
        robot_type: int = 0,
    ) -> None:
        super().__init__(robot_type=robot_type, seed=seed, vision=vision)
        from robocup_gym.backends.rcssservermj import LeagueAgentLink, RcssServerMJProcess
        from robocup_gym.robot.league import league_robot

        if (port is None) != (monitor_port is None):
            raise ValueError("give both port and monitor_port (a running server), or neither")
        self.robot = str(robot)
        self.team = str(team)
        self._model = league_robot(self.robot)
        self.timeout = float(timeout)
        self.reset_cycles = int(reset_cycles)
        self.server: RcssServerMJProcess | None = None
        self.link = None
        self._monitor: Connection | None = None
        try:
            self._reader = LeagueMonitorReader()
            self._frames: deque[tuple[int, np.ndarray | None]] = deque(maxlen=_FRAMES_KEPT)
            if port is None:
                self.server = RcssServerMJProcess()
                port = self.server.agent_port
                self._monitor, scene = self.server.take_monitor()
                for frame in scene:
                    self._take_frame(frame)
            else:
                self._monitor = Connection.open(
                    host, int(monitor_port), what="monitor", timeout=timeout
                )
            self.link = LeagueAgentLink(int(port), self.robot, self.team, 1, timeout=timeout)
            self._recv()  # the first perception, which the server waits an answer to
        except BaseException:
            self.close()
            raise
        self._last_pos: np.ndarray | None = None
        self._delay_parities: Counter[int] = Counter()
        """How often the cycles from the perception a placement was sent with to the first that
        shows it were even (0) and odd (1): mostly 3, sometimes 2 (or more, under load), as the
        server's monitor thread reads the command before or after its agent thread reads the
        answer. A reset expects the more frequent parity (even before any), so a rare delay does
        not mislead the next reset."""
        self._limp = {n: PDCommand(0.0) for n in self._model.effector_names}

    @property
    def robot_model(self) -> Any:
        return self._model

    @property
    def places_any_orientation(self) -> bool:
        return False  # rcssservermj places a player upright, every joint at 0

    # ------------------------------------------------------------------ wire
    def _recv(self) -> bytes:
        try:
            return self.link.recv()
        except (OSError, ConnectionError, TimeoutError) as e:
            tail = self.server.log_tail(1500) if self.server is not None else ""
            raise BackendError(
                f"the rcssservermj connection failed ({e}); is the server running?"
                + (f" Its output ends with:\n{tail}" if tail else "")
            ) from e

    def _send(self, commands: dict[str, PDCommand]) -> bytes:
        """Answer the pending perception with ``commands``; return the next perception."""
        try:
            self.link.send(format_pd_commands(commands))
        except OSError as e:
            raise BackendError(f"the rcssservermj connection failed ({e})") from e
        return self._recv()

    def _monitor_command(self, text: str) -> None:
        try:
            self._monitor.send(text)
        except OSError as e:
            raise BackendError(f"the rcssservermj monitor connection failed ({e})") from e

    def _read_monitor(self, until_cycle: int | None = None) -> None:
        """Take every monitor frame that has arrived; with ``until_cycle``, wait (up to the
        timeout) for one of that cycle or later. The server sends a frame after every second
        step (even cycles) before it makes the next perceptions, so the frame of a perception's
        cycle or the one before has always been sent when the perception arrives."""
        deadline = time.monotonic() + self.timeout
        while True:
            try:
                frames = self._monitor.available()
            except OSError as e:  # (a closed connection included)
                raise BackendError(f"the rcssservermj monitor connection failed ({e})") from e
            if frames:
                for frame in frames:
                    self._take_frame(frame)
                continue
            if until_cycle is None or (self._frames and self._frames[-1][0] >= until_cycle):
                return
            if time.monotonic() > deadline:
                raise BackendError("no monitor message from rcssservermj in time")
            time.sleep(0.0005)

    def _take_frame(self, frame: bytes) -> None:
        try:
            self._reader.feed(frame)
        except ProtocolError:
            return  # a delta before the first full scene: wait for the next full one
        t = self._reader.time
        if t is None:
            return
        cycle = round(t / CYCLE_S)
        if self._frames and cycle <= self._frames[-1][0]:
            return
        self._frames.append((cycle, self._reader.ball_position()))

    def _frame_cycle(self, cycle: int) -> int:
        """The newest cycle at or before ``cycle`` that has a monitor frame (every second one:
        even cycles in rcsssmj, odd ones if the frames seen so far say so)."""
        parity = self._frames[-1][0] % 2 if self._frames else 0
        return cycle - (cycle - parity) % 2

    def _ball_at(self, cycle: int) -> tuple[np.ndarray, np.ndarray]:
        """The ball's position (m) in the monitor frame of ``cycle`` (waiting for it), and its
        velocity (m/s) by the difference from the frame before (zeros without one); NaN
        before the monitor has shown a scene with the ball."""
        self._read_monitor(until_cycle=cycle)
        nan = np.full(3, np.nan)
        newest = [(c, b) for c, b in self._frames if c <= cycle][-2:]
        if not newest or newest[-1][0] != cycle or newest[-1][1] is None:
            return nan, np.zeros(3)
        (c1, b1) = newest[-1]
        if len(newest) < 2 or newest[0][1] is None:
            return b1.copy(), np.zeros(3)
        c0, b0 = newest[0]
        return b1.copy(), (b1 - b0) / ((c1 - c0) * CYCLE_S)

    # ------------------------------------------------------------------ episode control
    def _place(self, start: EpisodeSetup) -> tuple[Perception, int]:
        """Place the robot (all joints at 0) and the ball through the monitor, at rest and with
        no joint torque, and return the first perception that shows them placed (after one
        limp 20 ms step, as the in-process backend's reset; it counts as the first settle
        cycle).

        Raises:
            ValueError: start angles other than 0, or ``z=None`` with a tilted ``quat``.
            BackendError: the placement did not show within ``reset_cycles`` cycles.
        """
        pose, ball_pos, ball_vel = start.pose, start.ball_pos, start.ball_vel
        angles = league_pose(self._model, pose.joint_angles_deg)
        if np.abs(angles).max(initial=0.0) > 1e-9:
            raise ValueError(
                "rcssservermj's placement sets every joint to 0, so episodes on the real server "
                "start there; other start angles need the in-process backend ('rcsssmj')"
            )
        quat = _model_quat(pose)
        if pose.z is None:
            if pose.quat is not None:
                raise ValueError("give z for a tilted start (quat) on the real server")
            z = self._model.standing_torso_height
        else:
            z = float(pose.z)
        ball = league_ball(self._model, ball_pos)
        bv = [float(v) for v in ball_vel]
        if not all(math.isfinite(v) for v in (pose.x, pose.y, z, *quat, *ball, *bv)):
            raise ValueError("the start pose, ball position and velocity must be finite")
        head = f"(agent (unum 1) (team {self.team}) (move3d {pose.x!r} {pose.y!r} "
        tail = " ".join(repr(float(q)) for q in quat) + "))"
        # first somewhere else (1 m higher), so that the perception that first shows the real
        # placement is the one made after exactly one limp step from it: the server applies a
        # monitor command after a step's physics, and its next perception still shows the
        # sensors from before the placement
        first = f"{head}{z + 1.0!r} {tail}"
        ball_cmd = f"(ball (pos {ball[0]!r} {ball[1]!r} {ball[2]!r}) "
        ball_cmd += f"(vel {bv[0]!r} {bv[1]!r} {bv[2]!r}))"
        second = f"{head}{z!r} {tail}{ball_cmd}"
        above, want = np.array([pose.x, pose.y, z + 1.0]), np.array([pose.x, pose.y, z])
        for _ in range(_RESET_ATTEMPTS):
            answered = _perception_cycle(self._show(first, above).time)
            expected = answered + int(self._delay_parities[1] > self._delay_parities[0])
            if self._frame_cycle(expected) != expected:
                # so that the placement shows in a cycle with a monitor frame
                answered = _perception_cycle(self._parse(self._send(self._limp)).time)
            p = self._show(second, want)
            shown = _perception_cycle(p.time)
            self._delay_parities[(shown - answered) % 2] += 1
            if self._frame_cycle(shown) == shown:
                break
            # the server took the command a cycle later (or sooner) than it mostly does, so
            # no frame shows the ball when the perception does: place both again
        else:
            p = self._parse(self._send(self._limp))  # one more limp step brings a frame
        return self._with_ground_truth(p, fresh=True), 1

    def hold_command(self) -> AgentCommand:
        """No command: the joints stay limp, as the reset left them."""
        return AgentCommand()

    def _show(self, monitor_text: str, want: np.ndarray) -> LeaguePerception:
        """Send a placement through the monitor; answer with limp joints until a perception
        shows the torso within :data:`_PLACE_TOLERANCE_M` of ``want``; return it (parsed)."""
        self._monitor_command(monitor_text)
        for _ in range(self.reset_cycles):
            p = self._parse(self._send(self._limp))
            if (
                p.raw_torso_pos is not None
                and np.abs(p.raw_torso_pos - want).max() < _PLACE_TOLERANCE_M
            ):
                return p
        raise BackendError(
            f"rcssservermj did not show the placement within {self.reset_cycles} cycles"
        )

    def step(self, command: AgentCommand) -> Perception:
        return self.advance(1, command)

    def advance(self, cycles: int, command: AgentCommand | None = None) -> Perception:
        if cycles < 1:
            raise ValueError(f"cycles must be >= 1, got {cycles}")
        commands = pd_commands(self._model, command)
        msg = self._send(commands)
        for _ in range(cycles - 1):
            msg = self._send({})
        return self._with_ground_truth(self._parse(msg), fresh=False, cycles=cycles)

    def _parse(self, msg: bytes) -> LeaguePerception:
        return parse_league_perception(msg, self._model.perceptor_names)

    def _with_ground_truth(
        self, p: LeaguePerception, *, fresh: bool, cycles: int = 1
    ) -> LeaguePerception:
        """``p`` with its ground truth: the torso from its own perceptors, the ball from the
        monitor (waiting for a frame of the same cycle or the one before)."""
        ball, ball_vel = self._ball_at(self._frame_cycle(_perception_cycle(p.time)))
        pos = p.raw_torso_pos if p.raw_torso_pos is not None else np.full(3, np.nan)
        vel = (
            np.zeros(3)
            if fresh or self._last_pos is None
            else (pos - self._last_pos) / (CYCLE_S * cycles)
        )
        self._last_pos = pos
        quat = p.raw_torso_quat if p.raw_torso_quat is not None else np.array([1.0, 0, 0, 0])
        p.ground_truth = GroundTruth(
            ball_pos=ball,
            ball_vel=np.zeros(3) if fresh else ball_vel,
            torso_pos=pos,
            torso_quat=to_simspark_torso_quat(quat),
            torso_vel=vel,
            torso_ang_vel=None,
        )
        return p

    # ------------------------------------------------------------------ misc
    def close(self) -> None:
        if self.link is not None:
            self.link.close()
            self.link = None
        if self.server is not None:
            self.server.close()  # (closes the monitor connection after the server ended)
            self.server = None
        elif self._monitor is not None:
            self._monitor.close()
        self._monitor = None

    def describe(self) -> dict[str, Any]:
        d = super().describe()
        d.update(robot=self.robot, engine="a real rcssservermj (rcsssmj)")
        return d

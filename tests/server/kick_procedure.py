"""The measurement procedure of the real server's scripted kick (``robocup_gym/data/kick_D.json``),
message for message, as an independent client runs it against any server that speaks
rcssserver3d's protocol.

The fixture's ``procedure``: connect a type-0 Nao (sync mode), ``beam -1 0 0``, 20 cycles of
zero joint velocities, attach a monitor; one trainer message with the ``move`` of
``robot_placement.trainer_cmd``, the ball parked far away and ``(playMode PlayOn)``; 25 zero
cycles; the ball placement; then the command sequence (every cycle all 22 hinge effectors, joints
not listed at 0 rad/s). The fixture's own strings are sent, byte for byte; only the parked ball's
position is not given by it (20, 10 is off the field, where no rule touches it).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from robocup_gym.protocol.monitor import MonitorState
from robocup_gym.robot.nao import nao_model
from robocup_gym.server.client import AgentClient, MonitorClient
from robocup_gym.sim.fidelity import load_data
from robocup_gym.sim.physics import CYCLE_S

FIXTURE = load_data("kick_D.json")
PARKED_BALL = "(ball (pos 20 10 0.042)(vel 0 0 0))"
_FRP = re.compile(r"\(FRP \(n ([lr]f)\)")
_ACC = re.compile(r"\(ACC \(n torso\) \(a ([^)]*)\)\)")


@dataclass
class KickRun:
    """What the client saw: per command-sequence cycle (1-based), the ball (from the monitor's
    scene, ``None`` before it shows) and which feet report a force perceptor."""

    balls: list[np.ndarray | None] = field(default_factory=list)
    feet: list[set[str]] = field(default_factory=list)
    times: list[float] = field(default_factory=list)
    """The game time each command-sequence cycle's percept reports, s."""
    accel_before: list[np.ndarray] = field(default_factory=list)
    """The accelerometer in the 24 cycles between the two trainer messages."""

    def ball_travel(self) -> float:
        """Ball displacement in the plane from its placement to the end, m."""
        start = np.array([-0.8, -0.055])
        return float(np.hypot(*(self.balls[-1][:2] - start)))

    def first_ball_movement(self) -> int | None:
        """The first cycle whose monitor ball is more than 2 mm from its placement, after the
        monitor showed it there (a placement shows 2–3 cycles after it was sent)."""
        start = np.array([-0.8, -0.055])
        placed = False
        for k, b in enumerate(self.balls, 1):
            if b is None:
                continue
            near = np.hypot(*(b[:2] - start)) <= 0.002
            if placed and not near:
                return k
            placed |= near
        return None


_GAME_TIME = re.compile(r"\(GS [^\n]*?\(t ([0-9.]+)\)")


def _drain(monitor: MonitorClient, state: MonitorState, balls: dict, wait: float = 0.002) -> None:
    """Read the monitor frames that have come (waiting up to ``wait`` s for each); ``balls``
    gets the ball each frame shows, by the frame's game time."""
    while True:
        try:
            state.update(monitor.recv(timeout=wait))
        except TimeoutError:
            return
        if state.has_scene and state.info.time is not None:
            ball = state.scene.ball_position()
            balls[round(state.info.time, 3)] = None if ball is None else np.asarray(ball, float)


def _shown_at(balls: dict, t: float) -> np.ndarray | None:
    """The ball of the newest frame of game time ``t`` or earlier (what a monitor shows then)."""
    times = [u for u in balls if u <= t + 1e-6]
    return balls[max(times)] if times else None


def run(host: str, agent_port: int, monitor_port: int, *, trainer_first: bool = True) -> KickRun:
    """The fixture's procedure against the server at ``host``. ``trainer_first``: each trainer
    message goes out after a percept arrived and before the agent answers it; otherwise after
    the agent's answer, while the server computes the next cycle (both orders are accepted by
    rcssserver3d and give its result)."""
    names = nao_model(0).effector_names
    out = KickRun()
    monitor: MonitorClient | None = None
    with AgentClient(host, agent_port, timeout=20.0) as agent:
        agent.handshake("Left", 1, 0)

        def command(velocities: dict[str, float]) -> str:
            return "".join(f"({n} {velocities.get(n, 0.0):.2f})" for n in names) + "(syn)"

        zero = command({})

        def cycle(message: str, trainer: str | None = None) -> str:
            if trainer is not None and trainer_first:
                monitor.send(trainer)  # type: ignore[union-attr]
            agent.send(message)
            if trainer is not None and not trainer_first:
                monitor.send(trainer)  # type: ignore[union-attr]
            return agent.recv()

        cycle("(beam -1 0 0)" + zero)
        for _ in range(20):
            cycle(zero)
        monitor = MonitorClient(host, monitor_port, timeout=20.0)
        state = MonitorState()
        balls: dict[float, np.ndarray | None] = {}
        placement = FIXTURE["robot_placement"]["trainer_cmd"] + PARKED_BALL + "(playMode PlayOn)"
        cycle(zero, placement)
        for _ in range(24):
            percept = cycle(zero)
            out.accel_before.append(np.array(_ACC.search(percept).group(1).split(), float))
            _drain(monitor, state, balls)
        first = True
        times = out.times
        for segment in FIXTURE["command_sequence"]:
            message = command(segment["velocities_rad_per_s"])
            for _ in range(segment["cycles"]):
                trainer = FIXTURE["ball_placement_cmd"] if first else None
                first = False
                percept = cycle(message, trainer)
                _drain(monitor, state, balls)
                times.append(float(_GAME_TIME.search(percept).group(1)))
                out.feet.append(set(_FRP.findall(percept)))
        _drain(monitor, state, balls, wait=0.5)  # the frames still on their way
        monitor.close()
    # each cycle's ball from the frames by their game time, not by when they were read (a
    # frame read a cycle late on a busy machine would otherwise move the kick by a cycle); a
    # frame of a cycle carries the game time a cycle on from its percept's (on both servers)
    out.balls = [_shown_at(balls, t + CYCLE_S) for t in times]
    return out

"""Drive a robot on an rcssserver3d-protocol server with an exported ONNX policy.

This is the path from training to a team's agent: the agent connects like any other
(``scene``/``init`` on the agent port), and every cycle reads the percept, builds the observation
exactly as the training environment does, asks the ONNX policy for an action and sends the joint
velocities back. It works against ``robocup-gym serve`` and a real rcssserver3d alike.

How it reuses the environment: the task environment is built (from the metadata stored in the
ONNX file) around :class:`AgentConnectionBackend`, a :class:`~robocup_gym.backends.Backend` whose
``step`` sends one command over the socket and returns the parsed percept. Observation layout,
normalisation, clipping, frame stacking and action scaling are therefore the environment's own.

Ground truth. The kick tasks observe the ball relative to the robot from the simulator's ground
truth (the paper used the server's ``mypos``/``myorien``/``ballpos`` "cheat" extension). Over the
wire this backend rebuilds it from those ``See`` extensions: torso position = head position minus
the upright head offset, orientation = the head's heading (upright), ball velocity from successive
``See`` messages. Start the server with ground truth on (``robocup-gym serve --ground-truth``, or
FC Portugal's patched rcssserver3d). Without it only policies whose observations need no ground
truth can run.

Episodes. With a monitor port (trainer commands) every episode starts like in training: the robot
is moved to the start position, the joints are driven to the start pose, and the ball is put at
its start position with play mode ``PlayOn``. Without one the robot only beams (honoured before
kick-off) and drives its joints to the start pose, and the ball stays where it is.
"""

from __future__ import annotations

import contextlib
import math
import socket
from dataclasses import dataclass
from typing import Any

import numpy as np

from robocup_gym.backends.base import Backend, EpisodeSetup
from robocup_gym.protocol import trainer as trainer_cmds
from robocup_gym.protocol.effectors import format_command, format_init, format_scene
from robocup_gym.protocol.framing import (
    FrameDecoder,
    connect,
    decode_payload,
    recv_frame,
    send_frame,
)
from robocup_gym.protocol.perceptors import parse_perception
from robocup_gym.robot.nao import NaoModel, nao_model
from robocup_gym.sim.pose import heading_to_quat
from robocup_gym.types import AgentCommand, GroundTruth, Perception


class _Geometry:
    """Heights of an upright robot, from the embedded model (computed once per pose)."""

    def __init__(self, robot_type: int) -> None:
        from robocup_gym.sim.engines.mujoco.world import World

        self.world = World(robot_types=[robot_type])
        self._cache: dict[tuple[float, ...], tuple[float, float]] = {}

    def heights(self, angles_deg: np.ndarray) -> tuple[float, float]:
        """(head centre above torso centre, torso centre above ground) in the given pose, m."""
        key = tuple(np.round(np.asarray(angles_deg, dtype=float), 3))
        if key not in self._cache:
            import mujoco

            w = self.world
            r = w.robot(0)
            w.place_robot(0, x=0.0, y=0.0, joint_angles_deg=np.asarray(angles_deg, dtype=float))
            mujoco.mj_forward(w.model, w.data)
            torso_z = float(w.data.xpos[r.torso_body][2])
            self._cache[key] = (float(w.data.xpos[r.head_body][2]) - torso_z, torso_z)
        return self._cache[key]


class GroundTruthUnavailableError(RuntimeError):
    """The server sends no ``mypos``/``ballpos`` extension, which the policy's observation needs."""


class AgentConnectionBackend(Backend):
    """One robot connected to an rcssserver3d-protocol server as an ordinary agent.

    Args:
        host, port: The server's agent port.
        robot_type: Nao type 0–4 to load (``scene``).
        team, unum: ``init`` team name and uniform number (0 = server's choice).
        monitor_port: The server's monitor/trainer port for resetting episodes (``None`` = no
            trainer commands).
        sync: Append ``(syn)`` to every message (needed by servers in sync mode, harmless else).
        timeout: Seconds to wait for a percept.
        drive_cycles: Most cycles spent driving the joints to an episode's start pose.
    """

    name = "agent-connection"

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 3100,
        *,
        robot_type: int = 0,
        team: str = "RoboCupGym",
        unum: int = 0,
        monitor_port: int | None = None,
        sync: bool = True,
        timeout: float = 10.0,
        drive_cycles: int = 60,
        reset_cycles: int = 4,
        seed: int | None = None,
        vision: bool = False,
        **_: Any,
    ) -> None:
        super().__init__(robot_type=robot_type, seed=seed, vision=vision)
        self.host, self.port = host, int(port)
        self.team = team
        self.sync = sync
        self.timeout = timeout
        self.drive_cycles = int(drive_cycles)
        self.reset_cycles = int(reset_cycles)
        self._model = nao_model(self.robot_type)
        self._geometry = _Geometry(self.robot_type)
        self._head_dz = self._geometry.heights(np.zeros(len(self._model.joints)))[0]
        self._gt: GroundTruth | None = None
        self._last_seen: tuple[float, np.ndarray] | None = None
        self.side: str | None = None
        self.unum = unum
        self.cycles = 0
        self.sock = self._connect(host, self.port)
        self.decoder = FrameDecoder()
        self.monitor: socket.socket | None = None
        if monitor_port is not None:
            self.monitor = self._connect(host, int(monitor_port))
        self._send(format_scene(self.robot_type))
        self._recv()
        self._send(format_init(unum, team))
        self._recv()
        if self.unum == 0:  # the server announces the number it chose in a GS soon after
            for _ in range(5):
                self._send(format_command(AgentCommand(), self.robot_type, sync=False))
                self._recv()
                if self.unum:
                    break

    # ------------------------------------------------------------------ wire
    @staticmethod
    def _connect(host: str, port: int, retries_s: float = 5.0) -> socket.socket:
        try:
            return connect(host, port, retry_s=retries_s)
        except ConnectionRefusedError:
            raise ConnectionRefusedError(
                f"no server at {host}:{port} (start one with `robocup-gym serve`)"
            ) from None

    def _send(self, text: str) -> None:
        if self.sync and not text.endswith("(syn)"):
            text += "(syn)"
        send_frame(self.sock, text, self.timeout)

    def _recv(self) -> Perception:
        text = decode_payload(recv_frame(self.sock, self.decoder, self.timeout))
        p = parse_perception(text, robot_type=self.robot_type)
        if p.game.team_side is not None:
            self.side = p.game.team_side
        if p.game.unum is not None:
            self.unum = p.game.unum
        self.cycles += 1
        self._update_ground_truth(p)
        gt = self._gt
        if gt is not None:  # fresh arrays every cycle (callers may keep them)
            gt = GroundTruth(
                gt.ball_pos.copy(), gt.ball_vel.copy(), gt.torso_pos.copy(), gt.torso_quat.copy()
            )
        p.ground_truth = gt
        self.last = p
        return p

    def _torso_height(self, angles_deg: np.ndarray) -> float:
        return self._geometry.heights(angles_deg)[1] + 0.005

    def _trainer(self, *commands: str) -> None:
        if self.monitor is not None:
            send_frame(self.monitor, "".join(commands), self.timeout)

    # ------------------------------------------------------------------ ground truth
    def _update_ground_truth(self, p: Perception) -> None:
        v = p.vision
        if v is None or v.my_pos is None or v.ball_pos is None:
            return
        ball = np.asarray(v.ball_pos, dtype=float)
        head = np.asarray(v.my_pos, dtype=float)
        heading = float(v.my_orientation_deg or 0.0)
        ball_vel = np.zeros(3)
        if self._last_seen is not None and p.time > self._last_seen[0]:
            ball_vel = (ball - self._last_seen[1]) / (p.time - self._last_seen[0])
        self._last_seen = (p.time, ball)
        self._gt = GroundTruth(
            ball_pos=ball,
            ball_vel=ball_vel,
            torso_pos=head - np.array([0.0, 0.0, self._head_dz]),
            torso_quat=heading_to_quat(heading),
        )

    def _need_ground_truth(self, cycles: int = 12) -> None:
        for _ in range(cycles):
            if self._gt is not None:
                return
            self._send(format_command(AgentCommand(), self.robot_type, sync=False))
            self._recv()
        raise GroundTruthUnavailableError(
            "the server sends no mypos/ballpos in See, which this policy's observation needs; "
            "start it with ground truth on (robocup-gym serve --ground-truth)"
        )

    # ------------------------------------------------------------------ Backend API
    @property
    def robot_model(self) -> NaoModel:
        return self._model

    @property
    def has_ground_truth(self) -> bool:
        return True

    @property
    def places_any_orientation(self) -> bool:
        return False  # an agent alone can only beam itself upright

    def _world_xy(self, x: float, y: float) -> tuple[float, float]:
        """Team frame → world frame (the right team plays mirrored)."""
        return (-x, -y) if self.side == "right" else (x, y)

    def _place(self, start: EpisodeSetup) -> tuple[Perception, int]:
        pose, ball_pos, ball_vel, play_mode = (
            start.pose,
            start.ball_pos,
            start.ball_vel,
            start.play_mode,
        )
        team = "Left" if self.side != "right" else "Right"
        # 1. drive the joints to the start pose, wherever the robot is
        target = np.zeros(len(self._model.joints))
        if pose.joint_angles_deg is not None and not isinstance(pose.joint_angles_deg, dict):
            target = np.asarray(pose.joint_angles_deg, dtype=float)
        speeds = np.asarray(self._model.max_speeds, dtype=float)
        p = self.last
        for _ in range(self.drive_cycles):
            err = np.radians(target - np.asarray(p.joint_angles_deg, dtype=float))
            if np.max(np.abs(err)) < math.radians(1.0):
                break
            vel = np.clip(12.5 * err, -speeds, speeds)
            self._send(format_command(AgentCommand(vel), self.robot_type, sync=False))
            p = self._recv()
        stop = AgentCommand(np.zeros_like(target))
        # 2. put the robot (upright) and the ball at their start positions
        wx, wy = self._world_xy(pose.x, pose.y)
        world_heading = pose.heading_deg + (180.0 if self.side == "right" else 0.0)
        if self.monitor is not None:
            bx, by = self._world_xy(float(ball_pos[0]), float(ball_pos[1]))
            bvx, bvy = self._world_xy(float(ball_vel[0]), float(ball_vel[1]))
            bz = float(ball_pos[2]) if len(ball_pos) > 2 else 0.042
            z = float(pose.z) if pose.z is not None else self._torso_height(target)
            self._trainer(
                trainer_cmds.agent_move(self.unum, team, (wx, wy, z), world_heading - 90.0),
                trainer_cmds.ball((bx, by, bz), (bvx, bvy, float(ball_vel[2]))),
                trainer_cmds.play_mode(play_mode),
            )
        else:
            stop = AgentCommand(np.zeros_like(target), beam=(pose.x, pose.y, pose.heading_deg))
        # 3. let the commands take effect and wait for a fresh See with ground truth
        self._send(format_command(stop, self.robot_type, sync=False))
        self._recv()
        for _ in range(self.reset_cycles):
            self._send(format_command(AgentCommand(), self.robot_type, sync=False))
            self._recv()
        self._gt = None
        self._last_seen = None
        self._need_ground_truth()
        return self.last, 0

    def step(self, command: AgentCommand) -> Perception:
        self._send(format_command(command, self.robot_type, sync=False))
        return self._recv()

    def close(self) -> None:
        for s in (self.sock, self.monitor):
            if s is not None:
                with contextlib.suppress(OSError):
                    s.close()
        self.monitor = None

    def describe(self) -> dict[str, Any]:
        return {**super().describe(), "host": self.host, "port": self.port}


@dataclass
class EpisodeReport:
    steps: int
    ball_displacement: list[float] | None
    fallen: bool
    torso_displacement: list[float] | None = None
    """How far the torso moved over the episode (x, y, z in the field frame, m), where the
    environment knows it."""
    success: bool | None = None
    """Whether the episode ended in the task's success (GetUp: up and held 1 s), for tasks that
    report one (``info["success"]``); ``None`` for the others."""
    steps_to_up: int | None = None
    """GetUp: the step at which the robot got up for good (``info["steps_to_up"]``)."""


def run_onnx_agent(
    onnx_path: str,
    *,
    host: str = "127.0.0.1",
    port: int = 3100,
    monitor_port: int | None = None,
    episodes: int = 1,
    team: str = "RoboCupGym",
    unum: int = 0,
    sync: bool = True,
    monitor_interval: int = 2,
    seed: int = 100_000,
    on_episode=None,
    env_overrides: dict[str, Any] | None = None,
    reset_options: dict[str, Any] | None = None,
) -> list[EpisodeReport]:
    """Connect to a server and run ``episodes`` episodes of the exported policy.

    The task, its configuration and the robot type come from the ONNX file's metadata;
    ``env_overrides`` replace some of those options (they may not change the observation), and
    every episode is reset with ``reset_options`` (a Walk's ``{"velocity_command": (forward
    m/s, left m/s, turn deg/s)}``, say).

    With a ``monitor_port`` the robot runs on
    :class:`~robocup_gym.backends.rcssserver3d_backend.Rcssserver3dBackend` in connect mode:
    ground truth (torso pose, ball) comes from the monitor stream, the episode starts the way
    that backend starts it (joints driven while held above the ground, then robot and ball
    placed), and the observation is the one ``robocup-gym eval --backend rcssserver3d`` and the
    in-process environment build, so the same policy does the same thing on all three paths
    (docs/training.md gives the measured agreement). ``monitor_interval`` is the server's
    cycles per monitor frame (2 for rcssserver3d's default and ``robocup-gym serve``).

    Without one, :class:`AgentConnectionBackend` rebuilds ground truth from the ``See``
    extensions (``mypos``/``ballpos``, every third cycle, torso upright): enough to run a
    policy on a server the agent cannot reset, but the policy then sees a staler ball and no
    tilt, and kicks differently.

    Episode ``k`` is reset with seed ``seed + k`` (as ``robocup-gym eval``).
    """
    from robocup_gym.train.onnx_policy import OnnxPolicy
    from robocup_gym.train.pretrained import pretrained_env, recorded_env_options

    if int(episodes) < 1:
        raise ValueError(f"episodes must be >= 1, got {episodes}")
    for what, p in (("port", port), ("monitor port", monitor_port)):
        if p is not None and not 1 <= int(p) <= 65535:
            raise ValueError(f"{what} {p} is not a port number (1-65535)")
    policy = OnnxPolicy(onnx_path)
    meta = policy.metadata
    env_kwargs = {**recorded_env_options(meta), **(env_overrides or {})}
    robot_type = int(env_kwargs.get("robot_type", 0))
    backend: Backend
    if monitor_port is not None:
        from robocup_gym.backends.rcssserver3d_backend import Rcssserver3dBackend

        backend = Rcssserver3dBackend(
            robot_type=robot_type,
            host=host,
            agent_port=port,
            monitor_port=monitor_port,
            monitor_interval=monitor_interval,
            team=team,
            unum=unum,
        )
    else:
        backend = AgentConnectionBackend(
            host, port, robot_type=robot_type, team=team, unum=unum, sync=sync
        )
    reports = []
    try:
        env = pretrained_env(policy, backend, env_overrides)
        try:
            for k in range(episodes):
                obs, _ = env.reset(seed=seed + k, options=dict(reset_options or {}))
                start = _torso_position(env)
                done, steps, info = False, 0, {}
                while not done:
                    obs, _, terminated, truncated, info = env.step(policy(obs))
                    steps += 1
                    done = terminated or truncated
                disp = info.get("ball_displacement")
                end = _torso_position(env)
                rep = EpisodeReport(
                    steps=steps,
                    ball_displacement=None if disp is None else [float(x) for x in disp],
                    fallen=bool(info.get("fallen", False)),
                    torso_displacement=(
                        None if start is None or end is None else [float(x) for x in end - start]
                    ),
                    success=None if "success" not in info else bool(info["success"]),
                    steps_to_up=(
                        None if info.get("steps_to_up") is None else int(info["steps_to_up"])
                    ),
                )
                reports.append(rep)
                if on_episode is not None:
                    on_episode(rep)
        finally:
            env.close()
    finally:
        backend.close()
    return reports


def _torso_position(env) -> np.ndarray | None:
    """The torso's position now (m), if the environment's ground truth has it."""
    gt = getattr(env.unwrapped, "ground_truth", None)
    pos = None if gt is None else gt.torso_pos
    return None if pos is None else np.array(pos, dtype=float)

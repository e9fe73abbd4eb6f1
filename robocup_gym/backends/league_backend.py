"""RCSSServerMJ's world in-process as a backend: the league's robots (Booster T1, K1) for the
environments, ``backend="rcsssmj"`` (chosen by ``robot="T1"``).

It drives :class:`~robocup_gym.sim.engines.rcsssmj.LeagueWorld`, which steps ``rcsssmj``'s own
simulation exactly as ``rcssservermj`` does, so every perception holds the numbers of the server's
message (read from ``rcsssmj``'s perception objects: the same as parsing the message with
:func:`~robocup_gym.protocol.league.parse_league_perception`, without the text) and every
command acts as it would there. Commands are :class:`~robocup_gym.types.PDCommand` per joint
(:attr:`AgentCommand.joint_pd`). A command answers the last perception; as on the server, the
world meanwhile steps once more with the commands it had, so a command acts from the step after
(one cycle of dead time, as on rcssserver3d).

Episode starts use what the server's monitor commands do (``(agent … (move3d …))`` places the
torso, zeroes the joints and every velocity; ``(ball (pos …) (vel …))``), plus joint angles set
directly; the robot is put with its lowest point on the ground (MuJoCo's own geometry distance),
without joint torque, and the world runs one 20 ms step before the first perception, as the
real-server backend's reset does (``"rcssservermj"``, which can only start from 0 angles).
The play mode is the league referee's: its monitor protocol cannot set one, so the world stays in
``BeforeKickOff``, where its rules leave the robot and the ball free (no clock, no fouls).

Ground truth is the world's exact state, in the library's frames (the torso's orientation in
SimSpark's torso axes, x right, y forward: see :mod:`robocup_gym.protocol.league`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from robocup_gym.backends.base import Backend, BackendDivergedError, EpisodeSetup, RobotPose
from robocup_gym.protocol.league import (
    from_simspark_torso_quat,
    league_perception,
    to_simspark_torso_quat,
)
from robocup_gym.types import (
    AgentCommand,
    GameState,
    GroundTruth,
    PDCommand,
    Perception,
    SeenPlayer,
    Vision,
)

__all__ = [
    "LeagueBackend",
    "league_ball",
    "league_pose",
    "pd_commands",
    "perception_from_objects",
]


def _model_quat(pose: RobotPose) -> tuple[float, float, float, float]:
    """The torso orientation in the league model's axes (x forward, y left) for ``pose``."""
    if pose.quat is not None:
        q = from_simspark_torso_quat(pose.quat)
        q /= np.linalg.norm(q)
        return (float(q[0]), float(q[1]), float(q[2]), float(q[3]))
    h = math.radians(pose.heading_deg) / 2.0
    return (math.cos(h), 0.0, 0.0, math.sin(h))


def league_pose(robot: Any, angles: np.ndarray | Mapping[str, float] | None) -> np.ndarray:
    """Joint angles in degrees, model order, from an array or a name → degrees mapping
    (effector, perceptor or model names; others 0).

    Raises:
        ValueError: a wrong length or an unknown name (naming the robot's joints).
    """
    n = len(robot.joints)
    if angles is None:
        return np.zeros(n)
    if isinstance(angles, Mapping):
        out = np.zeros(n)
        for name, v in angles.items():
            i = robot.joint_index.get(name)
            if i is None:
                raise ValueError(
                    f"{robot.name} has no joint {name!r}; its joints: "
                    f"{', '.join(robot.effector_names)}"
                )
            out[i] = float(v)
        return out
    out = np.asarray(angles, dtype=float)
    if out.shape != (n,):
        raise ValueError(f"{robot.name} joint angles must have shape ({n},), got {out.shape}")
    return out


def pd_commands(robot: Any, command: AgentCommand | None) -> dict[str, PDCommand]:
    """The checked PD commands of ``command`` for the league robot ``robot`` (``{}`` for none).

    Raises:
        ValueError: joint velocities (the Nao's form), or a command
            :meth:`~robocup_gym.robot.league.LeagueRobot.check_commands` refuses.
    """
    if command is None:
        return {}
    if len(command.joint_velocities):
        raise ValueError(
            f"the {robot.name} takes PD joint commands (AgentCommand.joint_pd), not joint "
            "velocities"
        )
    commands = dict(command.joint_pd or {})
    robot.check_commands(commands)
    return commands


def perception_from_objects(objects: Sequence[Any], joint_order: Sequence[str]) -> Perception:
    """The :class:`Perception` that :func:`~robocup_gym.protocol.league.parse_league_perception`
    makes of the message ``rcsssmj`` encodes from its perception objects ``objects`` (one
    agent's ``perceptions`` after ``generate_perceptions``), made from the objects directly: the
    values are the same numbers (the server truncates them before writing them out, and writes
    them so that they read back exactly), without writing and parsing text
    (``tests/envs/test_league_envs.py`` checks the two agree).

    Raises:
        ValueError: the objects lack a joint of ``joint_order``, or the gyro or accelerometer.
    """
    time = 0.0
    game = GameState()
    gyro = accel = pos = quat = None
    joints: dict[str, tuple[float, float]] = {}
    touch: dict[str, bool] = {}
    vision = None
    for o in objects:
        kind = type(o).__name__
        if kind == "TimePerception":
            time = float(o.time)
        elif kind == "GameStatePerception":
            game = _game_state(o)
        elif kind == "GyroPerception":
            gyro = (float(o.rx), float(o.ry), float(o.rz))
        elif kind == "AccelerometerPerception":
            accel = (float(o.ax), float(o.ay), float(o.az))
        elif kind == "PositionPerception":
            pos = np.array([o.x, o.y, o.z], dtype=float)
        elif kind == "OrientationPerception":
            quat = np.array([o.qw, o.qx, o.qy, o.qz], dtype=float)
        elif kind == "JointStatePerception":
            for n, ax, vx in zip(o.joint_names, o.joint_axs, o.joint_vxs, strict=False):
                joints[str(n)] = (float(ax), float(vx))
        elif kind == "TouchPerception":
            touch[str(o.name)] = bool(int(o.active))
        elif kind == "VisionPerception":
            vision = Vision()
            for d in o.obj_detections:
                if hasattr(d, "body_detections"):
                    player = SeenPlayer(team=str(d.team_name), unum=int(d.player_no))
                    for b in d.body_detections:
                        player.parts[str(b.name)] = np.array(
                            [b.distance, b.azimuth, b.inclination], dtype=float
                        )
                    vision.players.append(player)
                else:
                    vision.objects[str(d.name)] = np.array(
                        [d.distance, d.azimuth, d.inclination], dtype=float
                    )
    if gyro is None or accel is None:
        raise ValueError("the perception objects have no gyro and accelerometer")
    missing = [n for n in joint_order if n not in joints]
    if missing:
        raise ValueError(f"the perception objects have no joint state for {', '.join(missing)}")
    values = np.array([joints[n] for n in joint_order], dtype=float).reshape(-1, 2)
    return league_perception(
        time=time,
        game=game,
        gyro=gyro,
        accel=accel,
        joint_names=joint_order,
        q_deg=values[:, 0].copy(),
        dq_deg_s=values[:, 1].copy(),
        pos=pos,
        quat=quat,
        vision=vision,
        touch=touch,
    )


def _game_state(gs: Any) -> GameState:
    """``rcsssmj``'s ``GameStatePerception`` as a :class:`GameState`."""
    return GameState(
        play_mode=str(gs.play_mode),
        game_time=float(gs.play_time),
        score_left=int(gs.score_left),
        score_right=int(gs.score_right),
    )


def league_ball(robot: Any, ball_pos: Sequence[float]) -> list[float]:
    """The ball's centre (m) from ``(x, y, z)``, or ``(x, y)``: resting on the ground (the
    league ball's radius up)."""
    ball = [float(v) for v in ball_pos]
    if len(ball) == 2:
        ball.append(robot.ball_radius)
    return ball


class _SceneView:
    """What :class:`~robocup_gym.sim.render.FollowCamera` reads of a world, for the league's."""

    def __init__(self, world: Any) -> None:
        self.model, self.data, self._world = world.sim.mj_model, world.sim.mj_data, world

    def torso_position(self, index: int) -> np.ndarray:
        return self._world.torso_pose(index)[0]


class LeagueBackend(Backend):
    """One league robot and the ball in RCSSServerMJ's world, stepped in-process and exactly.

    Args:
        robot: The robot model (``"T1"``, ``"K1"``, … as the installed ``rcsssmj`` ships).
        seed: Unused (the league's perceptions have no noise); accepted for the common interface.
        vision: Make the ``See`` perceptor (every second cycle, as the server); ``False`` skips
            it, the most expensive perceptor, when no observation reads it.
        team: The team name the robot joins with.
        robot_type: Must be 0 (the Nao's types do not apply); accepted for the common interface.

    Raises:
        robocup_gym.robot.league.RcsssmjUnavailableError: ``rcsssmj`` is not installed.
        ValueError: an unknown robot (naming those there are).
    """

    name = "rcsssmj"

    def __init__(
        self,
        *,
        robot: str = "T1",
        seed: int | None = None,
        vision: bool = False,
        team: str = "RobocupGym",
        robot_type: int = 0,
    ) -> None:
        super().__init__(robot_type=robot_type, seed=seed, vision=vision)
        from robocup_gym.robot.league import league_robot
        from robocup_gym.sim.engines.rcsssmj import LeagueWorld

        self.robot = str(robot)
        self._model = league_robot(self.robot)
        self.world = LeagueWorld([(self.robot, str(team), 1)])
        self._perceptors = self._model.perceptor_names
        self._camera = None
        model = self.world.sim.mj_model
        prefix = self.world.agents[0].agent_id.prefix
        self._feet = tuple(model.body(prefix + b).id if b else -1 for b in self._model.foot_bodies)

    @property
    def robot_model(self) -> Any:
        """The :class:`~robocup_gym.robot.league.LeagueRobot`."""
        return self._model

    # ------------------------------------------------------------------ episode control
    def _place(self, start: EpisodeSetup) -> tuple[Perception, int]:
        """Place the robot (joint angles included) and the ball, at rest, with no joint torque
        until the first command, and run one such limp 20 ms step (as a reset on the real
        server does; it counts as the first settle cycle); ``play_mode`` is not settable on
        RCSSServerMJ (see the module docstring) and ``seed`` has nothing to seed."""
        pose, ball_pos, ball_vel = start.pose, start.ball_pos, start.ball_vel
        w = self.world
        angles = np.radians(league_pose(self._model, pose.joint_angles_deg))
        quat = _model_quat(pose)
        if pose.z is None:
            w.place_player(0, (pose.x, pose.y, 2.0), quat, angles)
            z = 2.0 - w.lowest_point_above_ground(0)
        else:
            z = float(pose.z)
        w.place_player(0, (pose.x, pose.y, z), quat, angles)
        w.place_ball(league_ball(self._model, ball_pos), ball_vel)
        # one limp 20 ms step, as on the real server (whose placement shows in its perceptions
        # only a step later): the episode starts from what the robot then perceives
        self.advance(1)
        return self._perceive(), 1

    def hold_command(self) -> AgentCommand:
        """No command: the joints stay limp, as the reset left them."""
        return AgentCommand()

    def step(self, command: AgentCommand) -> Perception:
        return self.advance(1, command)

    def advance(self, cycles: int, command: AgentCommand | None = None) -> Perception:
        """``cycles`` cycles, perceiving only after the last one. ``command`` answers the
        current perception, and so acts from the step after the next one, exactly as on
        ``rcssservermj``: the server steps on with the commands it already has while the agent
        thinks (one cycle of dead time, as on rcssserver3d); commands are sticky."""
        if cycles < 1:
            raise ValueError(f"cycles must be >= 1, got {cycles}")
        w = self.world
        pd = pd_commands(self._model, command)
        from robocup_gym.sim.engines.rcsssmj import LeagueSimulationError

        try:
            w.step()  # with the commands that answered the last perception
            if pd:
                w.command(0, pd)
            for _ in range(cycles - 1):
                w.step()
        except LeagueSimulationError as e:
            raise BackendDivergedError(str(e)) from e
        return self._perceive()

    def _perceive(self) -> Perception:
        w = self.world
        if self.vision:
            w.sim.generate_perceptions()
            p = perception_from_objects(w.agents[0].perceptions, self._perceptors)
        else:  # the same numbers, straight from the sensor arrays
            r = w.readings(0)
            p = league_perception(
                time=r["time"],
                game=_game_state(r["game"]),
                gyro=r["gyro"],
                accel=r["accel"],
                joint_names=self._perceptors,
                q_deg=r["q_deg"],
                dq_deg_s=r["dq_deg_s"],
                pos=r["pos"],
                quat=r["quat"],
            )
        pos, quat = w.torso_pose(0)
        vel, ang = w.torso_velocity(0)
        ball = w.ball_position()
        if not (np.isfinite(pos).all() and np.isfinite(ball).all() and np.isfinite(quat).all()):
            raise BackendDivergedError(
                f"the league world produced a NaN/inf state at t = {w.time:.2f} s"
            )
        p.ground_truth = GroundTruth(
            ball_pos=ball,
            ball_vel=w.ball_velocity(),
            torso_pos=pos,
            torso_quat=to_simspark_torso_quat(quat),
            torso_vel=vel,
            torso_ang_vel=ang,
            feet_contact=self._feet_contact(),
        )
        return p

    def _feet_contact(self) -> dict[str, bool]:
        """Which feet touch the ground (a contact between a foot body and the world body)."""
        model, data = self.world.sim.mj_model, self.world.sim.mj_data
        left, right = self._feet
        touching = {"lf": False, "rf": False}
        body = model.geom_bodyid
        for k in range(data.ncon):
            c = data.contact[k]
            b1, b2 = int(body[c.geom1]), int(body[c.geom2])
            if b1 == 0 or b2 == 0:
                other = b2 if b1 == 0 else b1
                if other == left:
                    touching["lf"] = True
                elif other == right:
                    touching["rf"] = True
        return touching

    # ------------------------------------------------------------------ misc
    def set_torso_force(self, force: Sequence[float]) -> None:
        self.world.set_torso_force(0, force)

    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """RGB image of the scene from a camera that follows the robot, drawn by MuJoCo from
        the league world's own model (needs an OpenGL context, e.g. ``MUJOCO_GL=egl``)."""
        from robocup_gym.sim.render import FollowCamera

        if self._camera is None:
            self._camera = FollowCamera(distance=3.0)
        return self._camera.render(_SceneView(self.world), width, height)

    def close(self) -> None:
        if self._camera is not None:
            self._camera.close()
            self._camera = None

    def describe(self) -> dict[str, Any]:
        d = super().describe()
        d.update(robot=self.robot, engine="rcsssmj (RCSSServerMJ's own simulation, MuJoCo)")
        return d

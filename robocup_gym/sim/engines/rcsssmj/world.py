"""RCSSServerMJ's world, in-process and exact: ``rcsssmj``'s own soccer simulation, driven
cycle by cycle as its server drives it.

``rcssservermj`` (``python -m rcsssmj``) runs one loop per 20 ms cycle (four 5 ms MuJoCo steps):
it makes every agent's perceptions of the current state, takes each agent's joint commands (in
sync mode it waits for them: the answer to the perceptions of the cycle before), sends the new
perceptions, and steps the simulation with those commands. :meth:`LeagueWorld.cycle` is one
such pass, with the same simulation classes, the same model files and the same order, so an agent
sees the same perception bytes from it as from the server (``tests/sim/test_league_world.py``
checks this against a real ``rcssservermj`` process; ``benchmarks/rcssservermj_match.py``
prints the differences). Driving ``rcsssmj``'s own classes was chosen over a re-written step on
the same model: exact by construction, and nothing to drift when ``rcsssmj`` changes.

A joint command is ``(name, q, dq, kp, kd, tau)`` with ``q`` in degrees, ``dq`` in degrees per
second, ``kp``/``kd`` the PD gains and ``tau`` a feed-forward torque in N·m, as on the wire: the
simulation applies ``kp (q - q_now) + kd (dq - dq_now) + tau`` clamped to the actuator's torque
range, and keeps a joint's last command until a new one comes.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from robocup_gym.robot.league import RcsssmjUnavailableError, clearance, league_robot
from robocup_gym.sim.engines.rcsssmj.join import zero_filled_allocations
from robocup_gym.sim.physics import CYCLE_S, finite_force
from robocup_gym.types import PDCommand

__all__ = ["CYCLE_S", "LeagueSimulationError", "LeagueWorld", "PDCommand"]


class LeagueSimulationError(RuntimeError):
    """``rcsssmj``'s simulation failed in a step (the state is left as it was then: place the
    robots and the ball again before going on)."""


@dataclass(frozen=True)
class _Player:
    model: str
    team: str
    number: int

    # rcsssmj's agent parameter protocol (PAgentParameter)
    @property
    def model_name(self) -> str:
        return self.model

    @property
    def team_name(self) -> str:
        return self.team

    @property
    def player_no(self) -> int:
        return self.number


class LeagueWorld:
    """RCSSServerMJ's soccer world with the given players, stepped in-process.

    Args:
        players: ``(robot model, team name, player number)`` per player, e.g.
            ``[("T1", "A", 1)]``; they join in this order (the first team named is the left one),
            as agents whose ``init`` reached the server in that order.
        idle_cycles: Cycles the server ran before the players joined (≥ 1: ``rcsssmj``'s audio
            engine needs one step before a player can join; a real server runs many while the
            agents connect, and the number shows in the first perception's time: match it to
            compare, see :meth:`idle_cycles_before`).

    Raises:
        RcsssmjUnavailableError: ``rcsssmj`` is not installed.
        ValueError: an unknown robot, or a player the rules refuse (number, team size).
    """

    def __init__(self, players: Sequence[tuple[str, str, int]], *, idle_cycles: int = 1) -> None:
        if int(idle_cycles) < 1:
            raise ValueError(f"idle_cycles must be >= 1, got {idle_cycles}")
        try:
            from rcsssmj.games.soccer.game_phase import GamePhase
            from rcsssmj.games.soccer.sim.soccer_referee import SoccerReferee
            from rcsssmj.games.soccer.sim.soccer_sim import SoccerSimulation
            from rcsssmj.games.soccer.soccer_fields import create_soccer_field
            from rcsssmj.games.soccer.soccer_rules import SoccerRuleBooks, create_soccer_rule_book
            from rcsssmj.server.perception_encoder import DefaultPerceptionEncoder
        except ImportError as exc:
            raise RcsssmjUnavailableError(
                f"the league's simulator needs the rcsssmj package ({exc}); install it with: "
                "pip install 'robocup-gym[mj]'"
            ) from exc
        self._encoder = DefaultPerceptionEncoder()
        self.robots = [league_robot(str(model)) for model, _, _ in players]
        # as rcssservermj's command line builds it with its defaults
        rules = create_soccer_rule_book(SoccerRuleBooks.SSIM.value)
        field = create_soccer_field(rules.default_field_version.value)
        self.sim = SoccerSimulation(
            field=field,
            rules=rules,
            referee=SoccerReferee(),
            initial_game_phase=GamePhase.from_value(0),
            initial_play_time=None,
        )
        if not self.sim.init():
            raise RuntimeError("rcsssmj could not create the soccer world")
        for _ in range(int(idle_cycles)):
            self.sim.generate_perceptions()
            self.sim.step([])
        params = [_Player(str(m), str(t), int(n)) for m, t, n in players]
        # rcsssmj recompiles the model when players join, and MuJoCo's recompile gives the new
        # actuators controls read partly from uninitialised memory (see .join): zero-filled here,
        # as on a server started by RcssServerMJProcess, the join is the same in every process.
        with zero_filled_allocations() as zero_filled:
            self.agents = self.sim.add_players(params)
        if not zero_filled:  # no glibc: deterministic, but not the server's start to the byte
            self.sim.mj_data.ctrl[:] = 0.0
            mujoco.mj_forward(self.sim.mj_model, self.sim.mj_data)
        bad = [p for p, a in zip(params, self.agents, strict=True) if a is None]
        if bad:
            raise ValueError(
                f"rcsssmj refused these players (number, team size or team count): {bad}"
            )
        self._effectors = [r.effector_names for r in self.robots]
        model = self.sim.mj_model
        self._slots = [
            {
                name: tuple(
                    model.actuator(a.agent_id.prefix + name + kind).id
                    for kind in ("_pos", "_vel", "_tau")
                )
                for name in names
            }
            for a, names in zip(self.agents, self._effectors, strict=True)
        ]
        """Per player, joint command name → its (position, velocity, torque) actuator ids."""
        self._sensor_slots: list[dict] | None = None
        """Per player, the sensor data addresses :meth:`readings` reads (found on first use)."""
        self._pending: list[list] = [[] for _ in self.agents]
        """Each player's commands for the next step (the answer to the last perceptions): per
        joint ``(pos id, vel id, tau id, q rad, dq rad/s, kp, kd, tau)``."""

    @staticmethod
    def idle_cycles_before(first_perception: bytes) -> int:
        """How many cycles a server ran before the perception ``first_perception`` (a player's
        first, from the server): pass it as ``idle_cycles`` to start from the same state."""
        match = re.search(rb"\(time \(now ([-+0-9.eE]+)\)\)", first_perception)
        if match is None:
            raise ValueError("the perception has no (time (now ...))")
        # the time is n cycles, printed truncated to 2 decimals (n * 0.02 may print 0.01 lower)
        return max(1, math.ceil(float(match.group(1)) / CYCLE_S - 1e-6))

    @classmethod
    def joining_as(
        cls, players: Sequence[tuple[str, str, int]], first_perceptions: Sequence[bytes]
    ) -> LeagueWorld:
        """A world in the state a server was in when it sent ``first_perceptions`` (each
        player's first message, players in joining order), after its first :meth:`cycle`: the
        server's idle cycles are read off the perception's time and confirmed by comparing the
        perceptions (the printed time is truncated, so its neighbours are tried too).

        Raises:
            ValueError: no number of idle cycles near the printed time reproduces them.
        """
        n = cls.idle_cycles_before(first_perceptions[0])
        for idle in (n, n + 1, n - 1, n + 2, n - 2):
            if idle < 1:
                continue
            world = cls(players, idle_cycles=idle)
            if world.cycle() == list(first_perceptions):
                return world
        raise ValueError(f"no start near {n} idle cycles reproduces the server's first perceptions")

    # ------------------------------------------------------------------ commands
    def effector_names(self, index: int) -> tuple[str, ...]:
        """Names player ``index``'s joint commands use (``he1``, ``lae1``, …), model order."""
        return self._effectors[index]

    def command(self, index: int, commands: Mapping[str, PDCommand]) -> None:
        """Player ``index``'s joint commands for the next :meth:`cycle` (they act in that
        cycle's step; joints not named keep their last command).

        Raises:
            KeyError: an unknown joint (naming player ``index``'s).
        """
        slots = self._slots[index]
        pending = []
        for name, c in commands.items():
            ids = slots.get(name)
            if ids is None:
                names = self._effectors[index]
                raise KeyError(f"unknown joint {name!r}; joints: {', '.join(names)}")
            # the values rcsssmj's action parser makes of the wire text (math.radians)
            pending.append(
                (*ids, math.radians(c.q_deg), math.radians(c.dq_deg_s), c.kp, c.kd, c.tau)
            )
        self._pending[index] = pending

    # ------------------------------------------------------------------ stepping
    def perceive(self) -> list[bytes]:
        """Every player's perception of the current state: the message bytes the server would
        send now, one per player, in joining order (reading the state changes nothing)."""
        self.sim.generate_perceptions()
        return [bytes(self._encoder.encode(a.perceptions) or b"(syn)") for a in self.agents]

    def step(self) -> None:
        """One 20 ms step (four 5 ms MuJoCo steps and the referee) with the commands given
        since the last step."""
        sim = self.sim
        # rcsssmj's motor action, written directly (the same assignments as its
        # ``ctrl_motor``, which only writes, so doing them before the step changes nothing)
        model, data = sim.mj_model, sim.mj_data
        gain, bias, ctrl = model.actuator_gainprm, model.actuator_biasprm, data.ctrl
        for pending in self._pending:
            for pos, vel, tau_id, q, dq, kp, kd, tau in pending:
                ctrl[tau_id] = tau
                ctrl[pos] = q
                ctrl[vel] = dq
                gain[pos, 0] = kp
                bias[pos, 1] = -kp
                gain[vel, 0] = kd
                bias[vel, 2] = -kd
        self._pending = [[] for _ in self.agents]
        try:
            sim.step([])
        except AttributeError as exc:
            if "startswith" not in str(exc):
                raise
            # rcsssmj 0.2.1's ball-contact filter reads every touching geometry's name, and
            # the K1's model leaves most of its geometries unnamed
            raise LeagueSimulationError(
                "rcsssmj failed in its ball-contact check: the ball touched a part of a robot "
                "whose model geometry has no name (the K1's torso, head and arms in rcsssmj "
                f"0.2.1; the real rcssservermj stops the same way): {exc}"
            ) from exc

    def cycle(self, perceive: bool = True) -> list[bytes]:
        """One pass of the server's loop: every player's perceptions of the current state (the
        message bytes the server would send), then one 20 ms step with the commands given since
        the last pass. Returns the perception messages, one per player (none with
        ``perceive=False``: the perceptions only read the state, so skipping them changes
        nothing else and saves most of a cycle's Python work)."""
        out = self.perceive() if perceive else []
        self.step()
        return out

    # ------------------------------------------------------------------ placing
    def place_player(
        self,
        index: int,
        pos: Sequence[float],
        quat: Sequence[float] = (1.0, 0.0, 0.0, 0.0),
        joint_angles_rad: Sequence[float] | None = None,
    ) -> None:
        """Put player ``index`` at torso position ``pos`` (m) with orientation ``quat``
        (``(w, x, y, z)``, the model's axes), at rest, with joint angles ``joint_angles_rad``
        (model order; ``None``: all 0), as the server's ``(agent … (move3d …))`` monitor command
        does (same methods); its joint commands are cleared (no torque until the next
        command)."""
        agent = self.agents[index]
        n = len(self.robots[index].joints)
        angles = np.zeros(n) if joint_angles_rad is None else np.asarray(joint_angles_rad, float)
        if angles.shape != (n,) or not np.isfinite(angles).all():
            raise ValueError(f"joint_angles_rad must be {n} finite numbers (rad)")
        agent.place_at(tuple(float(v) for v in pos), tuple(float(v) for v in quat))
        agent.init_joints(pos=angles)
        model, data = self.sim.mj_model, self.sim.mj_data
        for pos_id, vel_id, tau_id in self._slots[index].values():
            data.ctrl[[pos_id, vel_id, tau_id]] = 0.0
            model.actuator_gainprm[pos_id, 0] = model.actuator_biasprm[pos_id, 1] = 0.0
            model.actuator_gainprm[vel_id, 0] = model.actuator_biasprm[vel_id, 2] = 0.0
        self._pending[index] = []
        data.qacc_warmstart[:] = 0.0  # no memory of the last episode in the solver's start
        mujoco.mj_forward(model, data)

    def place_ball(self, pos: Sequence[float], vel: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        """Put the ball's centre at ``pos`` (m) with velocity ``vel`` (m/s), as the server's
        ``(ball (pos …) (vel …))`` monitor command does."""
        self.sim.request_place_ball(tuple(float(v) for v in pos), tuple(float(v) for v in vel))
        mujoco.mj_forward(self.sim.mj_model, self.sim.mj_data)

    def lowest_point_above_ground(self, index: int) -> float:
        """How far (m) player ``index``'s lowest point is above the ground plane (negative:
        below), by MuJoCo's own geometry distance between each of its collision geometries and
        the field's plane."""
        model, data = self.sim.mj_model, self.sim.mj_data
        root = model.body(self.agents[index].root_body_name).id
        plane = int(mujoco.mjtGeom.mjGEOM_PLANE)
        return clearance(
            model,
            data,
            (g for g in range(model.ngeom) if model.body_rootid[model.geom_bodyid[g]] == root),
            (g for g in range(model.ngeom) if model.geom_type[g] == plane),
        )

    # ------------------------------------------------------------------ readings
    def readings(self, index: int) -> dict:
        """The numbers of player ``index``'s next perception message without vision, read
        straight from MuJoCo's sensor arrays and truncated as ``rcsssmj`` truncates them
        (joint angles and velocities in deg and deg/s, gyro in deg/s and the accelerometer to 2
        decimals, torso position and orientation to 3): what :meth:`perceive` would write, about
        ten times cheaper (``tests/envs/test_league_envs.py`` checks they are the same).

        Returns:
            ``time`` (s), ``game`` (the ``GS`` object ``rcsssmj`` makes), ``q_deg``,
            ``dq_deg_s`` (model order), ``gyro``, ``accel``, ``pos``, ``quat`` (``None`` where
            the robot lacks the sensor), in the model's axes.
        """
        if self._sensor_slots is None:
            self._sensor_slots = [self._find_sensors(i) for i in range(len(self.agents))]
        slots = self._sensor_slots[index]
        d = self.sim.mj_data.sensordata

        def t2(v):
            return np.trunc(v * 100) / 100.0

        def t3(v):
            return np.trunc(v * 1000) / 1000.0

        out = {
            "time": int(self.sim.mj_data.time * 100) / 100.0,
            "game": self.sim._generate_game_state_perception(),
            "q_deg": t2(np.degrees(d[slots["q"]])),
            "dq_deg_s": t2(np.degrees(d[slots["dq"]])),
        }
        for key, adr, n, f in (
            ("gyro", slots["gyro"], 3, lambda v: t2(np.degrees(v))),
            ("accel", slots["accel"], 3, t2),
            ("pos", slots["pos"], 3, t3),
            ("quat", slots["quat"], 4, t3),
        ):
            out[key] = None if adr is None else f(d[adr : adr + n])
        return out

    def _find_sensors(self, index: int) -> dict:
        """Sensor data addresses of player ``index``: its joint position and velocity sensors
        in model order, and its (first) gyro, accelerometer, frame position and orientation."""
        model = self.sim.mj_model
        kinds = mujoco.mjtSensor
        q: list[int] = []
        dq: list[int] = []
        one: dict[str, int | None] = {"gyro": None, "accel": None, "pos": None, "quat": None}
        which = {
            int(kinds.mjSENS_GYRO): "gyro",
            int(kinds.mjSENS_ACCELEROMETER): "accel",
            int(kinds.mjSENS_FRAMEPOS): "pos",
            int(kinds.mjSENS_FRAMEQUAT): "quat",
        }
        for spec in self.agents[index].spec.sensors:
            sensor = model.sensor(spec.name)
            adr, kind = int(sensor.adr[0]), int(sensor.type[0])
            if kind == int(kinds.mjSENS_JOINTPOS):
                q.append(adr)
            elif kind == int(kinds.mjSENS_JOINTVEL):
                dq.append(adr)
            elif kind in which and one[which[kind]] is None:
                one[which[kind]] = adr
        return {"q": np.array(q, dtype=int), "dq": np.array(dq, dtype=int), **one}

    @property
    def time(self) -> float:
        """Simulation time, s."""
        return float(self.sim.sim_time)

    def joint_angles(self, index: int) -> np.ndarray:
        """Player ``index``'s joint angles, rad, model order."""
        return np.array([float(j.qpos[0]) for j in self.agents[index]._joints])

    def set_torso_force(self, index: int, force: Sequence[float]) -> None:
        """Push player ``index``'s torso with ``force`` (N, world frame, at the torso's centre of
        mass, MuJoCo's ``xfrc_applied``, which ``rcsssmj`` leaves alone) in every step until it
        is changed; ``(0, 0, 0)`` ends it. The server has no such force: a training aid
        (``TrainConfig.assist_force``).

        Raises:
            ValueError: ``force`` is not three finite numbers.
        """
        f = finite_force(force)
        body = self.sim.mj_model.body(self.agents[index].root_body_name).id
        self.sim.mj_data.xfrc_applied[body, :3] = f

    def torso_pose(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Player ``index``'s torso position (m) and orientation quaternion (w, x, y, z)."""
        body = self.sim.mj_data.body(self.agents[index].root_body_name)
        return body.xpos.copy(), body.xquat.copy()

    def ball_position(self) -> np.ndarray:
        """Ball centre, m."""
        return self.sim.mj_data.body("ball").xpos.copy()

    def ball_velocity(self) -> np.ndarray:
        """Ball linear velocity, m/s, world frame."""
        return np.array(self.sim.ball._qvel[0:3], dtype=float)

    def torso_velocity(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Player ``index``'s torso linear (m/s) and angular (rad/s) velocity, world frame."""
        model, data = self.sim.mj_model, self.sim.mj_data
        out = np.zeros(6)
        body = model.body(self.agents[index].root_body_name).id
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, body, out, 0)
        return out[3:].copy(), out[:3].copy()

"""The soccer scenarios on the league's current simulator: RCSSServerMJ's own game (``rcsssmj``:
the Booster T1 or K1, its field, its referee and rules) in-process, stepped exactly as
``rcssservermj`` steps it (:class:`~robocup_gym.sim.engines.rcsssmj.LeagueWorld`), behind the same
PettingZoo API as the Nao's scenarios. ``penalty_v1.parallel_env(robot="T1")`` and
``game_v1.parallel_env(robot="K1", left_size=2, right_size=2)`` build it; the actions are joint
level (PD targets, as the single-agent environments' league robots take them).

====================  ==============  =====================================================
option                default         meaning
====================  ==============  =====================================================
``robot``             "T1"            the league robot (every player)
``left_size``         scenario        players of the left team (game: 0–7, penalty: 1)
``right_size``        scenario        the right team's
``max_cycles``        scenario        episode length in cycles (truncation)
``action_mode``       target_angle    ``"target_angle"``, ``"target_angle_gains"`` or
                                      ``"torque"`` (``robocup_gym.envs.actions.PDActionMapper``)
``pd_saturation_deg`` 20.0            default gain: the joint's whole torque at this error
``pd_damping_s``      0.05            default derivative gain, ``kd = kp ×`` this (s)
``privileged``        False           add ground truth (own pose and velocity, the ball's)
``reward_goal``       1.0             per goal, to the scorers (minus to the others)
``ball_progress``     0.0             per metre the ball moves toward the opponent goal
====================  ==============  =====================================================

Observations per agent, in the units the perceptors give them: joint angles (rad) and
velocities (rad/s), gyroscope (rad/s) and accelerometer (m/s²) as ``rcssservermj`` sends them
(``LeagueWorld.readings``); with ``privileged``, the torso's (x, y) (m), heading (cos, sin),
velocity (m/s), and the ball's position and velocity relative to the torso in its heading frame.
Every team sees the field as the left team does (the right team's x and y mirrored), so one
policy plays either side. The game's rules are ``rcsssmj``'s: ``game`` starts from the left
team's kick-off with the teams in their halves (the Nao's kick-off formation stretched to the
league's 55 × 36 m field, the right team out of the centre circle); ``penalty`` drops the ball
on the right penalty spot (7.32 m in front of the goal) with the striker behind it and the
goalkeeper on the goal line, and ends at a goal or when play stops. A step of a simulation
that fails ends the episode, truncated, for everyone (``info[agent]["diverged"]`` says why).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from pettingzoo import ParallelEnv

from robocup_gym.envs.actions import ActionMode, PDActionMapper
from robocup_gym.types import reject_unknown_fields

__all__ = ["LEAGUE_SCENARIOS", "LeagueSoccerConfig", "LeagueSoccerEnv"]

LEAGUE_SCENARIOS = ("game", "penalty")
"""The scenarios the league's robots play (keepaway needs the Nao's referee)."""
_SIDES = ("left", "right")
_TEAM_NAMES = ("RobocupGymLeft", "RobocupGymRight")
_PD_MODES = ("target_angle", "target_angle_gains", "torque")


@dataclass(frozen=True)
class LeagueSoccerConfig:
    """The options of a league soccer environment (see the module docstring)."""

    robot: str = "T1"
    left_size: int = 1
    right_size: int = 1
    max_cycles: int = 3000
    action_mode: str = "target_angle"
    pd_saturation_deg: float = 20.0
    pd_damping_s: float = 0.05
    privileged: bool = False
    reward_goal: float = 1.0
    ball_progress: float = 0.0

    def __post_init__(self) -> None:
        for name in ("left_size", "right_size"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= 7:
                raise ValueError(
                    f"{name} must be a number of players 0-7 (rcsssmj's teams), got {v!r}"
                )
        if self.left_size + self.right_size < 1:
            raise ValueError("a game needs at least one player")
        if isinstance(self.max_cycles, bool) or not isinstance(self.max_cycles, int):
            raise ValueError(f"max_cycles must be a positive integer, got {self.max_cycles!r}")
        if self.max_cycles < 1:
            raise ValueError(f"max_cycles must be a positive integer, got {self.max_cycles!r}")
        if self.action_mode not in _PD_MODES:
            raise ValueError(f"action_mode must be one of {_PD_MODES}, got {self.action_mode!r}")
        for name in ("pd_saturation_deg", "pd_damping_s", "reward_goal", "ball_progress"):
            if not np.isfinite(float(getattr(self, name))):
                raise ValueError(f"{name} must be a finite number, got {getattr(self, name)!r}")
        if not 0.0 < self.pd_saturation_deg <= 180.0:
            raise ValueError(f"pd_saturation_deg must be in (0, 180], got {self.pd_saturation_deg}")
        if self.pd_damping_s < 0.0:
            raise ValueError(f"pd_damping_s must be >= 0, got {self.pd_damping_s}")


_SCENARIO_DEFAULTS: dict[str, dict[str, Any]] = {
    "game": {"left_size": 2, "right_size": 2, "max_cycles": 3000},
    "penalty": {"left_size": 1, "right_size": 1, "max_cycles": 500},
}


class LeagueSoccerEnv(ParallelEnv):
    """One soccer scenario (``"game"`` or ``"penalty"``) on RCSSServerMJ's world; keyword
    arguments are :class:`LeagueSoccerConfig` fields.

    Raises:
        ValueError: an unknown scenario or a bad option value.
        TypeError: an unknown option (naming the known ones).
        robocup_gym.robot.league.RcsssmjUnavailableError: ``rcsssmj`` is not installed.
    """

    metadata: ClassVar[dict] = {
        "name": "robocup_league_soccer_v0",
        "render_modes": [],
        "is_parallelizable": True,
    }

    def __init__(self, scenario: str = "game", **options: Any) -> None:
        if scenario not in LEAGUE_SCENARIOS:
            raise ValueError(
                f"the league's robots play {', '.join(LEAGUE_SCENARIOS)}, not {scenario!r} "
                "(keepaway needs the Nao's referee: robot='nao')"
            )
        reject_unknown_fields(
            LeagueSoccerConfig, options, "league soccer option", "options", TypeError
        )
        self.scenario = scenario
        self.config = c = LeagueSoccerConfig(**{**_SCENARIO_DEFAULTS[scenario], **options})
        if scenario == "penalty" and (c.left_size, c.right_size) != (1, 1):
            raise ValueError("a penalty is one striker (left) against one goalkeeper (right)")
        from robocup_gym.robot.league import league_robot
        from robocup_gym.sim.engines.rcsssmj import LeagueWorld

        self.robot = league_robot(str(c.robot))
        self.possible_agents = [f"left_{k + 1}" for k in range(c.left_size)] + [
            f"right_{k + 1}" for k in range(c.right_size)
        ]
        players = [(self.robot.name, _TEAM_NAMES[0], k + 1) for k in range(c.left_size)] + [
            (self.robot.name, _TEAM_NAMES[1], k + 1) for k in range(c.right_size)
        ]
        self.world = LeagueWorld(players)
        n = len(self.robot.joints)
        self._mappers = {
            a: PDActionMapper(
                self.robot,
                np.arange(n),
                ActionMode(c.action_mode),
                c.pd_saturation_deg,
                c.pd_damping_s,
            )
            for a in self.possible_agents
        }
        size = self._mappers[self.possible_agents[0]].size
        self._action_space = gym.spaces.Box(-1.0, 1.0, (size,), np.float32)
        obs_size = 2 * n + 6 + (10 if c.privileged else 0)
        self._observation_space = gym.spaces.Box(-np.inf, np.inf, (obs_size,), np.float32)
        self.agents: list[str] = []
        self._rng = np.random.default_rng()
        self._cycles = 0
        self._score = (0, 0)
        self._ball_x = 0.0

    # ------------------------------------------------------------------ spaces
    def observation_space(self, agent: str) -> gym.spaces.Box:
        self._index(agent)
        return self._observation_space

    def action_space(self, agent: str) -> gym.spaces.Box:
        self._index(agent)
        return self._action_space

    def _index(self, agent: str) -> int:
        try:
            return self.possible_agents.index(agent)
        except ValueError:
            raise KeyError(
                f"no agent {agent!r} in this game (agents: {', '.join(self.possible_agents)})"
            ) from None

    @staticmethod
    def side_of(agent: str) -> str:
        return agent.split("_", 1)[0]

    # ------------------------------------------------------------------ episodes
    def _start(self) -> tuple[dict[str, tuple[float, float, float]], tuple[float, float]]:
        """Each agent's (x, y, heading in degrees) and the ball's (x, y)."""
        field = self.world.sim.field
        half_x, half_y = field.field_dim[0] / 2.0, field.field_dim[1] / 2.0
        if self.scenario == "penalty":
            bx, by = half_x - field.penalty_spot_distance, 0.0
            return {"left_1": (bx - 0.4, by, 0.0), "right_1": (half_x - 0.4, 0.0, 180.0)}, (bx, by)
        from robocup_gym.sim.field import FIELD_HALF_LENGTH, FIELD_HALF_WIDTH
        from robocup_gym.soccer.formation import kickoff_positions

        c = self.config
        sx, sy = half_x / FIELD_HALF_LENGTH, half_y / FIELD_HALF_WIDTH
        starts = {}
        for side, size in zip(_SIDES, (c.left_size, c.right_size), strict=True):
            for k, (x, y, heading) in enumerate(kickoff_positions(side, size)):
                x, y = x * sx, y * sy
                if side == "right" and math.hypot(x, y) < field.center_circle_radius + 0.3:
                    x = field.center_circle_radius + 0.3  # out of the left team's kick-off
                starts[f"{side}_{k + 1}"] = (x, y, heading)
        return starts, (0.0, 0.0)

    def reset(self, seed: int | None = None, options: dict | None = None):
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        w = self.world
        starts, ball = self._start()
        stand = np.zeros(len(self.robot.joints))
        for i, agent in enumerate(self.possible_agents):
            x, y, heading = starts[agent]
            h = math.radians(heading) / 2.0
            quat = (math.cos(h), 0.0, 0.0, math.sin(h))
            w.place_player(i, (x, y, 2.0), quat, stand)
            z = 2.0 - w.lowest_point_above_ground(i)
            w.place_player(i, (x, y, z), quat, stand)
            self._mappers[agent].start_episode(np.degrees(stand))
        w.place_ball((ball[0], ball[1], self.robot.ball_radius))
        if self.scenario == "penalty":
            w.sim.request_drop_ball(ball)
        else:
            from rcsssmj.games.teams import TeamSide

            w.sim.request_kick_off(TeamSide.LEFT)
        w.step()  # one limp step, as a placement on the server shows only a step later
        self.agents = list(self.possible_agents)
        self._cycles = 0
        game = w.readings(0)["game"]
        self._score = (int(game.score_left), int(game.score_right))
        self._ball_x = float(w.ball_position()[0])
        obs = {a: self._observe(a) for a in self.agents}
        infos = {a: self._info(str(game.play_mode), None, {}) for a in self.agents}
        return obs, infos

    def step(self, actions: dict[str, np.ndarray]):
        if not self.agents:
            raise RuntimeError("step() after the episode ended: call reset()")
        commands = {}
        for agent in self.agents:
            if agent not in actions:
                raise ValueError(f"no action for agent {agent!r}")
            a = np.asarray(actions[agent], dtype=float)
            if a.shape != self._action_space.shape:
                raise ValueError(
                    f"agent {agent!r}: action shape {a.shape}, expected {self._action_space.shape}"
                )
            if not np.isfinite(a).all():
                raise ValueError(f"agent {agent!r}: action has NaN or inf values: {a}")
            commands[agent] = np.clip(a, -1.0, 1.0)
        unknown = sorted(set(actions) - set(self.agents))
        if unknown:
            raise ValueError(f"actions for agents not in the game: {', '.join(unknown)}")
        from robocup_gym.sim.engines.rcsssmj import LeagueSimulationError

        w = self.world
        diverged = None
        try:
            w.step()  # with the commands that answered the last observations
        except LeagueSimulationError as exc:
            diverged = str(exc)
        for agent, a in commands.items():
            i = self._index(agent)
            w.command(i, self._mappers[agent].command(a, np.degrees(w.joint_angles(i))))
        self._cycles += 1
        game = w.readings(0)["game"]
        score = (int(game.score_left), int(game.score_right))
        goal = None
        if score[0] > self._score[0]:
            goal = "left"
        elif score[1] > self._score[1]:
            goal = "right"
        self._score = score
        ball_x = float(w.ball_position()[0])
        progress, self._ball_x = ball_x - self._ball_x, ball_x
        c = self.config
        mode = str(game.play_mode)
        ended = diverged is not None or mode == "GameOver"
        if self.scenario == "penalty":
            ended = ended or goal is not None or mode != "PlayOn"
        truncated = self._cycles >= c.max_cycles or diverged is not None
        rewards, infos = {}, {}
        for agent in self.agents:
            side = self.side_of(agent)
            sign = 1.0 if side == "left" else -1.0
            terms = {
                "goal": 0.0 if goal is None else c.reward_goal * (1.0 if goal == side else -1.0),
                "ball_progress": c.ball_progress * sign * progress,
            }
            rewards[agent] = float(sum(terms.values()))
            infos[agent] = self._info(mode, goal, terms)
            if diverged is not None:
                infos[agent]["diverged"] = diverged
        obs = {a: self._observe(a) for a in self.agents}
        terminations = {a: bool(ended and diverged is None) for a in self.agents}
        truncations = {a: bool(truncated and not terminations[a]) for a in self.agents}
        if ended or truncated:
            self.agents = []
        return obs, rewards, terminations, truncations, infos

    # ------------------------------------------------------------------ observations
    def _observe(self, agent: str) -> np.ndarray:
        i = self._index(agent)
        w = self.world
        r = w.readings(i)
        parts = [
            np.radians(r["q_deg"]),
            np.radians(r["dq_deg_s"]),
            np.zeros(3) if r["gyro"] is None else np.radians(r["gyro"]),
            np.zeros(3) if r["accel"] is None else np.asarray(r["accel"], dtype=float),
        ]
        if self.config.privileged:
            mirror = -1.0 if self.side_of(agent) == "right" else 1.0
            pos, quat = w.torso_pose(i)
            vel, _ = w.torso_velocity(i)
            heading = math.atan2(
                2 * (quat[0] * quat[3] + quat[1] * quat[2]),
                1 - 2 * (quat[2] ** 2 + quat[3] ** 2),
            )
            if mirror < 0:
                heading += math.pi
            ch, sh = math.cos(heading), math.sin(heading)
            to_own = np.array([[ch, sh], [-sh, ch]])  # field (team view) -> heading frame
            ball, ball_vel = w.ball_position(), w.ball_velocity()
            parts += [
                mirror * pos[:2],
                np.array([ch, sh]),
                mirror * vel[:2],
                to_own @ (mirror * (ball[:2] - pos[:2])),
                to_own @ (mirror * ball_vel[:2]),
            ]
        obs = np.concatenate(parts).astype(np.float32)
        return np.nan_to_num(obs, nan=0.0, posinf=0.0, neginf=0.0)

    def _info(self, mode: str, goal: str | None, terms: dict[str, float]) -> dict[str, Any]:
        return {"play_mode": mode, "score": self._score, "goal": goal, "reward_terms": terms}

    def state(self) -> np.ndarray:
        """Every player's torso pose and the ball's position (world, m)."""
        w = self.world
        rows = [np.concatenate(w.torso_pose(i)) for i in range(len(self.possible_agents))]
        return np.concatenate([*rows, w.ball_position()]).astype(np.float32)

    def close(self) -> None:
        self.agents = []

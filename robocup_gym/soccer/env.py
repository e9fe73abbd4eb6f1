"""RoboCup 3D soccer as a PettingZoo Parallel environment; the scenarios (:mod:`.penalty_v1`,
:mod:`.keepaway_v1`, :mod:`.game_v1`) say only where an episode starts, when it ends and what
they reward beyond goals.

Agents are named by team and uniform number (``left_1`` … ``right_11``). Every agent acts every
step with joint-level actions, as :class:`robocup_gym.envs.BaseEnv` does: ``Box(-1, 1)``, one value
per joint of its robot (22, 24 for type 4), as joint velocities (``action_mode="velocity"``: value
× the joint's max speed, rad/s) or target angles over each joint's range (``"target_angle"``). A
step is ``cycles_per_step`` 20 ms cycles with the same action. Observations:
:mod:`robocup_gym.soccer.observations`.

Rewards are team-shared and zero-sum: a goal pays ``reward_goal`` to every player of the
scoring team and takes as much from every player of the other; the shaping terms below do the
same with their weight (0 by default), and each scenario adds its own. ``info[agent]`` carries
``play_mode``, ``score`` (own, opponent), the cycle's ``goal`` side, ``reward_terms`` (each
term's share of this step's reward) and, when the simulation diverged, ``diverged`` (the reason;
the episode then ends, truncated, for everyone).

====================  =======  ===========================================================
option                default  meaning
====================  =======  ===========================================================
``left_types``        (0,)     Nao type of each left player (uniform numbers 1, 2, …)
``right_types``       (0,)     the right team's
``engine``            "ode"    ``"ode"`` (SimSpark's physics) or ``"mujoco"``
``max_cycles``        scenario episode length in cycles (truncation)
``cycles_per_step``   1        cycles per step, the action held
``action_mode``       velocity ``"velocity"`` or ``"target_angle"``
``target_gain``       12.5     1/s, target-angle mode: velocity = gain × angle error
``privileged``        False    add ground truth to the observations (training only)
``vision_noise``      True     ``See`` with rcssserver3d's noise
``rules``             True     the referee's rules: all, none (False) or single ones
                               switched (``{"ball_out": False}``; see ``sim.referee.Rules``)
``self_collisions``   False    rcssserver3d's self-collision rule (a robot's own colliding
                               boxes freeze their joints for 1 s; ``sim.self_collision``),
                               as a real server and ``serve`` apply it; the get-up skill
                               then plays ``GetUp-v1``'s scripts alone
``contact_fouls``     False    rcssserver3d's touching-group and charging fouls
                               (``sim.fouls``), as a real server and ``serve`` apply them;
                               off, the rules ``touching`` and ``charging`` are off
``first_touch_plays_on`` True  a kick-off or set piece ends at the first touch of the ball, as
                               on rcssserver3d (``game_v0``: False, its referee waited for the
                               drop ball after 15 s)
``actions``           joints   ``"joints"`` or ``"skills"`` (:mod:`robocup_gym.soccer.skills`)
``walk``              game-walk skill actions: the shipped walk the players walk with
                               (``game-walk``, to which the scripted team is tuned; ``walk``,
                               the omnidirectional one, with ``walk_faces_x=False``)
``walk_faces_x``      True     skill actions: the walk sees its player as if it faced +x, as
                               it was trained (its observation of the torso's orientation is
                               in the world frame); the scenarios' v0 versions: False, their
                               walk went askew and hardly turned facing −x
``random_start``      False    the game only: every player and the ball at a random place on
                               the field, in play (as dm_control's soccer starts), instead of
                               the kick-off; a training aid (:func:`random_start`)
``skill_cycles``      10       cycles per step with skill actions
``skills``            ("kick",) skill actions: the motion skills a player can start, their
                               values (start, parameters) after the walk's three
                               (``motions.register_motion_skill``)
``reward_goal``       1.0      per goal, to the scorers (minus to the others)
``ball_progress``     0.0      per metre the ball moves toward the opponent goal
``possession``        0.0      per step for the team whose player is nearest the ball
====================  =======  ===========================================================
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

try:
    from pettingzoo import ParallelEnv
    from pettingzoo.utils import parallel_to_aec, wrappers
except ImportError as exc:  # pragma: no cover - depends on the installation
    raise ImportError(
        f"the soccer environments need PettingZoo ({exc}): pip install 'robocup-gym[soccer]'"
    ) from exc

from robocup_gym.envs.actions import ActionMapper, ActionMode
from robocup_gym.envs.observations import heading_frame
from robocup_gym.sim.field import FIELD_HALF_LENGTH, FIELD_HALF_WIDTH
from robocup_gym.sim.referee import Rules, other
from robocup_gym.soccer.game import SIDES, CycleReport, SoccerGame, Start
from robocup_gym.soccer.motions import checked_motion_skills
from robocup_gym.soccer.observations import PlayerObserver
from robocup_gym.soccer.scripted import TeamView
from robocup_gym.soccer.skills import (
    DEFAULT_MOTION_SKILLS,
    DEFAULT_WALK,
    SkillSet,
    checked_action,
    skill_action_labels,
)
from robocup_gym.types import check_field_kinds, is_integer, is_number, reject_unknown_fields

__all__ = [
    "ActionsChecked",
    "SoccerConfig",
    "SoccerParallelEnv",
    "aec_from_parallel",
    "random_start",
]

_ACTION_MODES = ("velocity", "target_angle")


@dataclass(frozen=True)
class SoccerConfig:
    """The options of a soccer environment (see the module docstring)."""

    left_types: tuple[int, ...] = (0,)
    right_types: tuple[int, ...] = (0,)
    engine: str = "ode"
    max_cycles: int = 500
    cycles_per_step: int = 1
    action_mode: str = "velocity"
    target_gain: float = 12.5
    privileged: bool = False
    vision_noise: bool = True
    rules: bool | Mapping[str, bool] = True
    self_collisions: bool = False
    contact_fouls: bool = False
    first_touch_plays_on: bool = True
    actions: str = "joints"
    walk: str = DEFAULT_WALK
    walk_faces_x: bool = True
    random_start: bool = False
    skill_cycles: int = 10
    skills: tuple[str, ...] = DEFAULT_MOTION_SKILLS
    reward_goal: float = 1.0
    ball_progress: float = 0.0
    possession: float = 0.0

    def __post_init__(self) -> None:
        for name in ("left_types", "right_types"):
            value = getattr(self, name)
            if not isinstance(value, Sequence) or not all(map(is_integer, value)):
                raise ValueError(f"{name} must be a sequence of Nao types 0-4, got {value!r}")
            object.__setattr__(self, name, tuple(int(t) for t in value))
            for t in getattr(self, name):
                if t not in range(5):
                    raise ValueError(f"{name}: {t} is not a Nao type (0-4)")
            if len(getattr(self, name)) > 11:
                raise ValueError(f"{name}: a team has at most 11 players")
        if not self.left_types and not self.right_types:
            raise ValueError("a game needs at least one player")
        if self.engine not in ("ode", "mujoco"):
            raise ValueError(f"engine must be 'ode' or 'mujoco', got {self.engine!r}")
        if self.action_mode not in _ACTION_MODES:
            raise ValueError(
                f"action_mode must be one of {_ACTION_MODES}, got {self.action_mode!r}"
            )
        Rules.of(self.rules)  # an unknown rule or a value that is not a bool: a clear error
        # the flags ("no" is not false); the other fields are checked here with messages of
        # their own
        check_field_kinds(self, skip=("int", "float", "str", "tuple[int, ...]", "tuple[str, ...]"))
        if not isinstance(self.walk, str) or not self.walk:
            raise ValueError(f"walk must be the name of a shipped walk, got {self.walk!r}")
        if self.actions not in ("joints", "skills"):
            raise ValueError(f"actions must be 'joints' or 'skills', got {self.actions!r}")
        object.__setattr__(self, "skills", checked_motion_skills(self.skills))
        for name in ("max_cycles", "cycles_per_step", "skill_cycles"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be a positive integer, got {value!r}")
        for name in ("target_gain", "reward_goal", "ball_progress", "possession"):
            value = getattr(self, name)
            if not (is_number(value) and math.isfinite(value)):
                raise ValueError(f"{name} must be a finite number, got {value!r}")

    @property
    def game_rules(self) -> Rules:
        """The referee's rules of this configuration (:attr:`rules`, the contact fouls off
        unless :attr:`contact_fouls`)."""
        rules = Rules.of(self.rules)
        if not self.contact_fouls:
            rules = replace(rules, touching=False, charging=False)
        return rules

    @classmethod
    def with_options(cls, defaults: SoccerConfig, options: Mapping[str, Any]) -> SoccerConfig:
        """``defaults`` with ``options`` over them.

        Raises:
            TypeError: an unknown option (the message lists the known ones).
        """
        reject_unknown_fields(cls, options, "soccer option", "options", TypeError)
        return replace(defaults, **options)


class SoccerParallelEnv(ParallelEnv):
    """The soccer environment of one scenario (subclasses say where an episode starts, when it
    ends and what else they reward). Keyword arguments are :class:`SoccerConfig` fields."""

    metadata: ClassVar[dict] = {
        "name": "robocup_soccer_v0",
        "render_modes": ["rgb_array"],
        "render_fps": 50,
        "is_parallelizable": True,
    }
    default_config = SoccerConfig()
    random_starts: ClassVar[bool] = False
    """Whether the scenario has the option ``random_start``."""

    def __init__(
        self,
        render_mode: str | None = None,
        render_size: tuple[int, int] = (640, 360),
        **options: Any,
    ) -> None:
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(
                f"render_mode must be None or one of {self.metadata['render_modes']}, "
                f"got {render_mode!r}"
            )
        self.render_mode = render_mode
        self.render_size = (int(render_size[0]), int(render_size[1]))
        self.cycle_hook: Any = None
        """Called with the environment after every simulated cycle of a step (a step of skill
        actions runs several), e.g. to record every cycle of a video."""
        self._scene: Any = None
        self._camera: Any = None
        self.config = SoccerConfig.with_options(self.default_config, options)
        if self.config.random_start and not self.random_starts:
            raise ValueError(f"random_start is an option of the game, not of {type(self).__name__}")
        c = self.config
        self.game = SoccerGame(
            c.left_types,
            c.right_types,
            engine=c.engine,
            rules=c.game_rules,
            vision_noise=c.vision_noise,
            self_collisions=c.self_collisions,
            first_touch_plays_on=c.first_touch_plays_on,
        )
        self.possible_agents = list(self.game.names)
        self.agents: list[str] = []
        self._side = {n: p.side for n, p in zip(self.game.names, self.game.players, strict=True)}
        world = self.game.world
        self._observers: dict[str, PlayerObserver] = {}
        self._mappers: dict[str, ActionMapper] = {}
        teams = teams_of(c)
        self._others: dict[str, list[str]] = {}
        """Per agent, the other players its privileged observation places, in order."""
        for name, p in zip(self.game.names, self.game.players, strict=True):
            model = world.robots[p.index].model
            mates = [a for a in teams[p.side] if a != name]
            opponents = teams["right" if p.side == "left" else "left"]
            self._others[name] = mates + opponents if c.privileged else []
            self._observers[name] = PlayerObserver(
                model, p.side, c.privileged, len(mates), len(opponents)
            )
            self._mappers[name] = ActionMapper(
                model,
                np.arange(len(model.joints)),
                ActionMode(c.action_mode),
                c.target_gain,
                stop_margin_deg=0.5 if c.action_mode == "target_angle" else 0.0,
            )
        self.skills = (
            SkillSet(
                self.game.robot_types,
                walk=c.walk,
                self_collisions=c.self_collisions,
                walk_faces_x=c.walk_faces_x,
                motions=c.skills,
            )
            if c.actions == "skills"
            else None
        )
        self.skill_action_labels = (
            self.skills.action_labels if self.skills is not None else skill_action_labels(c.skills)
        )
        """The values of a skill action in this game (the walk's, then each motion skill's of
        ``skills``, as registered when the game was made), whatever its ``actions``: what a
        scripted team fits its actions to."""
        self._angles: dict[str, np.ndarray] = {}
        self._cycles = 0
        self._rng = np.random.default_rng()
        self._ball_x = 0.0

    # ------------------------------------------------------------------ spaces
    @functools.cache  # noqa: B019 (one space object per agent, as PettingZoo asks)
    def observation_space(self, agent: str) -> gym.spaces.Box:
        size = self._observer(agent).size
        return gym.spaces.Box(-1.0, 1.0, (size,), np.float32)

    @functools.cache  # noqa: B019
    def action_space(self, agent: str) -> gym.spaces.Box:
        n = len(self.skill_action_labels) if self.skills is not None else self._mapper(agent).size
        return gym.spaces.Box(-1.0, 1.0, (n,), np.float32)

    def observation_labels(self, agent: str) -> list[str]:
        """One label per value of ``agent``'s observation, in order
        (:func:`~robocup_gym.soccer.observations.observation_labels`)."""
        return list(self._observer(agent).labels)

    def _observer(self, agent: str) -> PlayerObserver:
        try:
            return self._observers[agent]
        except KeyError:
            raise KeyError(
                f"no agent {agent!r} in this game (agents: {', '.join(self.possible_agents)})"
            ) from None

    def _mapper(self, agent: str) -> ActionMapper:
        self._observer(agent)
        return self._mappers[agent]

    # ------------------------------------------------------------------ scenario hooks
    def _start(self, rng: np.random.Generator) -> Start:
        """Where an episode starts."""
        raise NotImplementedError

    def _ended(self, report: CycleReport) -> str | None:
        """Why the episode ends after this cycle (``None``: it goes on)."""
        return "game over" if report.play_mode == "GameOver" else None

    def _scenario_reward(self, report: CycleReport) -> dict[str, float]:
        """The scenario's own reward terms for the left team this cycle (zero-sum: the right
        team gets the negatives), by term name."""
        return {}

    # ------------------------------------------------------------------ the API
    def reset(
        self, seed: int | None = None, options: dict | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, dict]]:
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        start = self._start(self._rng)
        self.game.reset(start, seed=None if seed is None else int(seed))
        self.agents = list(self.possible_agents)
        self._cycles = 0
        self._ball_x = float(self.game.ball_position()[0])
        infos = {}
        seen = self._perceive_all()
        for name in self.agents:
            self._observers[name].reset()
        obs = self._observe(self.agents, seen)
        for name in self.agents:
            infos[name] = self._info(name, None, {})
        if self.skills is not None:
            self.skills.reset(seen, None if seed is None else int(seed))
        return obs, infos

    def step(self, actions: Mapping[str, np.ndarray]):
        if not self.agents:
            raise RuntimeError("the episode has ended: call reset() first")
        commands = self._commands(actions)
        report = CycleReport(play_mode=self.game.world.game.play_mode)
        goal = None
        terms = {"goal": 0.0, "ball_progress": 0.0, "possession": 0.0}
        ended = None
        skills = self.skills
        seen: dict[str, np.ndarray] = {}
        # with skills every cycle is perceived: the observers keep each cycle's perception and
        # build an observation from the last one only
        pending: Mapping[int, Any] | None = None
        cycles = self.config.skill_cycles if skills is not None else self.config.cycles_per_step
        for _ in range(cycles):
            if skills is not None:
                commands = skills.commands()
            report = self.game.step(commands)
            commands = {}  # the targets stay
            self._cycles += 1
            if self.cycle_hook is not None:
                self.cycle_hook(self)
            if report.diverged is not None:
                break
            if skills is not None:  # the skills (and vision) see every cycle
                perceptions = self._perceive_all()
                skills.observe(perceptions)
                if pending is not None:
                    for name in self.agents:
                        self._observers[name].remember(pending[self.game.index(name)])
                pending = perceptions
            goal = goal or report.goal
            for k, v in self._cycle_terms(report).items():
                terms[k] = terms.get(k, 0.0) + v
            ended = self._ended(report)
            if ended is not None:
                break
        truncated = report.diverged is not None or (
            ended is None and self._cycles >= self.config.max_cycles
        )
        terminated = ended is not None and report.diverged is None
        rewards, obs, infos = {}, {}, {}
        left_reward = sum(terms.values())
        if pending is not None:
            seen = self._observe(self.agents, pending)
        last = self._perceive_all() if report.diverged is None and not seen else {}
        if last:
            seen = self._observe(self.agents, last)
        for name in self.agents:
            sign = 1.0 if self._side[name] == "left" else -1.0
            rewards[name] = float(sign * left_reward)
            if name in seen:
                obs[name] = seen[name]
            else:
                obs[name] = np.zeros(self._observers[name].size, np.float32)
            info = self._info(name, goal, {k: sign * v for k, v in terms.items()})
            if report.diverged is not None:
                info["diverged"] = report.diverged
            if ended is not None:
                info["end"] = ended
            infos[name] = info
        terminations = {n: terminated for n in self.agents}
        truncations = {n: truncated for n in self.agents}
        if terminated or truncated:
            self.agents = []
        return obs, rewards, terminations, truncations, infos

    def _cycle_terms(self, report: CycleReport) -> dict[str, float]:
        """Every reward term of one cycle, for the left team."""
        c = self.config
        out: dict[str, float] = {}
        if report.goal is not None:
            out["goal"] = c.reward_goal if report.goal == "left" else -c.reward_goal
        ball = self.game.ball_position()
        if c.ball_progress:
            out["ball_progress"] = c.ball_progress * (float(ball[0]) - self._ball_x)
        self._ball_x = float(ball[0])
        if c.possession:
            nearest = self._nearest_side(ball)
            if nearest is not None:
                out["possession"] = c.possession if nearest == "left" else -c.possession
        out.update(self._scenario_reward(report))
        return out

    def _nearest_side(self, ball: np.ndarray) -> str | None:
        w = self.game.world
        best, side = np.inf, None
        for p in self.game.players:
            d = float(np.hypot(*(w.torso_position(p.index)[:2] - ball[:2])))
            if d < best:
                best, side = d, p.side
        return side

    def _commands(self, actions: Mapping[str, np.ndarray]) -> dict[int, np.ndarray]:
        unknown = [a for a in actions if a not in self.agents]
        if unknown:
            raise KeyError(
                f"actions for {', '.join(map(repr, unknown))}, which "
                f"{'is' if len(unknown) == 1 else 'are'} not playing "
                f"(agents: {', '.join(self.agents)})"
            )
        checked: dict[str, np.ndarray] = {}
        for name in self.agents:
            if name not in actions:
                raise KeyError(f"no action for {name!r} (every agent acts every step)")
            checked[name] = self.check_action(name, actions[name])
        commands: dict[int, np.ndarray] = {}
        for name, a in checked.items():  # nothing is changed before every action is checked
            if self.skills is not None:
                self.skills.decide(self.game.index(name), a)
            else:
                commands[self.game.index(name)] = self._mappers[name].command(a, self._angles[name])
        return commands

    def check_action(self, name: str, action: Any) -> np.ndarray:
        """Agent ``name``'s ``action`` as it acts (clipped to [-1, 1]).

        Raises:
            ValueError: naming the agent and what its action must be (one value per joint of
                its robot, or a skill action's values), or the value that is not finite.
        """
        if self.skills is not None:
            labels, what = self.skills.action_labels, self.skills.action_what
        else:
            labels = self._mappers[name].labels()
            what = f"one value per joint of its type-{self._type(name)} robot"
        return checked_action(name, action, labels, what)

    def goalkeepers(self) -> set[str]:
        """The agents that play goalkeeper (for scripted teams): uniform number 1 of a team of
        several players; a scenario may say otherwise."""
        teams = teams_of(self.config)
        return {names[0] for names in teams.values() if len(names) > 1}

    def team_view(self, agents: list[str]) -> TeamView:
        """What a scripted team of ``agents`` (one side's) decides from, from ground truth."""
        world, game = self.game.world, self.game
        side = self.side_of(agents[0])
        others = teams_of(self.config)[other(side)]
        return TeamView(
            side=side,
            ball=world.ball_position()[:2].copy(),
            positions={a: world.torso_position(game.index(a))[:2].copy() for a in agents},
            headings={a: heading_frame(world.torso_quat(game.index(a))) for a in agents},
            keepers=self.goalkeepers() & set(agents),
            play_mode=game.referee.play_mode,
            opponents=np.array([world.torso_position(game.index(o))[:2] for o in others]).reshape(
                -1, 2
            ),
        )

    def side_of(self, agent: str) -> str:
        """``"left"`` or ``"right"``."""
        self._observer(agent)
        return self._side[agent]

    def _type(self, name: str) -> int:
        return self.game.robot_types[self.game.index(name)]

    def _observe(self, agents: list[str], perceptions: Mapping[int, Any]) -> dict[str, np.ndarray]:
        """The observations of ``agents`` from their perceptions (by world index)."""
        xy: dict[str, np.ndarray] = {}
        if self.config.privileged:
            w = self.game.world
            xy = {a: w.torso_position(self.game.index(a))[:2] for a in self.possible_agents}
        return {
            a: self._observers[a](
                perceptions[self.game.index(a)],
                np.array([xy[o] for o in self._others[a]]) if self._others[a] else None,
            )
            for a in agents
        }

    def _perceive_all(self) -> dict[int, Any]:
        """Every playing agent's perception, by world index (vision's shared work done once)."""
        gt = self.config.privileged or self.skills is not None
        idx = [self.game.index(n) for n in self.agents]
        out = dict(zip(idx, self.game.world.perceive_all(idx, ground_truth=gt), strict=True))
        for n, i in zip(self.agents, idx, strict=True):
            self._angles[n] = np.asarray(out[i].joint_angles_deg, float)
        return out

    def _info(self, name: str, goal: str | None, terms: dict[str, float]) -> dict[str, Any]:
        g = self.game.world.game
        side = self._side[name]
        score = (g.score_left, g.score_right) if side == "left" else (g.score_right, g.score_left)
        return {"play_mode": g.play_mode, "score": score, "goal": goal, "reward_terms": terms}

    def render(self) -> np.ndarray | None:
        """With ``render_mode="rgb_array"``: an RGB image ``(height, width, 3)`` of the game now,
        from the side, following the ball (MuJoCo's renderer over a scene posed like the world,
        whatever its engine; needs an OpenGL context, e.g. ``MUJOCO_GL=egl``); else ``None``."""
        if self.render_mode is None:
            return None
        from robocup_gym.sim.render import FollowCamera, ScenePoser

        world = self.game.world
        if self._scene is None:
            types = [0] * len(self.game.players)
            for p, t in zip(self.game.players, self.game.robot_types, strict=True):
                types[p.index] = t
            self._scene = ScenePoser(types)
            self._paint_teams(self._scene.scene)
            self._camera = FollowCamera(distance=9.0, elevation=-35.0, azimuth=90.0, follow="ball")
        return self._camera.render(self._scene.pose(world), *self.render_size)

    def _paint_teams(self, scene: Any) -> None:
        """The right team's robots drawn red (the left's keep their colours)."""
        m = scene.model
        roots = {
            int(m.body_rootid[scene.robots[p.index].torso_body])
            for p in self.game.players
            if p.side == "right"
        }
        for g in range(m.ngeom):
            if int(m.body_rootid[m.geom_bodyid[g]]) in roots:
                r, gr, b, a = (float(v) for v in m.geom_rgba[g])
                grey = (r + gr + b) / 3.0
                m.geom_rgba[g] = (min(1.0, 0.45 + grey), 0.6 * grey, 0.6 * grey, a)

    def close(self) -> None:
        if self._camera is not None:
            self._camera.close()
            self._camera = None
        self.game.close()

    def __enter__(self) -> SoccerParallelEnv:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def state(self) -> np.ndarray:
        """The global state: ball position and velocity, then each player's torso position, in
        the world frame."""
        w = self.game.world
        parts = [w.ball_position(), w.ball_velocity()]
        parts += [w.torso_position(p.index) for p in self.game.players]
        return np.concatenate(parts).astype(np.float32)


def scenario_env(cls: type, scenario: str, options: dict[str, Any]):
    """The parallel environment of ``scenario``: ``cls`` for the Nao (``robot`` absent or
    ``"nao"``), RCSSServerMJ's game (:class:`robocup_gym.soccer.league.LeagueSoccerEnv`) for
    a league robot (``robot="T1"``, ``"K1"``)."""
    options = dict(options)
    robot = options.pop("robot", "nao")
    if str(robot).lower() == "nao":
        return cls(**options)
    from robocup_gym.soccer.league import LeagueSoccerEnv

    return LeagueSoccerEnv(scenario, robot=robot, **options)


def scenario_functions(cls: type, scenario: str):
    """A scenario module's ``parallel_env``, ``raw_env`` and ``env`` (PettingZoo's names) for
    the Nao's environment class ``cls`` (:func:`scenario_env` picks the league's for a league
    robot)."""

    def parallel_env(**options: Any):
        """The scenario's Parallel environment; ``robot="T1"`` or ``"K1"`` plays it on the
        league's simulator (:mod:`robocup_gym.soccer.league`)."""
        return scenario_env(cls, scenario, options)

    def raw_env(**options: Any):
        """The scenario's AEC environment (PettingZoo's conversion of :func:`parallel_env`)."""
        return aec_from_parallel(parallel_env(**options))

    return parallel_env, raw_env, raw_env


def aec_from_parallel(parallel: SoccerParallelEnv):
    """The AEC form of a soccer environment (PettingZoo's own conversion and checks, and each
    action checked at its agent's own step: :class:`ActionsChecked`)."""
    env = parallel_to_aec(parallel)
    env = ActionsChecked(env, parallel)
    env = wrappers.OrderEnforcingWrapper(env)
    return env


class ActionsChecked(wrappers.BaseWrapper):
    """Checks an agent's action at the agent's own step of an AEC soccer environment
    (:meth:`SoccerParallelEnv.check_action`). PettingZoo's conversion keeps the actions until
    the last agent of a cycle acts: a bad action would fail only there, named by that agent's
    step, and stay kept, failing every step after. Refused here, it is never kept: the agent
    acts again."""

    def __init__(self, env, parallel: SoccerParallelEnv) -> None:
        super().__init__(env)
        self._parallel = parallel

    def step(self, action: Any) -> None:
        agent = self.agent_selection
        if not (self.terminations.get(agent) or self.truncations.get(agent)):
            self._parallel.check_action(agent, action)
        self.env.step(action)


def teams_of(config: SoccerConfig) -> dict[str, list[str]]:
    """Agent names per side."""
    return {
        side: [f"{side}_{k + 1}" for k in range(len(types))]
        for side, types in zip(SIDES, (config.left_types, config.right_types), strict=True)
    }


RANDOM_START_MARGIN_M = (2.0, 1.0)
"""How far inside the goal lines and the side lines :func:`random_start` places players and
the ball (x, y), m."""
RANDOM_START_SPACING_M = 0.8
"""The least distance :func:`random_start` leaves between two players, and between a player
and the ball, m."""


def random_start(agents: Sequence[str], rng: np.random.Generator) -> Start:
    """Every agent and the ball at a uniformly random place on the field (at least
    :data:`RANDOM_START_MARGIN_M` inside its lines, :data:`RANDOM_START_SPACING_M` apart),
    each agent facing a random direction, in play."""
    hx = FIELD_HALF_LENGTH - RANDOM_START_MARGIN_M[0]
    hy = FIELD_HALF_WIDTH - RANDOM_START_MARGIN_M[1]
    ball = rng.uniform((-hx, -hy), (hx, hy))
    taken = [ball]
    players = {}
    for name in agents:
        while True:
            xy = rng.uniform((-hx, -hy), (hx, hy))
            if all(float(np.hypot(*(xy - t))) >= RANDOM_START_SPACING_M for t in taken):
                break
        taken.append(xy)
        players[name] = (float(xy[0]), float(xy[1]), float(rng.uniform(-180.0, 180.0)))
    return Start(players=players, ball=(float(ball[0]), float(ball[1])), play_mode="PlayOn")

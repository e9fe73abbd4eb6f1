"""BaseEnv: the Gymnasium environment every RoboCup Gym task derives from.

One environment step is one 20 ms agent cycle of one learning robot: the action becomes joint
velocity commands, the backend (the embedded MuJoCo world by default) advances one cycle, and the
robot's perception becomes the observation. Tasks override :meth:`BaseEnv._get_reward` (and, if
they want, :meth:`~BaseEnv._is_terminated`, :meth:`~BaseEnv._is_truncated` and
:meth:`~BaseEnv._initial_state`)::

    class KickLeft(BaseEnv):
        def _get_reward(self, action):
            if not self.has_completed:          # reward only once, at the end
                return 0.0
            return float(self.ball_pos[1] - self.ball_spawn_pos[1])
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.envs.registration import EnvSpec

from robocup_gym.backends import (
    Backend,
    BackendDivergedError,
    RobotPose,
    make_backend,
    resolve_backend,
)
from robocup_gym.envs.actions import ActionMapper, PDActionMapper
from robocup_gym.envs.config import (
    ON_FIELD_X_M,
    ON_FIELD_Y_M,
    ActionMode,
    EnvConfig,
    EnvConfigError,
    Normalisation,
    check_joint_ranges,
    resolve_angles,
    resolve_joints,
    robot_model,
)
from robocup_gym.envs.observations import (
    COMPONENTS,
    ObservationContext,
    heading_frame,
    up_z,
)
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.types import AgentCommand, GroundTruth, Perception, float_array

__all__ = ["BaseEnv", "EpisodeStart", "reset_numbers"]

_RESET_OPTIONS = frozenset(
    {"robot_pos", "robot_heading_deg", "joint_angles_deg", "ball_pos", "ball_vel", "kick_target"}
)


@dataclass
class EpisodeStart:
    """The start state of one episode (what :meth:`BaseEnv._initial_state` returns)."""

    pose: RobotPose
    """Robot placement and joint angles (deg, canonical order)."""
    ball_pos: np.ndarray
    """Ball centre (x, y, z), m, world frame."""
    ball_vel: np.ndarray
    """Ball velocity, m/s, world frame."""
    kick_target: np.ndarray
    """(distance m, angle deg) for the ``kick_target`` observation."""
    settle_cycles: int = 0
    """Cycles the placed robot spends still (every joint velocity 0) before the episode's
    first observation, e.g. to come to rest after a drop (``Backend.reset_episode``)."""


FALL_HEIGHT_FRACTION = 0.65
"""A league robot has fallen below this fraction of its standing torso height (the Nao's
default ``fall_height`` 0.25 m is 0.65 of its 0.384 m)."""


def _fallen_from_accel(acc: np.ndarray) -> bool:
    """The paper's accelerometer fall test (used when the backend has no ground truth)."""
    ax, ay, az = float(acc[0]), float(acc[1]), float(acc[2])
    if (abs(ax) > az or abs(ay) > az) and az < 5:
        return (ay < -6.5 and az < 3) or (ay > 7.5 and az < 3) or abs(ax) > 6.5
    return False


class BaseEnv(gym.Env[np.ndarray, np.ndarray]):
    """A Gymnasium environment for one learning Nao, configured by an :class:`EnvConfig`.

    Args:
        config: The configuration; ``None`` = :meth:`default_config` of the class.
        engine: Physics engine of the in-process world: ``"ode"`` (SimSpark's own step, exact;
            the default) or ``"mujoco"`` (the fast approximation).
        backend: Instead of ``engine``: a simulator name (``"ode"``, ``"mujoco"``,
            ``"rcssserver3d"`` for a real server) or a ready
            :class:`~robocup_gym.backends.Backend` instance (its robot type must match).
        render_mode: ``None`` or ``"rgb_array"`` (drawn by MuJoCo on either engine; needs
            OpenGL, e.g. ``MUJOCO_GL=egl``).
        render_size: ``(width, height)`` of rendered images, pixels.
        **overrides: Any :class:`EnvConfig` field (or task field), applied on top of ``config``.

    Observation: ``Box(-obs_clip, obs_clip, (frame_stack · Σ component sizes,), float32)``; the
    layout is in :attr:`observation_labels`. Action: ``Box(-1, 1, (n,), float32)`` with one value
    per controlled joint (two for ``"target_angle_max_speed"``); see :attr:`action_labels`.

    Attributes available to tasks (all refreshed every step):
        perception: the latest :class:`~robocup_gym.types.Perception`;
        ground_truth: its :class:`~robocup_gym.types.GroundTruth` (``None`` if the backend has
            none);
        ball_pos / ball_vel: ball centre (m) / velocity (m/s), world frame;
        ball_spawn_pos: where the ball started this episode (after spawn noise);
        torso_pos: torso centre (m); fallen: whether the robot has fallen;
        episode_step: steps taken in this episode; has_completed: True from the moment the
        episode ended (during the final :meth:`_get_reward` call).
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 50}
    config_class: ClassVar[type[EnvConfig]] = EnvConfig
    task_reset_options: ClassVar[frozenset[str]] = frozenset()
    """Reset options a task adds to the common ones (it reads them in :meth:`_initial_state`)."""
    _closed = False
    """Config type of this environment (tasks use a subclass with their reward options)."""

    @classmethod
    def default_config(cls, robot: str = "nao") -> EnvConfig:
        """The configuration used when none is given, for ``robot`` (``"nao"`` or a league
        robot such as ``"T1"``: the task's defaults with :meth:`league_defaults` applied)."""
        config = cls.config_class()
        if robot == "nao":
            return config
        return config.replace(robot=robot, **cls.league_defaults(robot))

    @classmethod
    def league_defaults(cls, robot: str) -> dict[str, Any]:
        """The options that differ on a league robot (RCSSServerMJ) from the task's Nao
        defaults, derived from the robot's model (tasks extend this):

        ==================  ===================================================================
        option              on a league robot
        ==================  ===================================================================
        ``action_mode``     ``"target_angle"`` (PD targets with default gains)
        ``observations``    the task's, without foot and toe pressure (the robots have no FRP)
        ``fall_height``     0.65 × the robot's standing torso height (as 0.25 m is the Nao's)
        ``ball_start_pos``  0.2 m + ball radius ahead of the right foot, resting on the ground
        ``joint_start_deg`` every joint at 0 (the T1 and K1 stand upright there), or the
                            nearest angle in range for a joint whose range excludes 0
        ==================  ===================================================================
        """
        from robocup_gym.envs.config import league_robot_of

        base = cls.config_class()
        r = league_robot_of(robot)
        x, y = base.robot_start_pos
        fwd, left = r.right_foot_offset
        return {
            "action_mode": ActionMode.TARGET_ANGLE,
            "observations": tuple(
                o for o in base.observations if o not in ("foot_force", "toe_force")
            ),
            "fall_height": round(FALL_HEIGHT_FRACTION * r.standing_torso_height, 3),
            "ball_start_pos": (x + fwd + 0.2 + r.ball_radius, y + left, r.ball_radius),
            # all 0, or the nearest angle in range for a joint whose range excludes 0
            "joint_start_deg": {
                n: float(np.clip(0.0, lo, hi))
                for n, (lo, hi) in zip(r.effector_names, r.ranges_deg, strict=True)
                if not lo <= 0.0 <= hi
            }
            or None,
        }

    # ================================================================== construction
    def __init__(
        self,
        config: EnvConfig | None = None,
        *,
        backend: str | Backend | None = None,
        engine: str | None = None,
        render_mode: str | None = None,
        render_size: tuple[int, int] = (480, 360),
        **overrides: Any,
    ) -> None:
        super().__init__()
        config = self._coerce_config(config, overrides)
        self.config = config
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise EnvConfigError(
                f"render_mode must be None or one of {self.metadata['render_modes']}, "
                f"got {render_mode!r}"
            )
        self.render_mode = render_mode
        self.render_size = (int(render_size[0]), int(render_size[1]))

        model = robot_model(config)
        self.league = config.robot != "nao"
        """Whether the robot is one of the league's (RCSSServerMJ, PD joints)."""
        comps = self._components(model)
        ctrl, obs_joints = self._joints(model)
        self._attach_backend(backend, engine, comps)
        n_act = self._build_actions(model, ctrl)
        self._build_observations(model, comps, obs_joints, n_act)
        self._start_state(n_act)

    # ------------------------------------------------------------------ construction steps
    def _components(self, model) -> list:
        """The configured observation components, checked against the robot (before any
        backend is started)."""
        config = self.config
        unknown = [n for n in config.observations if n not in COMPONENTS]
        if unknown:
            raise EnvConfigError(
                f"unknown observation component(s) {', '.join(map(repr, unknown))}; valid: "
                f"{', '.join(COMPONENTS)}"
            )
        comps = [COMPONENTS[n] for n in config.observations]
        for c in comps:
            if self.league and c.name in ("foot_force", "toe_force"):
                raise EnvConfigError(
                    f"observation {c.name!r} reads the Nao's foot pressure perceptors (FRP); the "
                    f"{config.robot} has none"
                )
            if c.needs_toes and not self.league and not model.robot_type.has_toes:
                raise EnvConfigError(
                    f"observation {c.name!r} needs the toes of robot type 4, "
                    f"got robot_type={config.robot_type}"
                )
        return comps

    def _joints(self, model) -> tuple[np.ndarray, np.ndarray]:
        """The controlled and observed joints, and the start pose's angles and noise."""
        config = self.config
        if config.controlled_joints is None:
            ctrl = np.array(
                [i for i, n in enumerate(model.effector_names) if not n.startswith("he")],
                dtype=int,
            )
        else:
            ctrl = resolve_joints(model, config.controlled_joints, "controlled_joints")
            if len(ctrl) == 0:
                raise EnvConfigError("controlled_joints must name at least one joint")
        obs_joints = (
            ctrl
            if config.observed_joints is None
            else resolve_joints(model, config.observed_joints, "observed_joints")
        )
        self._start_angles = resolve_angles(model, config.joint_start_deg, "joint_start_deg")
        if isinstance(config.joint_start_noise_deg, Mapping):
            self._start_noise = resolve_angles(
                model, config.joint_start_noise_deg, "joint_start_noise_deg"
            )
        else:
            self._start_noise = np.full(len(model.joints), float(config.joint_start_noise_deg))
        if (self._start_noise < 0).any() or not np.isfinite(self._start_noise).all():
            raise EnvConfigError("joint_start_noise_deg must be finite and >= 0")
        self._ranges = model.ranges_deg.astype(float)
        return ctrl, obs_joints

    def _attach_backend(self, backend: str | Backend | None, engine: str | None, comps) -> None:
        """The given backend (checked against the config) or a new one of the named kind."""
        config = self.config
        needs_vision = any(c.needs_vision for c in comps)
        if isinstance(backend, Backend):
            if engine is not None and engine != backend.name:
                raise EnvConfigError(f"engine={engine!r} but the given backend is {backend.name!r}")
            self.backend = backend
            given = getattr(backend, "robot", "nao")
            if given != config.robot:
                raise EnvConfigError(f"backend robot {given!r} != config robot {config.robot!r}")
            if backend.robot_type != config.robot_type:
                raise EnvConfigError(
                    f"backend robot_type {backend.robot_type} != config robot_type "
                    f"{config.robot_type}"
                )
        elif backend is None or isinstance(backend, str):
            name = resolve_backend(backend, engine, config.robot)
            self.backend = make_backend(name, **self.backend_kwargs(needs_vision))
        else:
            raise EnvConfigError(
                f"backend must be a name or a Backend, got {type(backend).__name__}"
            )
        self._owns_backend = not isinstance(backend, Backend)
        world = getattr(self.backend, "world", None)
        if hasattr(world, "self_collision_rule"):  # an in-process world (a server has its own)
            world.self_collision_rule = bool(config.self_collisions)
        self.robot_model = self.backend.robot_model
        needs_gt = [c.name for c in comps if c.needs_ground_truth]
        if needs_gt and not self.backend.has_ground_truth:
            raise EnvConfigError(
                f"observation(s) {needs_gt} need ground truth, which the "
                f"{self.backend.name!r} backend does not provide"
            )

    def _build_actions(self, model, ctrl: np.ndarray) -> int:
        """The action mapper and space; returns the action size."""
        config = self.config
        spread = config.target_around_start_deg
        around = None if spread is None else self._start_angles
        if self.league:
            self._actions = PDActionMapper(
                model,
                ctrl,
                config.action_mode,
                config.pd_saturation_deg,
                config.pd_damping_s,
                around_deg=around,
                spread_deg=spread,
            )
        else:
            self._actions = ActionMapper(
                model,
                ctrl,
                config.action_mode,
                config.target_gain,
                bool(config.mirror_actions),
                around_deg=around,
                spread_deg=spread,
                stop_margin_deg=float(config.target_stop_margin_deg),
            )
        n_act = self._actions.size
        self.action_space = gym.spaces.Box(-1.0, 1.0, (n_act,), dtype=np.float32)
        self.action_labels: list[str] = self._actions.labels()
        return n_act

    def _build_observations(self, model, comps, obs_joints: np.ndarray, n_act: int) -> None:
        """The observation frame's writers, slices, bounds, normalisation and space."""
        config = self.config
        ctx = ObservationContext(model, obs_joints, n_act, int(config.max_episode_steps))
        self._obs_joints = obs_joints
        los, his, labels, sizes = [], [], [], []
        for c in comps:
            lo, hi = c.bounds(ctx)
            los.append(lo)
            his.append(hi)
            labels += c.labels(ctx)
            sizes.append(len(lo))
        lo, hi = np.concatenate(los), np.concatenate(his)
        self.frame_size = int(lo.size)
        self._frame = np.zeros(self.frame_size)
        self._writers = []
        start = 0
        for c, size in zip(comps, sizes, strict=True):
            self._writers.append((c.write, self._frame[start : start + size]))
            start += size
        self.component_slices: dict[str, slice] = {}
        start = 0
        for c, size in zip(comps, sizes, strict=True):
            self.component_slices[c.name] = slice(start, start + size)
            start += size
        self.raw_bounds = (lo, hi)
        """Analytic range of each raw frame value (what min–max normalisation maps)."""
        norm = config.normalise
        if norm is Normalisation.NONE:
            self._scale, self._offset = None, None
        else:
            a, b = (-1.0, 1.0) if norm is Normalisation.MIN_MAX else (0.0, 1.0)
            self._scale = (b - a) / (hi - lo)
            self._offset = a - lo * self._scale
        clip = config.obs_clip
        self._clip = None if clip is None or clip == math.inf else float(clip)
        k = int(config.frame_stack)
        self._obs = np.zeros(k * self.frame_size)
        bound = np.inf if self._clip is None else self._clip
        self.observation_space = gym.spaces.Box(
            -bound, bound, (k * self.frame_size,), dtype=np.float32
        )
        self.observation_labels: list[str] = (
            labels if k == 1 else [f"{lab}@t-{k - 1 - i}" for i in range(k) for lab in labels]
        )

    def _start_state(self, n_act: int) -> None:
        """What an environment holds between and within episodes, before its first reset."""
        config = self.config
        self._obs_noise = float(config.observation_noise_std)
        self._act_noise = float(config.action_noise_std)
        self._last_action = np.zeros(n_act)
        self._acted = self._last_action.copy()
        """The action of the command :meth:`act` made last (clipped, noise included)."""
        self.rewarded = True
        """Compute rewards (a task run as a skill, whose reward nobody reads, turns this off)."""
        self.reward_terms: dict[str, float] = {}
        """The last step's reward by term (:meth:`_reward_terms`)."""
        self._vision_ball = np.zeros(4)
        self._needs_heading = bool(
            {"ball_rel", "ball_vel", "target_rel"} & set(config.observations)
        )
        self._heading = (1.0, 0.0)
        self._started = False
        self.perception: Perception | None = None
        self.ground_truth: GroundTruth | None = None
        self.has_completed = False
        self.episode_step = 0
        self.fallen = False
        self.ball_spawn_pos = config.ball_start.copy()
        self.kick_target = np.array(config.kick_target, dtype=float)
        self.target_pos = np.zeros(2)
        """A point a task asks for, world (x, y) m (the ``target_rel`` observation); the origin
        unless the task sets it."""
        self.velocity_command = np.zeros(3)
        """The planar velocity a task commands (forward m/s, left m/s, turn deg/s); zeros unless
        the task sets it."""
        self.policy_command = self.velocity_command
        """The planar velocity the policy is told (the ``velocity_command`` observation):
        ``velocity_command`` itself unless the task closes a loop around it (Walk's
        ``command_feedback_gain``)."""
        self.gait_clock = (0.0, 0.0)
        """The task's gait clock (phase at the episode's start in [0, 1), frequency in Hz): the
        ``gait_phase`` observation; (0, 0) unless the task sets it."""
        self.episode_start: EpisodeStart | None = None
        self.diverged_episodes = 0
        """Episodes ended early because the simulation diverged."""

    def backend_kwargs(self, vision: bool = False) -> dict[str, Any]:
        """The keyword arguments that make a backend for this environment's robot (with the
        config's ``backend_options``)."""
        c = self.config
        robot = {"robot": c.robot} if c.robot != "nao" else {}
        return {"robot_type": c.robot_type, "vision": vision, **robot, **dict(c.backend_options)}

    def _coerce_config(self, config: EnvConfig | None, overrides: Mapping[str, Any]) -> EnvConfig:
        cls = self.config_class
        robot = overrides.get("robot", getattr(config, "robot", "nao"))
        if robot != "nao" and isinstance(robot, str):
            # the options left at their Nao defaults take the league robot's (given overrides
            # and changed options win)
            nao = cls()
            given = config if isinstance(config, EnvConfig) else nao
            league = {
                k: v
                for k, v in self.league_defaults(robot).items()
                if k not in overrides and getattr(given, k, None) == getattr(nao, k)
            }
            overrides = {**league, **overrides}
        if config is None:
            config = cls()
        elif not isinstance(config, EnvConfig):
            raise EnvConfigError(
                f"config must be an EnvConfig ({cls.__name__} for {type(self).__name__}), "
                f"got {type(config).__name__}"
            )
        elif not isinstance(config, cls):
            # a plain EnvConfig given to a task: keep its values, add the task's defaults
            base = {f: getattr(config, f) for f in config.__dataclass_fields__}
            config = cls(**base)
        if overrides:
            config = config.replace(**overrides)
        return config

    # ================================================================== gymnasium API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode (instantly: the robot and ball are teleported, no warm-up cycles).

        Args:
            seed: Seeds the environment's random generator (start noise, observation and action
                noise) and the backend's (vision noise); a seeded reset is reproducible.
            options: Per-episode overrides of the start state: ``robot_pos`` (x, y),
                ``robot_heading_deg``, ``joint_angles_deg`` (by name or canonical array),
                ``ball_pos`` (x, y[, z]), ``ball_vel`` (x, y, z), ``kick_target`` (m, deg).
        """
        self._refuse_if_closed("reset")
        super().reset(seed=seed)
        if options is not None and not isinstance(options, Mapping):
            raise ValueError(f"reset options must map option names to values, got {options!r}")
        options = dict(options or {})
        valid = _RESET_OPTIONS | self.task_reset_options
        bad = sorted(set(options) - valid)
        if bad:
            raise ValueError(f"unknown reset option(s) {bad}; valid: {', '.join(sorted(valid))}")
        self.reward_terms = {}
        start = self._initial_state(options)
        backend_seed = int(self.np_random.integers(2**31 - 1)) if seed is not None else None
        p = self.backend.reset_episode(
            start.pose,
            start.ball_pos,
            start.ball_vel,
            play_mode=self.config.play_mode,
            seed=backend_seed,
            settle_cycles=start.settle_cycles,
        )
        self.episode_start = start
        self.ball_spawn_pos = np.array(start.ball_pos, dtype=float)
        self.kick_target = np.asarray(start.kick_target, dtype=float)
        self.episode_step = 0
        self.has_completed = False
        self._started = True
        self._last_action[:] = 0.0
        self._vision_ball[:] = 0.0
        self._q = np.asarray(p.joint_angles_deg, dtype=float)
        self._qdot = np.zeros_like(self._q)
        self._actions.start_episode(self._q)
        self._set_perception(p)
        self._build_frame()
        k = int(self.config.frame_stack)
        self._obs[:] = np.tile(self._frame, k)
        return self._obs.astype(np.float32), self._info()

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """One 20 ms agent cycle. On the last step of an episode the world first runs
        ``wait_steps`` more cycles with zero joint velocities, then the final reward is computed
        (the returned observation is the one from before the wait, as in the paper; ``info``,
        ``fallen`` included, describes the world after the wait, as the reward does)."""
        command = self.act(action)
        try:
            p = self.backend.step(command)
        except BackendDivergedError as e:
            return self._diverged(e)
        return self.observe_step(p)

    def act(self, action: Any) -> AgentCommand:
        """The first half of :meth:`step`: the joint command of ``action`` (checked, noised and
        clipped as a step does), without running a cycle. With :meth:`observe_step` this lets
        a caller step the world itself, e.g. a game running many players' skills at once.

        Raises:
            RuntimeError: before :meth:`reset`, or after the episode ended.
            ValueError: a bad action (its shape or a value that is not finite, named).
        """
        self._refuse_if_closed("step")
        if not self._started:
            raise RuntimeError("call reset() before step()")
        if self.has_completed:
            raise RuntimeError("the episode is over (terminated or truncated); call reset()")
        a = self._check_action(action)
        self._before_action()
        if self._act_noise:
            a = a + self.np_random.normal(0.0, self._act_noise, a.shape)
        np.minimum(a, 1.0, out=a)  # clip to [-1, 1] (cheaper than np.clip on small arrays)
        np.maximum(a, -1.0, out=a)
        self._acted = a
        return self._actions.agent_command(a, self._q)

    def observe_step(self, p: Perception) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """The second half of :meth:`step`: the cycle's perception ``p`` (after the command of
        :meth:`act`) made into the step's observation, reward, end flags and info."""
        a = self._acted
        self._last_action[:] = a
        self.episode_step += 1
        self._set_perception(p)
        obs = self._build_frame_and_stack()
        terminated = bool(self._is_terminated())
        truncated = bool(self._is_truncated())
        cycles = 1
        if terminated or truncated:
            self.has_completed = True
            n = int(self.config.wait_steps)
            if n > 0:
                try:
                    p = self.backend.advance(n, self._actions.stop_command(self._q))
                except BackendDivergedError as e:
                    return self._diverged(e, terminated=terminated)
                self._set_perception(p, cycles=n, episode_over=True)
                cycles += n
        reward = float(self._get_reward(a)) if self.rewarded else 0.0
        info = self._info()
        info["cycles"] = cycles
        return obs, reward, terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """An RGB image ``(height, width, 3)`` when ``render_mode="rgb_array"``, else ``None``."""
        if self.render_mode is None:
            gym.logger.warn("render() called without render_mode; pass render_mode='rgb_array'")
            return None
        return self.backend.render(*self.render_size)

    def close(self) -> None:
        """Release the backend (if this environment created it); the environment then refuses
        :meth:`reset` and :meth:`step`. Closing twice is harmless."""
        self._closed = True
        backend = getattr(self, "backend", None)
        if backend is not None and getattr(self, "_owns_backend", False):
            backend.close()

    def _refuse_if_closed(self, what: str) -> None:
        if self._closed:
            raise RuntimeError(f"{what}() on a closed environment; make a new one")

    # ================================================================== overridables
    def _before_action(self) -> None:
        """Called before each action becomes a command (tasks with a reference motion set its
        targets for the step here)."""

    def _get_reward(self, action: np.ndarray) -> float:
        """The reward of the step just taken: the sum of the task's named terms
        (:meth:`_reward_terms`, in their order), which are kept in :attr:`reward_terms` and
        given in ``info["reward_terms"]`` (the trainer logs each term's episode sum)."""
        terms = self._reward_terms(action)
        self.reward_terms = terms
        return float(sum(terms.values()))

    def _reward_terms(self, action: np.ndarray) -> dict[str, float]:
        """The reward of the step just taken, as named terms (weights applied, a penalty
        negative); tasks override this.

        Called once per step, after the episode-end bookkeeping: on the final step
        :attr:`has_completed` is True and the world has already run ``wait_steps`` more cycles.

        Args:
            action: The action as applied (clipped to [-1, 1], noise included).
        """
        return {}

    def _is_terminated(self) -> bool:
        """True when the episode ends for a task reason (default: the robot has fallen and
        ``terminate_on_fall``)."""
        return self.config.terminate_on_fall and self.fallen

    def _is_truncated(self) -> bool:
        """True when the episode is cut off (default: ``max_episode_steps`` reached)."""
        return self.episode_step >= self.config.max_episode_steps

    def _initial_state(self, options: Mapping[str, Any]) -> EpisodeStart:
        """The start state of the next episode: config values plus the configured noise (drawn
        from :attr:`np_random`), then ``reset(options=...)`` overrides."""
        cfg = self.config
        rng = self.np_random
        angles = self._start_angles.copy()
        if self._start_noise.any():
            angles += rng.normal(0.0, 1.0, angles.shape) * self._start_noise
            np.clip(angles, self._ranges[:, 0], self._ranges[:, 1], out=angles)
        ball = cfg.ball_start.copy()
        if cfg.ball_spawn_noise > 0:
            th = rng.uniform(0.0, 2.0 * math.pi)
            ball[0] += cfg.ball_spawn_noise * math.cos(th)
            ball[1] += cfg.ball_spawn_noise * math.sin(th)
        target = np.array(cfg.kick_target, dtype=float)
        if cfg.randomise_kick_target:
            target = np.array(
                [
                    rng.uniform(*cfg.kick_target_distance_range),
                    rng.uniform(*cfg.kick_target_angle_range),
                ]
            )
        x, y = cfg.robot_start_pos
        heading = cfg.robot_start_heading_deg
        ball_vel = np.array(cfg.ball_start_vel, dtype=float)
        if "robot_pos" in options:
            x, y = reset_numbers(options, "robot_pos", (2,), "be (x, y) in m").tolist()
        if "robot_heading_deg" in options:
            what = "be a number of degrees"
            (heading,) = reset_numbers(options, "robot_heading_deg", (1,), what).tolist()
        if "joint_angles_deg" in options:
            given = options["joint_angles_deg"]
            if isinstance(given, Mapping):
                angles = resolve_angles(self.robot_model, given, "joint_angles_deg")
            else:
                n = len(self.robot_model.joints)
                angles = reset_numbers(options, "joint_angles_deg", (n,), f"have shape ({n},)")
        if "ball_pos" in options:
            b = reset_numbers(options, "ball_pos", (2, 3), "be (x, y) or (x, y, z) in m")
            ball = np.array([b[0], b[1], cfg.ball_start[2]]) if len(b) == 2 else b
        if "ball_vel" in options:
            ball_vel = reset_numbers(options, "ball_vel", (3,), "be (x, y, z) in m/s")
        if "kick_target" in options:
            target = reset_numbers(options, "kick_target", (2,), "be (distance m, direction deg)")
        self._check_start(x, y, heading, angles, ball, ball_vel, target)
        return EpisodeStart(
            pose=RobotPose(x=x, y=y, heading_deg=heading, joint_angles_deg=angles),
            ball_pos=ball,
            ball_vel=ball_vel,
            kick_target=target,
        )

    def _check_start(self, x, y, heading, angles, ball, ball_vel, target) -> None:
        """Refuse a start state the world cannot take (reset options are checked here as the
        config's values are in :meth:`EnvConfig.validate`)."""
        values = {
            "robot_pos": (x, y),
            "robot_heading_deg": (heading,),
            "ball_pos": tuple(ball),
            "ball_vel": tuple(ball_vel),
            "kick_target": tuple(target),
        }
        for name, v in values.items():
            if not all(math.isfinite(float(c)) for c in v):
                raise ValueError(f"reset option {name} must be finite numbers, got {v}")
        for name, (px, py) in (("robot_pos", (x, y)), ("ball_pos", (ball[0], ball[1]))):
            if abs(px) > ON_FIELD_X_M or abs(py) > ON_FIELD_Y_M:
                raise ValueError(
                    f"reset option {name} ({px:g}, {py:g}) is off the field: x must be within "
                    f"±{ON_FIELD_X_M:g} m and y within ±{ON_FIELD_Y_M:g} m"
                )
        if not np.isfinite(angles).all():
            raise ValueError("reset option joint_angles_deg must be finite (deg)")
        check_joint_ranges(self.robot_model, angles, "joint_angles_deg")

    # ================================================================== registration
    @property
    def spec(self) -> EnvSpec | None:  # type: ignore[override]
        """The registration this environment was made from (set by ``gymnasium.make``), with
        ``nondeterministic`` true where the backend is a real server, which does not repeat an
        episode exactly (:attr:`Backend.deterministic`)."""
        spec = self.__dict__.get("_spec")
        backend = self.__dict__.get("backend")
        if spec is not None and backend is not None and not backend.deterministic:
            return dataclasses.replace(spec, nondeterministic=True)
        return spec

    @spec.setter
    def spec(self, value: EnvSpec | None) -> None:
        self.__dict__["_spec"] = value

    # ================================================================== state for tasks
    @property
    def ball_pos(self) -> np.ndarray:
        """Ball centre (m, world frame) now (ground truth)."""
        return self._gt_or_raise().ball_pos

    @property
    def ball_vel(self) -> np.ndarray:
        """Ball velocity (m/s, world frame) now (ground truth)."""
        return self._gt_or_raise().ball_vel

    @property
    def torso_pos(self) -> np.ndarray:
        """Torso centre (m, world frame) now (ground truth)."""
        return self._gt_or_raise().torso_pos

    @property
    def ball_displacement(self) -> np.ndarray:
        """Ball position minus its spawn position this episode, m."""
        return self.ball_pos - self.ball_spawn_pos

    @property
    def joint_angles_deg(self) -> np.ndarray:
        """Perceived joint angles now, degrees, canonical order."""
        return self._q

    @property
    def joint_velocities(self) -> np.ndarray:
        """Joint velocities over the last cycle, rad/s, canonical order."""
        return self._qdot

    def _gt_or_raise(self) -> GroundTruth:
        gt = self.ground_truth
        if gt is None:
            if self.perception is None:
                raise RuntimeError("no perception yet; call reset()")
            raise RuntimeError(f"the {self.backend.name!r} backend provides no ground truth")
        return gt

    # ================================================================== internals
    def _check_action(self, action: Any) -> np.ndarray:
        try:
            a = np.array(action, dtype=np.float64)
        except (TypeError, ValueError) as e:
            raise ValueError(f"action must be an array of numbers, got {action!r}") from e
        shape = self.action_space.shape
        if a.shape != shape:
            raise ValueError(
                f"action must have shape {shape} (action_mode={self.config.action_mode.value!r}, "
                f"{self._actions.n_joints} controlled joints: "
                f"{', '.join(self.action_labels)}); got shape {a.shape}"
            )
        if not np.isfinite(a).all():
            i = int(np.argmax(~np.isfinite(a)))
            raise ValueError(
                f"action contains {a[i]} at index {i} ({self.action_labels[i]}); actions must be "
                "finite numbers in [-1, 1]"
            )
        return a

    def _set_perception(self, p: Perception, cycles: int = 1, episode_over: bool = False) -> None:
        q = np.asarray(p.joint_angles_deg, dtype=float)
        if p.joint_velocities_deg_s is not None:  # sent by the simulator (RCSSServerMJ)
            self._qdot = np.radians(p.joint_velocities_deg_s)
        else:
            self._qdot = np.radians(q - self._q) * (1.0 / (CYCLE_S * cycles))
        self._q = q
        self.perception = p
        gt = p.ground_truth
        self.ground_truth = gt
        if gt is not None:
            cfg = self.config
            self.fallen = bool(
                up_z(gt.torso_quat) < cfg.fall_up_z or gt.torso_pos[2] < cfg.fall_height
            )
            if self._needs_heading:
                self._heading = heading_frame(gt.torso_quat)
        else:
            self.fallen = _fallen_from_accel(p.accel)
        if p.vision is not None:
            ball = p.vision.ball
            if ball is None:
                self._vision_ball[3] = 0.0
            else:
                self._vision_ball[:3] = ball
                self._vision_ball[3] = 1.0

    def _build_frame(self) -> None:
        for write, out in self._writers:
            write(self, out)
        f = self._frame
        if self._scale is not None:
            f *= self._scale
            f += self._offset
        if self._obs_noise:
            f += self.np_random.normal(0.0, self._obs_noise, f.shape)
        if self._clip is not None:
            np.minimum(f, self._clip, out=f)
            np.maximum(f, -self._clip, out=f)

    def _build_frame_and_stack(self) -> np.ndarray:
        self._build_frame()
        n = self.frame_size
        obs = self._obs
        if len(obs) > n:
            obs[:-n] = obs[n:]
        obs[-n:] = self._frame
        return obs.astype(np.float32)

    def _diverged(
        self, error: Exception, terminated: bool = False
    ) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        self.has_completed = True
        self.diverged_episodes += 1
        if self.diverged_episodes == 1:
            warnings.warn(
                f"simulation diverged, episode truncated with reward 0 ({error}); further "
                "divergences are reported only in info['diverged']",
                RuntimeWarning,
                stacklevel=3,
            )
        info = self._info()
        info["diverged"] = True
        info["cycles"] = 0
        return self._obs.astype(np.float32), 0.0, terminated, not terminated, info

    def _info(self) -> dict[str, Any]:
        gt = self.ground_truth
        info: dict[str, Any] = {
            "step": self.episode_step,
            "fallen": self.fallen,
            "diverged": False,
        }
        if gt is not None:
            bp, bv = gt.ball_pos, gt.ball_vel
            disp = bp - self.ball_spawn_pos
            info["ball_pos"] = bp
            info["ball_vel"] = bv
            info["ball_displacement"] = disp
            info["ball_distance"] = math.sqrt(disp[0] ** 2 + disp[1] ** 2 + disp[2] ** 2)
            info["ball_speed"] = math.sqrt(bv[0] ** 2 + bv[1] ** 2 + bv[2] ** 2)
            info["torso_pos"] = gt.torso_pos
        if self.reward_terms:
            info["reward_terms"] = dict(self.reward_terms)
        return info

    @property
    def gait_phase(self) -> float:
        """The gait clock's phase now, in [0, 1) (see :attr:`gait_clock`)."""
        start, hz = self.gait_clock
        return (start + hz * CYCLE_S * self.episode_step) % 1.0

    # ================================================================== misc
    @property
    def action_mode(self) -> ActionMode:
        """The configured :class:`ActionMode`."""
        return self.config.action_mode

    @property
    def controlled_joints(self) -> tuple[str, ...]:
        """Effector names of the controlled joints, in action order."""
        return tuple(self.robot_model.effector_names[i] for i in self._actions.joints)

    @property
    def observed_joints(self) -> tuple[str, ...]:
        """Perceptor names of the joints in ``joint_pos``/``joint_vel``."""
        return tuple(self.robot_model.perceptor_names[i] for i in self._obs_joints)

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(backend={self.backend.name!r}, "
            f"robot_type={self.config.robot_type}, obs={self.observation_space.shape}, "
            f"act={self.action_space.shape}, mode={self.config.action_mode.value!r})"
        )


def reset_numbers(
    options: Mapping[str, Any],
    name: str,
    sizes: tuple[int, ...],
    what: str,
    *,
    finite: bool = False,
) -> np.ndarray:
    """Reset option ``name`` as a flat float array of one of ``sizes`` values (with
    ``finite``, each finite).

    Raises:
        ValueError: naming the option and what it must do (``what``: "be (x, y) in m"), for
            text, a value that is not numbers, another number of them, or (``finite``) one
            that is not finite.
    """
    value = options[name]
    out = float_array(value)
    if out is not None:
        out = out.reshape(-1)
    if out is None or len(out) not in sizes or (finite and not np.isfinite(out).all()):
        raise ValueError(f"{name} must {what}, got {value!r}")
    return out

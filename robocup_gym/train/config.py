"""Training configuration: one typed dataclass, written verbatim to every run folder.

The defaults are the paper's hyperparameters (Beukman et al., *RobocupGym*, 2024, and its public
training script): PPO with gamma 0.99, GAE lambda 0.95, ``n_steps`` 64 per environment, 10 epochs,
clip 0.2, Adam with learning rate 1e-4, no entropy bonus, minibatch 128, a 2×256 MLP, gSDE
exploration and a value-function clip of 1.0; SAC with Stable-Baselines3's defaults. Observation
clipping (1.0) happens inside the environment, as in the paper, so no ``VecNormalize`` is used
unless ``normalize_obs`` is switched on (it is then folded into the exported ONNX graph).
PPO's updates overlap the next rollout (``overlap_updates``, :data:`PPO_RUN_DEFAULTS`); that is
not in the paper and can be switched off.

A config file (YAML) holds any subset of the fields; nested ``algo_kwargs`` / ``env_kwargs`` are
merged over the defaults::

    algo: ppo
    n_envs: 4
    timesteps: 200000
    algo_kwargs: {learning_rate: 3.0e-4}
    env_kwargs: {episode_steps: 40}
"""

from __future__ import annotations

import copy
import functools
import os
import re
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

from robocup_gym.backends import (
    IN_PROCESS_BACKENDS,
    BackendNotAvailableError,
    available_backends,
    resolve_backend,
)
from robocup_gym.robot.types import ROBOT_TYPES, is_type_number
from robocup_gym.train.algos import ALGOS
from robocup_gym.train.tasks import is_team_task, resolve_task, with_version_options
from robocup_gym.types import check_field_kinds, reject_unknown_fields

PPO_PAPER_DEFAULTS: dict[str, Any] = {
    "learning_rate": 1e-4,
    "n_steps": 64,
    "batch_size": 128,
    "n_epochs": 10,
    "gamma": 0.99,
    "gae_lambda": 0.95,
    "clip_range": 0.2,
    "clip_range_vf": 1.0,
    "ent_coef": 0.0,
    "use_sde": True,
    # Adam as in the paper, in PyTorch's fused implementation (same update, one kernel per
    # tensor: ~12 % less time per PPO update on CPU than the default per-tensor loop)
    "policy_kwargs": {"net_arch": [256, 256], "optimizer_kwargs": {"fused": True}},
}
"""PPO as in the paper (its public ``v0001_ppo`` script)."""

PPO_RUN_DEFAULTS: dict[str, Any] = {"overlap_updates": True}
"""How our PPO runs, beyond the paper's hyperparameters: each update overlaps the next rollout,
which acts with the policy from before that update (a one-rollout policy lag;
:class:`robocup_gym.train.pipelined.PipelinedPPO`). ~25 % faster on a 2-core machine. Set
``overlap_updates: false`` for the paper's strictly alternating schedule."""

SAC_PAPER_DEFAULTS: dict[str, Any] = {}
"""SAC: Stable-Baselines3's defaults, as in the paper."""

_RESIDUAL_PPO: dict[str, Any] = {
    "learning_rate": 3e-4,
    "batch_size": 256,
    # a residual over a reference motion (the gait, the kick) wants small, plain Gaussian
    # noise: with gSDE's state-dependent noise, even at log_std_init -1.5, a fresh policy's
    # actions average 0.77 (of ±30°) and it falls within 30 steps (docs/training.md, *Walk*)
    "use_sde": False,
    "policy_kwargs": {"log_std_init": -2.0},
}

_KICK_RESIDUAL_PPO: dict[str, Any] = {
    **_RESIDUAL_PPO,
    # one reward per 60-step episode: with the paper's 64 steps a rollout and a 3e-4 step
    # size the kick over the reference collapsed into lunges within 200k steps (every episode
    # a fall); 256 steps a rollout at 1e-4 keeps it standing (docs/training.md)
    "learning_rate": 1e-4,
    "n_steps": 256,
}

_GETUP_PPO: dict[str, Any] = {
    # a residual over the scripted get-up (5° of reach): σ = e^-2 of it is 0.7°, which the
    # script (searched under 1.5° of noise) stands (docs/training.md, *Get-up*)
    "learning_rate": 3e-4,
    "batch_size": 256,
    "use_sde": False,
    "policy_kwargs": {"log_std_init": -2.0},
}

TASK_ALGO_DEFAULTS: dict[tuple[str, str], dict[str, Any]] = {
    ("RobocupGym/Walk-v0", "ppo"): _RESIDUAL_PPO,
    ("RobocupGym/Run-v0", "ppo"): _RESIDUAL_PPO,
    ("RobocupGym/Run-v1", "ppo"): _RESIDUAL_PPO,
    ("RobocupGym/Dribble-v0", "ppo"): _RESIDUAL_PPO,
    ("RobocupGym/Dribble-v1", "ppo"): _RESIDUAL_PPO,
    ("RobocupGym/TargetKick-v0", "ppo"): _KICK_RESIDUAL_PPO,
    ("RobocupGym/TargetKick-v1", "ppo"): _KICK_RESIDUAL_PPO,
    ("RobocupGym/LongKick-v0", "ppo"): _KICK_RESIDUAL_PPO,
    ("RobocupGym/LongKick-v1", "ppo"): _KICK_RESIDUAL_PPO,
    ("RobocupGym/GetUp-v0", "ppo"): _GETUP_PPO,
    ("RobocupGym/GetUp-v1", "ppo"): _GETUP_PPO,
}
"""Hyperparameters a task's reference policy was trained with where they differ from the
paper's, by (Gymnasium id, algorithm): :meth:`TrainConfig.resolved_algo_kwargs` puts them
between the paper's defaults and the run's own ``algo_kwargs``."""

TEAM_PPO_DEFAULTS: dict[str, Any] = {
    # a decision every 10 cycles (0.2 s): rollouts of 25.6 s of play per player, plain
    # Gaussian exploration over the skill actions (walk velocity, kick)
    "learning_rate": 3e-4,
    "n_steps": 128,
    "batch_size": 512,
    "use_sde": False,
    "policy_kwargs": {"log_std_init": -0.5},
}
"""PPO's hyperparameters for the team scenarios (``penalty``, ``keepaway``, ``game-NvN``),
where they differ from the paper's."""

DEFAULT_N_ENVS = 16
"""The paper's number of worker environments."""


_YAML_FLOAT = re.compile(
    r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)(?:[eE][-+]?[0-9]+)?$"
    r"|^[-+]?\.(?:inf|Inf|INF)$|^\.(?:nan|NaN|NAN)$"
)


@functools.cache
def _yaml_loader() -> type:
    import yaml

    class _Loader(yaml.SafeLoader):
        """PyYAML's safe loader with YAML 1.2's floats."""

    _Loader.yaml_implicit_resolvers = {
        k: [(tag, rx) for tag, rx in v if tag != "tag:yaml.org,2002:float"]
        for k, v in yaml.SafeLoader.yaml_implicit_resolvers.items()
    }
    _Loader.add_implicit_resolver("tag:yaml.org,2002:float", _YAML_FLOAT, list("-+0123456789."))
    return _Loader


def load_yaml(text: str) -> Any:
    """YAML as users write it: PyYAML's safe loader, except that numbers in exponent notation
    without a dot (``3e-4``, ``1e6``) are floats, as in YAML 1.2, not strings."""
    import yaml

    return yaml.load(text, Loader=_yaml_loader())  # a SafeLoader subclass: safe


def parse_assignments(items: list[str] | None, what: str) -> dict[str, Any]:
    """``["a=1", "b=[1, 2]"]`` → ``{"a": 1, "b": [1, 2]}`` (values read with :func:`load_yaml`;
    ``3e-4`` is a number).

    Raises:
        ValueError: an item without ``=`` or with an empty key (the message names ``what``).
    """
    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"{what} expects KEY=VALUE, got {item!r}")
        out[key.strip()] = load_yaml(value)
    return out


def algo_defaults(algo: str) -> dict[str, Any]:
    """A fresh copy of the paper's hyperparameters for ``algo`` (``ppo`` or ``sac``), plus, for
    PPO, :data:`PPO_RUN_DEFAULTS`."""
    algo = algo.lower()
    if algo == "ppo":
        return {**copy.deepcopy(PPO_PAPER_DEFAULTS), **PPO_RUN_DEFAULTS}
    if algo == "sac":
        return copy.deepcopy(SAC_PAPER_DEFAULTS)
    raise ValueError(f"unknown algorithm {algo!r}; choose one of {', '.join(ALGOS)}")


def default_n_envs() -> int:
    """The paper's 16 workers (the vectorised env spreads them over the machine's cores)."""
    return DEFAULT_N_ENVS


VEC_ENVS = ("auto", "subproc", "dummy", "ray")
"""How the environments of a run are stepped (:attr:`TrainConfig.vec_env`)."""


def _field_docs(cls: type) -> dict[str, str]:
    """The string literal under each annotated assignment of a class body, by name."""
    import ast
    import inspect
    import itertools
    import textwrap

    tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    body = tree.body[0].body  # type: ignore[attr-defined]
    out: dict[str, str] = {}
    for node, after in itertools.pairwise(body):
        if (
            isinstance(node, ast.AnnAssign)
            and isinstance(node.target, ast.Name)
            and isinstance(after, ast.Expr)
            and isinstance(after.value, ast.Constant)
            and isinstance(after.value.value, str)
        ):
            out[node.target.id] = inspect.cleandoc(after.value.value)
    return out


@dataclass
class TrainConfig:
    """Everything that defines a training run (saved as ``config.yaml`` in the run folder)."""

    task: str = "velocity-kick"
    """Task name (``velocity-kick``, ``simple-kick``, …), a team scenario (``game-2v2``, …) or
    any registered Gymnasium id."""
    env_id: str = ""
    """The Gymnasium id the task resolved to (filled in by the trainer)."""
    algo: str = "ppo"
    """The algorithm: ``ppo`` or ``sac``."""
    n_envs: int = DEFAULT_N_ENVS
    """Parallel environments (the paper's 16); with a team scenario, parallel games."""
    timesteps: int = 1_000_000
    """Total environment steps of the run."""
    seed: int = 0
    """Random seed (of the learner and, offset per environment, of the environments)."""
    backend: str | None = None
    """Simulator: ``ode`` (SimSpark's physics, exact, the default), ``mujoco`` (the fast
    approximation; its kicks do not work on rcssserver3d) or ``rcssserver3d`` (a real server);
    for a league robot (``env_kwargs`` ``robot: T1``) ``rcsssmj`` (its simulator in-process,
    the default there) or ``rcssservermj`` (a real server)."""
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    """Keyword arguments for ``gymnasium.make`` (the task's config fields)."""
    env_config: dict[str, Any] = field(default_factory=dict)
    """Every option of the run's environment as it was when the run started (filled in by the
    trainer). Resuming, evaluating and exporting the run build its environment from these,
    ``env_kwargs`` over them (:meth:`env_options`), so that a later change of a task's defaults
    does not change a run's environment. Empty in runs from before it existed."""
    algo_kwargs: dict[str, Any] = field(default_factory=dict)
    """Hyperparameters passed to the SB3 algorithm (merged over the paper's defaults)."""
    init_from: str = ""
    """A run folder whose final policy (and observation statistics) this run starts from, e.g.
    a policy learnt on the embedded world, fine-tuned here on ``backend="ode"``, or an exported
    policy, a shipped ``pretrained:NAME`` or an ``.onnx`` file (its actor and recorded action
    noise; under this run's ``env_kwargs``, on the policy's own task the environment it was
    exported with, on another those of its ``env_kwargs`` that shape how it acts: the task
    config's ``policy_options``). The action spaces must match, and the run must observe what
    the policy observed (more starts with zero weights); this run's hyperparameters apply.
    Empty: start from scratch."""
    normalize_obs: bool = False
    """Wrap in ``VecNormalize`` (observations only); off in the paper."""
    checkpoint_freq: int = 100_000
    """Save a checkpoint every this many environment steps (0 = never)."""
    checkpoint_every_s: float = 120.0
    """Also save one every this many seconds of wall-clock time (0 = never), so that a run has
    something saved within its first minutes whatever its speed; each time-triggered
    checkpoint replaces the previous time-triggered one."""
    eval_freq: int = 100_000
    """Evaluate deterministically every this many environment steps (0 = never)."""
    eval_episodes: int = 5
    """Episodes of each periodic evaluation."""
    device: str = "cpu"
    """Torch device; small MLPs train fastest on the CPU."""
    torch_threads: int = 1
    """Torch intra-op threads. 1 keeps a run's numbers the same on every machine (reductions
    over several threads round differently, and PPO amplifies that into a different policy) and
    is about as fast for these small MLPs: every tiny matrix product pays a thread barrier while
    the environment workers keep the other cores busy. With any other value, torch runs on one
    thread while the workers step and on ``torch_threads`` for the gradient steps (0 = one per core;
    measured on the 2-core machine: gradient steps ~20 % faster, a whole run within the noise)."""
    assist_force: float = 0.0
    """An upward push on the learning robot's torso while it trains, as a share of its weight
    (0 = none, the default), falling linearly to 0 over :attr:`assist_steps`: HoST's
    pulling-force curriculum, which lets a get-up policy meet standing before it can stand alone
    (:class:`robocup_gym.envs.assist.TorsoAssist`). In-process engines only; evaluations never
    have it."""
    assist_steps: int = 0
    """Training steps (all environments together) over which :attr:`assist_force` fades out."""
    assist_schedule: str = "linear"
    """How :attr:`assist_force` fades: ``linear`` over :attr:`assist_steps`, or ``success``: down
    2 % with each successful episode of an environment and up 0.5 % with each failed one (tasks
    that report ``info["success"]``, such as GetUp; :attr:`assist_steps` unused)."""
    assist_max_tilt_deg: float = 180.0
    """Push only while the torso is inclined less than this from the vertical (180: always);
    e.g. 60 makes the robot sit or kneel up by itself before the push helps."""
    vec_env: str = "auto"
    """``auto`` (subprocesses when n_envs > 1), ``subproc``, ``dummy``, or ``ray``: the workers
    as Ray actors, on this machine or a cluster (:mod:`robocup_gym.train.ray_vecenv`)."""
    ray_address: str = ""
    """With ``vec_env="ray"``: the Ray cluster to join (``auto``, or ``HOST:PORT`` of its head);
    empty: an embedded Ray on this machine, ended with the run."""
    ray_start_timeout_s: float = 60.0
    """With ``vec_env="ray"``: how long an actor started again after its node was lost may take
    to start (the run's first actors: at least 60 s, ``ray_vecenv.FIRST_START_S``); when none
    can start in time the run saves and stops."""
    n_workers: int = 0
    """Worker processes (or Ray actors) for the environments (0 = one per CPU core, with Ray one
    per CPU of the cluster; at most n_envs); each steps a block of n_envs / n_workers
    environments."""
    start_method: str = ""
    """multiprocessing start method for subprocess envs ('' = forkserver where available)."""
    robot_types: list[int] = field(default_factory=list)
    """Nao types to train on together: environment ``i`` of the run is of type
    ``robot_types[i % len(robot_types)]`` (e.g. ``[0, 1, 2, 3, 4]`` with ``n_envs`` a multiple
    of 5 trains one policy on every type); empty (the default): every environment is of
    ``env_kwargs``' ``robot_type``. Evaluations use ``env_kwargs``' type."""
    selfplay: dict[str, Any] = field(default_factory=dict)
    """Team scenarios: how opponents are drawn (``snapshot_every``, ``pool_size``,
    ``scripted_share``; :class:`robocup_gym.train.selfplay.SelfPlaySettings`), over the
    defaults."""

    def __post_init__(self) -> None:
        for f in fields(self):  # "timesteps: 2.0e6" in a config file: a whole number
            value = getattr(self, f.name)
            if f.type == "int" and isinstance(value, float) and value.is_integer():
                setattr(self, f.name, int(value))
        check_field_kinds(self)  # "timesteps: 1e6" (a text in YAML 1.1), say
        self.algo = self.algo.lower()
        if self.algo not in ALGOS:
            raise ValueError(f"unknown algorithm {self.algo!r}; choose one of {', '.join(ALGOS)}")
        try:
            self.backend = resolve_backend(self.backend, robot=self.env_kwargs.get("robot", "nao"))
        except BackendNotAvailableError as exc:
            raise ValueError(str(exc)) from None
        backends = available_backends()
        if self.backend not in backends:
            raise ValueError(
                f"unknown backend {self.backend!r}; choose one of {', '.join(backends)}"
            )
        if self.n_envs < 1:
            raise ValueError(f"n_envs must be >= 1, got {self.n_envs}")
        if self.timesteps < 1:
            raise ValueError(f"timesteps must be >= 1, got {self.timesteps}")
        for name in ("checkpoint_freq", "eval_freq", "eval_episodes", "n_workers"):
            if int(getattr(self, name)) < 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)}")
        if not self.checkpoint_every_s >= 0:  # also refuses NaN
            raise ValueError(f"checkpoint_every_s must be >= 0, got {self.checkpoint_every_s}")
        if not (0.0 <= self.assist_force <= 2.0):  # also refuses NaN
            raise ValueError(
                f"assist_force is a share of the robot's weight, 0 to 2; got {self.assist_force}"
            )
        from robocup_gym.envs.assist import SCHEDULES

        if self.assist_schedule not in SCHEDULES:
            raise ValueError(
                f"assist_schedule must be one of {', '.join(SCHEDULES)}, got "
                f"{self.assist_schedule!r}"
            )
        if self.assist_force > 0.0:
            if self.assist_schedule == "linear" and int(self.assist_steps) < 1:
                raise ValueError(
                    "assist_force needs assist_steps >= 1: the training steps over which the "
                    "push fades out"
                )
            if self.backend not in IN_PROCESS_BACKENDS:
                raise ValueError(
                    f"assist_force pushes the robot in-process; the {self.backend!r} backend "
                    "cannot (use the ode or mujoco engine, rcsssmj for a league robot, or "
                    "assist_force 0)"
                )
            if not (0.0 < self.assist_max_tilt_deg <= 180.0):
                raise ValueError(
                    f"assist_max_tilt_deg must be within 0 and 180, got {self.assist_max_tilt_deg}"
                )
        elif int(self.assist_steps) < 0:
            raise ValueError(f"assist_steps must be >= 0, got {self.assist_steps}")
        if self.vec_env not in VEC_ENVS:
            raise ValueError(f"vec_env must be one of {', '.join(VEC_ENVS)}, got {self.vec_env!r}")
        from robocup_gym.train.selfplay import SelfPlaySettings

        SelfPlaySettings.of(self.selfplay)  # an unknown setting or a bad value: named here
        if self.robot_types:
            if not all(is_type_number(t) for t in self.robot_types):
                raise ValueError(f"robot_types are Nao types 0-4, got {self.robot_types!r}")
            if self.env_kwargs.get("robot", "nao") != "nao" or is_team_task(self._task_id()):
                raise ValueError(
                    "robot_types varies the Nao of a single-robot task; this run's robot is "
                    f"{self.env_kwargs.get('robot', 'nao')!r} in task {self.task!r}"
                )
            self.robot_types = [int(t) for t in self.robot_types]
            if len({ROBOT_TYPES[t].has_toes for t in self.robot_types}) > 1:
                raise ValueError(
                    f"robot_types {self.robot_types}: type 4 (toes) has two joints more than "
                    "types 0-3, so its observations and actions differ; train it apart"
                )
        if self.ray_address and self.vec_env != "ray":
            raise ValueError(f"ray_address {self.ray_address!r} needs vec_env='ray'")

    @classmethod
    def field_docs(cls) -> dict[str, str]:
        """Each field's docstring (as written under it in the class), by field name."""
        return _field_docs(cls)

    # ------------------------------------------------------------------ derived
    def resolved_algo_kwargs(self) -> dict[str, Any]:
        """The paper's defaults for :attr:`algo`, the task's own (:data:`TASK_ALGO_DEFAULTS`)
        over them, and :attr:`algo_kwargs` over those (``policy_kwargs`` merged key by key)."""
        merged = algo_defaults(self.algo)
        task_id = self._task_id()
        task = TASK_ALGO_DEFAULTS.get((task_id, self.algo.lower()), {})
        if is_team_task(task_id) and self.algo == "ppo":
            task = TEAM_PPO_DEFAULTS
        for layer in (task, self.algo_kwargs):
            for key, value in copy.deepcopy(layer).items():
                if key == "policy_kwargs" and isinstance(value, dict):
                    merged.setdefault("policy_kwargs", {}).update(value)
                else:
                    merged[key] = value
        return merged

    def _task_id(self) -> str:
        """The Gymnasium id of :attr:`task` (:attr:`env_id` once the trainer filled it in);
        ``""`` for a name no task has (the trainer reports that)."""
        if self.env_id:
            return self.env_id
        try:
            return resolve_task(self.task)
        except ValueError:
            return ""

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    # ------------------------------------------------------------------ files
    def save(self, path: str | os.PathLike) -> None:
        """Write as YAML (the exact config of a run, with the resolved hyperparameters)."""
        import yaml

        data = self.to_dict()
        data["algo_kwargs"] = self.resolved_algo_kwargs()
        Path(path).write_text(yaml.safe_dump(data, sort_keys=False))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrainConfig:
        reject_unknown_fields(cls, data, "config key", "valid keys")
        return cls(**copy.deepcopy(data))

    @classmethod
    def load(cls, path: str | os.PathLike) -> TrainConfig:
        """Read a YAML config file (any subset of the fields)."""
        text = Path(path).read_text()
        data = load_yaml(text) or {}
        if not isinstance(data, dict):
            raise ValueError(
                f"{path}: a config file must hold a mapping, got {type(data).__name__}"
            )
        config = cls.from_dict(data)
        if config.env_id and config.env_config:
            config.env_config = with_version_options(
                config.env_id, config.env_config, config.env_kwargs
            )
        return config

    def env_options(self, **overrides: Any) -> dict[str, Any]:
        """The options to build this run's environment with: :attr:`env_config`, then
        :attr:`env_kwargs`, then ``overrides``."""
        return {**self.env_config, **self.env_kwargs, **overrides}

    def merged(self, **overrides: Any) -> TrainConfig:
        """A copy with the given fields replaced (``None`` values are ignored)."""
        data = self.to_dict()
        if overrides.get("backend") is None and self.backend == resolve_backend(
            robot=self.env_kwargs.get("robot", "nao")
        ):
            data["backend"] = None  # the default backend follows the robot
        for key, value in overrides.items():
            if value is not None:
                data[key] = value
        return TrainConfig.from_dict(data)

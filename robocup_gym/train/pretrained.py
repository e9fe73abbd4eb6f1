"""Policies shipped with the package: trained with the project's own CLI on the default engine,
exported to ONNX, ready to run.

Each lives in ``robocup_gym/data/policies/`` as ``<name>.onnx`` (the graph, with its description
in the metadata) and ``<name>.json`` (the same description, readable: task, environment options,
observation layout, action mapping, and how it was trained). Where one policy does not serve every
Nao type, a type has its own, trained on it: ``<name>.type<N>.onnx`` (and its ``.json``), which
:func:`pretrained_path` and :func:`pretrained_policy` give for ``robot_type=N``; the other types
run ``<name>.onnx``. ``robocup-gym eval --pretrained
NAME`` evaluates one in-process; ``robocup-gym agent --pretrained NAME`` drives a robot with it
on a server; :func:`pretrained_policy` gives one to Python code.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from robocup_gym.backends import DEFAULT_ENGINE
from robocup_gym.envs.config import nao_type
from robocup_gym.robot.types import is_type_number
from robocup_gym.train.episodes import run_episodes
from robocup_gym.train.metrics import summarize
from robocup_gym.train.onnx_policy import OnnxPolicy
from robocup_gym.train.tasks import is_team_task, make_env, task_name

if TYPE_CHECKING:
    from robocup_gym.backends.base import Backend

__all__ = [
    "POLICY_DIR",
    "evaluate_pretrained",
    "pretrained_env",
    "pretrained_names",
    "pretrained_path",
    "pretrained_policy",
    "pretrained_types",
    "pretrained_weights",
    "recorded_env_options",
    "with_policy_joints",
]

POLICY_DIR = Path(__file__).resolve().parents[1] / "data" / "policies"
"""Where the shipped policies are."""


_TYPE_TAG = ".type"
"""Between a policy's name and the Nao type of a type's own policy: ``run.type1.onnx``."""


def pretrained_names() -> list[str]:
    """The names of the shipped policies (``get-up``, …), sorted (a type's own policy is
    listed under its name: :func:`pretrained_types`)."""
    if not POLICY_DIR.is_dir():
        return []
    return sorted(p.stem for p in POLICY_DIR.glob("*.onnx") if _TYPE_TAG not in p.stem)


def _shipped_name(name: str) -> str:
    names = pretrained_names()
    key = str(name).strip().lower().replace("_", "-")
    for n in names:
        if key in (n, n.replace("-", "")):
            return n
    shipped = ", ".join(names) if names else "none"
    raise ValueError(f"no pretrained policy {name!r}; shipped: {shipped}")


def pretrained_types(name: str) -> list[int]:
    """The Nao types that have a policy of their own under the shipped name ``name``, sorted
    (the others run the name's shared policy).

    Raises:
        ValueError: no such policy (the message lists the shipped ones).
    """
    n = _shipped_name(name)
    types = []
    for p in POLICY_DIR.glob(f"{n}{_TYPE_TAG}*.onnx"):
        tag = p.stem[len(n) + len(_TYPE_TAG) :]
        if tag.isdigit():
            types.append(int(tag))
    return sorted(types)


def pretrained_path(name: str, robot_type: int | None = None) -> Path:
    """The ONNX file of the shipped policy ``name`` (``get-up``; ``Get_Up`` and ``getup``
    too): for ``robot_type`` its own where that Nao type has one (:func:`pretrained_types`),
    else the shared one.

    Raises:
        ValueError: no such policy (the message lists the shipped ones), or a ``robot_type``
            that is not a Nao type.
    """
    n = _shipped_name(name)
    if robot_type is not None and not is_type_number(robot_type):
        raise ValueError(f"robot_type must be a Nao type 0-4, got {robot_type!r}")
    if robot_type is not None:
        own = POLICY_DIR / f"{n}{_TYPE_TAG}{int(robot_type)}.onnx"
        if own.is_file():
            return own
    return POLICY_DIR / f"{n}.onnx"


def pretrained_policy(name: str, robot_type: int | None = None):
    """The shipped policy ``name`` (for ``robot_type``: see :func:`pretrained_path`) as an
    :class:`~robocup_gym.train.export.OnnxPolicy` (``policy(obs) → action``;
    ``policy.metadata`` has its task and options)."""
    return OnnxPolicy(pretrained_path(name, robot_type))


def pretrained_weights(policy) -> dict[str, np.ndarray]:
    """The network of an exported ``policy`` (an :class:`~robocup_gym.train.export.OnnxPolicy`)
    as the parameters of the SB3 policy it was exported from, by their names there
    (``mlp_extractor.policy_net.0.weight``, ``action_net.bias``, …): the actor only; a value
    network is not exported."""
    import onnx
    from onnx import numpy_helper

    graph = onnx.load(str(policy.path)).graph
    prefix = "policy."
    return {
        init.name[len(prefix) :]: numpy_helper.to_array(init)
        for init in graph.initializer
        if init.name.startswith(prefix)
    }


def recorded_env_options(meta: dict[str, Any]) -> dict[str, Any]:
    """The environment options an exported policy's description (``meta``) records: every
    option of the configuration it was exported with (``env_config``; so that a later change
    of a task's defaults does not change the environment a shipped policy runs in), with its
    ``env_kwargs`` over them. ``backend_options`` (objects, written as text) are left out."""
    recorded = dict(meta.get("env_config") or {})
    recorded.pop("backend_options", None)
    if recorded:
        # options a task gained after the policy was exported: what it ran without them
        for key, value in OPTIONS_ADDED.get(meta.get("env_id", ""), {}).items():
            recorded.setdefault(key, value)
    return {**recorded, **(meta.get("env_kwargs") or {})}


def with_policy_joints(meta: dict[str, Any], options: dict[str, Any]) -> dict[str, Any]:
    """``options`` driving the joints an exported policy (its description ``meta``) drives,
    named, unless they name their own: on a Nao type with more joints than the one it was
    trained on (type 4's toes) the others are held still (0 rad/s)."""
    joints = meta.get("controlled_joints")
    if joints and options.get("controlled_joints") is None:
        return {**options, "controlled_joints": tuple(joints)}
    return options


_TARGETS_ONTO_STOPS = {"target_stop_margin_deg": 0.0}
OPTIONS_ADDED: dict[str, dict[str, Any]] = {
    "RobocupGym/SimpleKick-v0": _TARGETS_ONTO_STOPS,
    "RobocupGym/VelocityKick-v0": _TARGETS_ONTO_STOPS,
    "RobocupGym/Walk-v0": _TARGETS_ONTO_STOPS,
    "RobocupGym/GetUp-v0": {"reference_motion": False, **_TARGETS_ONTO_STOPS},
}
"""Per task, options added since policies were first exported, with the value that gives the
environment those policies ran in (a recorded ``env_config`` without the option predates it)."""


def pretrained_env(
    policy, backend: str | Backend | None = None, env_overrides: dict[str, Any] | None = None
):
    """The environment an exported ``policy`` (an :class:`~robocup_gym.train.export.OnnxPolicy`)
    is meant for: its task with its recorded options (:func:`recorded_env_options`;
    ``env_overrides`` over them) on ``backend`` (a backend's name or a built backend, such as
    the agent's connection to a server; default: the engine it was trained on). The policy
    drives the joints it was trained with (``controlled_joints`` of its description): on Nao
    type 4 the toes of a policy trained on types 0–3 are held still.

    Raises:
        ValueError: the overrides give observations of another size than the policy takes.
    """
    meta = policy.metadata
    if is_team_task(meta.get("env_id", "")):
        name = policy.path.stem
        raise ValueError(
            f"{name} is a team's policy ({task_name(meta['env_id'])}): play it with "
            f"robocup-gym match pretrained:{name} scripted"
            + (" --scenario penalty" if meta["env_id"].endswith("/penalty") else "")
        )
    extra = dict(env_overrides or {})
    options = with_policy_joints(meta, {**recorded_env_options(meta), **extra})
    env = make_env(
        meta["env_id"], backend=backend or meta.get("backend") or DEFAULT_ENGINE, env_kwargs=options
    )
    want = int(meta["input"]["shape"][1])
    if env.observation_space.shape != (want,):
        env.close()
        raise ValueError(
            f"with {extra} the environment's observations have shape "
            f"{env.observation_space.shape}; the policy {policy.path.stem!r} takes ({want},)"
        )
    return env


class _Predictor:
    """``predict(obs, deterministic)`` over an ONNX policy, for :func:`run_episodes`."""

    def __init__(self, policy) -> None:
        self.policy = policy

    def predict(self, obs: np.ndarray, deterministic: bool = True):
        return self.policy(obs), None


def evaluate_pretrained(
    name: str,
    *,
    episodes: int = 10,
    seed: int = 100_000,
    backend: str | None = None,
    robot_type: int | None = None,
) -> dict[str, Any]:
    """Evaluate the shipped policy ``name`` in-process, as ``robocup-gym eval`` evaluates a
    run: ``episodes`` episodes of its task with its options (episode ``k`` seeded ``seed + k``)
    on ``backend`` (default: the engine it was trained on), on Nao type ``robot_type``
    (default: the policy's own; a type with a policy of its own runs that). Returns the summary
    (mean return, the task's measures: ``success_rate``, ``forward_speed_mps_mean``, …)."""
    if int(episodes) < 1:
        raise ValueError(f"episodes must be >= 1, got {episodes}")
    policy = pretrained_policy(name, robot_type)
    meta = policy.metadata
    backend = backend or meta.get("backend") or DEFAULT_ENGINE
    on_type = None if robot_type is None else {"robot_type": int(robot_type)}
    env = pretrained_env(policy, backend, on_type)
    try:
        records = run_episodes(_Predictor(policy), env, episodes, seed=seed)
    finally:
        env.close()
    return {
        "pretrained": policy.path.stem,
        "model": str(policy.path),
        "env_id": meta["env_id"],
        "backend": backend,
        "robot_type": nao_type(env.unwrapped.config),
        "training": meta.get("training", {}),
        **summarize(records),
    }


def describe(name: str) -> dict[str, Any]:
    """The JSON description shipped beside the policy ``name``."""
    return json.loads(pretrained_path(name).with_suffix(".json").read_text())

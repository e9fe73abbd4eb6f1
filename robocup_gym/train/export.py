"""Export a trained policy to ONNX: observation → deterministic action, ready for an agent.

The graph contains everything between the environment's observation and the action the
environment expects: observation normalisation (when the run used ``VecNormalize``; the paper's
setup normalises inside the environment, so usually there is none), the policy network, and the
final squashing/clipping to the action space that Stable-Baselines3's ``predict`` applies. The
export is verified against ``model.predict(obs, deterministic=True)`` on random observations and
on observations from real episodes; a mismatch above the tolerance is an error.

Next to ``policy.onnx`` a ``policy.json`` describes the observation layout (labels, analytic
ranges, normalisation) and the action mapping, so that a team can rebuild the observation in its
own agent; the same JSON is stored in the ONNX file's metadata (key ``robocup_gym``).
"""

from __future__ import annotations

import json
import os
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from robocup_gym.train.episodes import run_episodes
from robocup_gym.train.onnx_policy import (  # noqa: F401 (import path kept)
    INPUT_NAME,
    METADATA_KEY,
    OUTPUT_NAME,
    OnnxPolicy,
    one_thread_options,
    read_metadata,
)
from robocup_gym.train.run import (
    RunInfo,
    curve_so_far,
    load_model,
    load_run,
    space_mismatch,
)
from robocup_gym.train.tasks import is_team_task, make_env, task_name

FORMAT = "robocup-gym-policy/1"


class ExportError(RuntimeError):
    """The ONNX graph does not reproduce the policy within the tolerance."""


def _policy_module(model, algo: str, obs_stats, action_space):
    import torch
    from torch import nn

    policy = model.policy
    low = torch.as_tensor(np.asarray(action_space.low, dtype=np.float32))
    high = torch.as_tensor(np.asarray(action_space.high, dtype=np.float32))

    class ExportPolicy(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.policy = policy
            self.register_buffer("low", low)
            self.register_buffer("high", high)
            if obs_stats is not None:
                mean, var, eps, clip = obs_stats
                self.register_buffer("obs_mean", torch.as_tensor(mean, dtype=torch.float32))
                self.register_buffer(
                    "obs_std", torch.as_tensor(np.sqrt(var + eps), dtype=torch.float32)
                )
                self.obs_clip = float(clip)
            else:
                self.obs_mean = None

        def forward(self, obs):
            x = obs
            if self.obs_mean is not None:
                x = torch.clamp((x - self.obs_mean) / self.obs_std, -self.obs_clip, self.obs_clip)
            if algo == "sac":
                a = self.policy.actor(x, deterministic=True)  # tanh-squashed, in [-1, 1]
                return self.low + 0.5 * (a + 1.0) * (self.high - self.low)
            features = self.policy.pi_features_extractor(x)
            latent = self.policy.mlp_extractor.forward_actor(features)
            a = self.policy.action_net(latent)
            if self.policy.squash_output:
                a = torch.tanh(a)
                return self.low + 0.5 * (a + 1.0) * (self.high - self.low)
            return torch.maximum(torch.minimum(a, self.high), self.low)

    module = ExportPolicy()
    module.eval()
    return module


def _sample_observations(info: RunInfo, model, obs_space, n_random: int, seed: int) -> np.ndarray:
    """Random observations in the space plus observations from one real episode."""
    rng = np.random.default_rng(seed)
    low = np.asarray(obs_space.low, dtype=np.float64)
    high = np.asarray(obs_space.high, dtype=np.float64)
    finite = np.isfinite(low) & np.isfinite(high)
    samples = rng.normal(0.0, 1.0, (n_random, *obs_space.shape))
    u = rng.uniform(0.0, 1.0, samples.shape)
    samples = np.where(finite, low + u * (high - low), samples)
    rows = [samples.astype(np.float32)]
    cfg = info.config
    if is_team_task(cfg.env_id):
        from robocup_gym.train.selfplay import team_observations

        rows.append(team_observations(task_name(cfg.env_id), cfg.env_options(), seed=seed))
        return np.concatenate(rows, axis=0)
    try:
        env = make_env(cfg.env_id, backend=cfg.backend, env_kwargs=cfg.env_options())
        seen: list[np.ndarray] = []
        orig_step = env.step

        def recording_step(action):
            out = orig_step(action)
            seen.append(np.asarray(out[0], dtype=np.float32))
            return out

        env.step = recording_step
        try:
            run_episodes(model, env, 1, seed=seed)
        finally:
            env.close()
        if seen:
            rows.append(np.stack(seen)[:256])
    except Exception as exc:  # verification still runs on the random samples
        warnings.warn(
            f"could not collect episode observations for verification: {exc}",
            RuntimeWarning,
            stacklevel=2,
        )
    return np.concatenate(rows, axis=0)


def _action_noise(model) -> dict[str, Any]:
    """``{"action_log_std": [...]}``: the log standard deviation of the policy's Gaussian
    action noise when it has one of its own per action (PPO without gSDE), for a run that goes
    on from the exported policy; else nothing."""
    log_std = getattr(model.policy, "log_std", None)
    if log_std is None or getattr(model, "use_sde", False) or log_std.dim() != 1:
        return {}
    return {"action_log_std": log_std.detach().cpu().numpy().astype(float).tolist()}


def _env_description(info: RunInfo, env_kwargs: dict[str, Any], model=None) -> dict[str, Any]:
    """Observation/action layout of the policy's environment (RobocupGym tasks): the run's
    (:meth:`TrainConfig.env_options`), with ``env_kwargs`` over it.

    Raises:
        ValueError: with ``model``, the environment's observation or action space is not the
            policy's (an option given to the export changed it).
    """

    cfg = info.config
    if is_team_task(cfg.env_id):
        from robocup_gym.train.selfplay import team_description

        return team_description(cfg.env_options(**env_kwargs))
    out: dict[str, Any] = {}
    try:
        env = make_env(cfg.env_id, backend=cfg.backend, env_kwargs=cfg.env_options(**env_kwargs))
    except Exception as exc:
        if env_kwargs != cfg.env_kwargs:
            raise ValueError(
                f"the environment options {env_kwargs} do not make one: {exc}"
            ) from exc
        return {"error": f"environment not available: {exc}"}
    try:
        base = env.unwrapped
        mismatch = None if model is None else space_mismatch(env, model)
        if mismatch is not None:
            what, mine, policy = mismatch
            raise ValueError(
                f"with {env_kwargs} the environment's {what} has shape {mine}, the policy's "
                f"{policy}: the options do not fit this policy"
            )
        config = getattr(base, "config", None)
        if config is not None and hasattr(config, "to_dict"):
            out["env_config"] = config.to_dict()
        if hasattr(base, "observation_labels"):
            out["observation_labels"] = list(base.observation_labels)
        if hasattr(base, "raw_bounds"):
            lo, hi = base.raw_bounds
            out["observation_raw_low"] = np.asarray(lo, float).tolist()
            out["observation_raw_high"] = np.asarray(hi, float).tolist()
        if hasattr(base, "action_labels"):
            out["action_labels"] = list(base.action_labels)
        if hasattr(base, "controlled_joints"):
            out["controlled_joints"] = list(base.controlled_joints)
            model = getattr(base, "robot_model", None)
            joints = getattr(getattr(base, "_actions", None), "joints", None)
            if model is not None and joints is not None:
                out["controlled_joint_max_speed_rad_s"] = (
                    np.asarray(model.max_speeds)[joints].astype(float).tolist()
                )
    finally:
        env.close()
    return out


def export_onnx(
    run: str | os.PathLike,
    onnx_path: str | os.PathLike,
    *,
    checkpoint: str | os.PathLike | None = None,
    n_random: int = 512,
    atol: float = 1e-5,
    seed: int = 0,
    opset: int = 17,
    env_overrides: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Write ``onnx_path`` (and ``<name>.json`` beside it); returns the metadata.

    ``env_overrides``: environment options the policy is meant for, over the run's (a get-up
    trained on both sides and exported for ``start_side="front"``, say); they go into the
    description's ``env_kwargs`` and must leave the observation and action spaces as they are.

    Raises:
        ExportError: when ONNX Runtime's actions differ from ``model.predict`` by more than
            ``atol`` on any sample.
        ValueError: the overrides change the spaces or make no environment.
    """
    import onnx
    import onnxruntime as ort
    import torch

    info = load_run(run)
    cfg = info.config
    model = load_model(info, checkpoint=checkpoint)
    env_kwargs = {**cfg.env_kwargs, **(env_overrides or {})}
    described = _env_description(info, env_kwargs, model)
    obs_space, act_space = model.observation_space, model.action_space
    if len(obs_space.shape) != 1 or len(act_space.shape) != 1:
        raise ExportError("only flat Box observation and action spaces can be exported")
    obs_stats = info.obs_stats()
    module = _policy_module(model, cfg.algo, obs_stats, act_space)

    onnx_path = Path(onnx_path)
    onnx_path.parent.mkdir(parents=True, exist_ok=True)
    dummy = torch.zeros((1, obs_space.shape[0]), dtype=torch.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        torch.onnx.export(
            module,
            (dummy,),
            str(onnx_path),
            input_names=[INPUT_NAME],
            output_names=[OUTPUT_NAME],
            dynamic_axes={INPUT_NAME: {0: "batch"}, OUTPUT_NAME: {0: "batch"}},
            opset_version=opset,
            dynamo=False,
        )

    # ---- verify against the SB3 policy
    obs = _sample_observations(info, model, obs_space, n_random, seed)
    normalizer = info.obs_normalizer()
    expected, _ = model.predict(
        normalizer(obs) if normalizer is not None else obs, deterministic=True
    )
    session = ort.InferenceSession(  # as OnnxPolicy runs it
        str(onnx_path), sess_options=one_thread_options(ort), providers=["CPUExecutionProvider"]
    )
    got = session.run([OUTPUT_NAME], {INPUT_NAME: obs.astype(np.float32)})[0]
    max_diff = float(np.max(np.abs(got - expected)))
    if not max_diff <= atol:
        raise ExportError(
            f"ONNX actions differ from the SB3 policy by up to {max_diff:.3g} (> {atol:g}) on "
            f"{len(obs)} sample observations; the export is not faithful"
        )

    meta: dict[str, Any] = {
        "format": FORMAT,
        "task": cfg.task,
        "env_id": cfg.env_id,
        "backend": cfg.backend,
        "env_kwargs": env_kwargs,
        "algo": cfg.algo,
        "run": str(info.path),
        "model": str(checkpoint or info.model_path),
        "timesteps_trained": int(model.num_timesteps),
        "input": {
            "name": INPUT_NAME,
            "shape": ["batch", int(obs_space.shape[0])],
            "dtype": "float32",
            "low": np.asarray(obs_space.low, float).tolist(),
            "high": np.asarray(obs_space.high, float).tolist(),
        },
        "output": {
            "name": OUTPUT_NAME,
            "shape": ["batch", int(act_space.shape[0])],
            "dtype": "float32",
            "low": np.asarray(act_space.low, float).tolist(),
            "high": np.asarray(act_space.high, float).tolist(),
        },
        "obs_normalization_in_graph": obs_stats is not None,
        **_action_noise(model),
        "verification": {"samples": len(obs), "max_abs_diff": max_diff, "atol": atol},
        "training": _training_description(info),
        **described,
    }
    model_proto = onnx.load(str(onnx_path))
    entry = model_proto.metadata_props.add()
    entry.key = METADATA_KEY
    entry.value = json.dumps(meta)
    model_proto.producer_name = "robocup-gym"
    onnx.save(model_proto, str(onnx_path))
    onnx_path.with_suffix(".json").write_text(_compact_json(meta) + "\n")
    return meta


def _training_description(info: RunInfo) -> dict[str, Any]:
    """How the run was trained (enough to train it again with the CLI): seed, environments,
    hyperparameters, the assist, and the wall-clock time of its learning curve."""
    cfg = info.config
    out: dict[str, Any] = {
        "seed": cfg.seed,
        "n_envs": cfg.n_envs,
        "timesteps": cfg.timesteps,
        "algo_kwargs": cfg.resolved_algo_kwargs(),
    }
    if cfg.assist_force > 0.0:
        out["assist"] = {
            "force_share": cfg.assist_force,
            "steps": cfg.assist_steps,
            "max_tilt_deg": cfg.assist_max_tilt_deg,
            "schedule": cfg.assist_schedule,
        }
    wall_s, _ = curve_so_far(info.path / "progress.csv")
    if wall_s > 0.0:
        out["wall_s"] = wall_s
    return out


def _compact_json(data: Any) -> str:
    """Indented JSON with lists of numbers/strings kept on one line."""
    text = json.dumps(data, indent=2)
    return re.sub(
        r"\[\s+([^\[\]{}]*?)\s+\]", lambda m: "[" + " ".join(m.group(1).split()) + "]", text
    )

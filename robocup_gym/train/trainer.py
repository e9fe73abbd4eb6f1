"""Training with Stable-Baselines3: run folder, live progress, checkpoints, evaluation, resume."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from robocup_gym.train.algos import algo_class, validate_algo_kwargs
from robocup_gym.train.config import TrainConfig
from robocup_gym.train.ray_vecenv import WorkersLostError
from robocup_gym.train.run import checkpoints, curve_so_far, load_run, new_run_dir
from robocup_gym.train.tasks import (
    is_team_task,
    make_env,
    resolve_task,
    resolved_env_config,
    task_name,
)


@dataclass
class TrainResult:
    run_dir: Path
    timesteps: int
    wall_s: float
    steps_per_s: float
    interrupted: bool = False
    """Stopped before ``timesteps`` by Ctrl-C, SIGTERM or SIGHUP (the model was saved)."""
    signal: int | None = None
    """The signal (SIGTERM/SIGHUP) that stopped the run, if one did."""
    recent: dict[str, Any] = field(default_factory=dict)
    """Running means over the last 100 training episodes."""
    last_eval: dict[str, Any] | None = None


STOP_SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name)
)
"""Signals that end a run the way Ctrl-C does: the model is saved and the run can resume."""


@contextlib.contextmanager
def _stop_on_signals(stopper):
    """While training, SIGTERM/SIGHUP set ``stopper.signal`` (training then stops at the next
    step and saves); the previous handlers come back afterwards. Only in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {}

    def handler(signum, frame):
        stopper.signal = signum

    for sig in STOP_SIGNALS:
        previous[sig] = signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)


def _console(console):
    if console is not None:
        return console
    from rich.console import Console

    return Console(soft_wrap=True)


def prepare_run(
    config: TrainConfig, out: str | os.PathLike = "runs", run_dir: str | os.PathLike | None = None
) -> tuple[TrainConfig, Path]:
    """Resolve the task, check its options and hyperparameters, create the run folder and write
    ``config.yaml``. Nothing is created when a check fails."""
    env_id = resolve_task(config.task)
    config = config.merged(env_id=env_id)
    if _from_exported(config.init_from):
        config = _over_exported_options(config)
    elif config.init_from and not Path(config.init_from).is_dir():
        raise ValueError(
            f"init_from {config.init_from!r} is neither a run folder, an exported policy "
            "(.onnx) nor pretrained:NAME"
        )
    # check the options (before any folder or worker exists) and freeze every option of the
    # environment, so that the run keeps it if a default changes
    options = config.env_options()
    if is_team_task(env_id):
        if config.backend not in ("ode", "mujoco"):
            raise ValueError(
                f"team scenarios run in-process on the ode or mujoco engine, not {config.backend!r}"
            )
        if config.assist_force > 0.0:
            raise ValueError("assist_force pushes one robot; team scenarios have none")
        options.setdefault("engine", config.backend)
    config = config.merged(env_config=resolved_env_config(env_id, options))
    validate_algo_kwargs(config.algo, config.algo_kwargs)
    if run_dir is None:
        path = new_run_dir(out, task_name(env_id), config.algo)
    else:
        path = Path(run_dir)
        path.mkdir(parents=True, exist_ok=True)
    config.save(path / "config.yaml")
    return config, path


def _from_exported(init_from: str) -> bool:
    """Whether ``init_from`` names an exported policy: ``pretrained:NAME`` or an ``.onnx`` file
    (else a run folder)."""
    return init_from.startswith("pretrained:") or init_from.endswith(".onnx")


def _init_policy(cfg: TrainConfig):
    """The exported policy a run starts from: an ``.onnx`` file, or the shipped
    ``pretrained:NAME`` (for a run on one Nao type, that type's own where it has one).

    Raises:
        ValueError: no such policy.
    """
    from robocup_gym.train.pretrained import pretrained_policy

    if not cfg.init_from.startswith("pretrained:"):
        from robocup_gym.train.onnx_policy import OnnxPolicy

        if not Path(cfg.init_from).is_file():
            raise ValueError(f"init_from {cfg.init_from}: no such exported policy")
        return OnnxPolicy(cfg.init_from)
    types = set(cfg.robot_types) or {cfg.env_kwargs.get("robot_type")}
    robot_type = types.pop() if len(types) == 1 else None
    return pretrained_policy(cfg.init_from.split(":", 1)[1], robot_type)


def _over_exported_options(cfg: TrainConfig) -> TrainConfig:
    """``cfg`` starting from an exported policy (:func:`_init_policy`), under the run's own
    environment options: on the policy's task, every option it was exported with
    (:func:`~robocup_gym.train.pretrained.recorded_env_options`); on another task, the options
    it was trained with that shape how it acts
    (:func:`~robocup_gym.train.tasks.options_a_policy_takes_along`: a walk's gait for a task
    built on Walk, say), the task's own otherwise (observations, reward, starts, ends).

    Raises:
        ValueError: no such policy, one of another algorithm, or one that normalises its
            observations in its graph (or a run that would normalise them).
    """
    from robocup_gym.train.pretrained import recorded_env_options, with_policy_joints
    from robocup_gym.train.tasks import options_a_policy_takes_along

    meta = _init_policy(cfg).metadata
    if meta.get("algo") != cfg.algo:
        raise ValueError(
            f"init_from {cfg.init_from} is a {meta.get('algo')} policy; this run uses {cfg.algo}"
        )
    if meta.get("obs_normalization_in_graph") or cfg.normalize_obs:
        raise ValueError(
            f"init_from {cfg.init_from}: an exported policy starts a run without "
            "normalize_obs, and only one that normalises nothing itself"
        )
    if meta.get("env_id") == cfg.env_id:
        options = recorded_env_options(meta)
    else:
        options = options_a_policy_takes_along(cfg.env_id, meta.get("env_kwargs") or {})
    options.pop("robot_type", None)  # the run's own (robot_types, or the task's default)
    return cfg.merged(env_kwargs=with_policy_joints(meta, {**options, **cfg.env_kwargs}))


_FIRST_LAYER = "mlp_extractor.policy_net.0.weight"
"""The actor's first layer in an SB3 ``MlpPolicy``: (units, observations)."""


def _start_from_exported(model, cfg: TrainConfig) -> None:
    """Give a fresh ``model`` the actor of the exported policy ``cfg.init_from``
    (:func:`_init_policy`) and, where its description records it (``action_log_std``), its
    action noise; its value network starts afresh (none is exported). Where the run's task
    observes more than the policy did (:func:`_widened_first_layer`), the added observations
    start with zero weights: the run starts acting exactly as the policy.

    Raises:
        ValueError: the policy's network does not fit the model's (its layers named).
    """
    import numpy as np
    import torch

    from robocup_gym.train.pretrained import pretrained_weights

    own = model.policy.state_dict()
    policy = _init_policy(cfg)
    weights = pretrained_weights(policy)
    first = weights.get(_FIRST_LAYER)
    if first is not None and _FIRST_LAYER in own and own[_FIRST_LAYER].shape[1] != first.shape[1]:
        weights[_FIRST_LAYER] = _widened_first_layer(first, policy.metadata, cfg, model.get_env())
    if "action_log_std" in policy.metadata and "log_std" in own:
        weights["log_std"] = np.asarray(policy.metadata["action_log_std"], dtype=np.float32)
    misfit = [k for k, w in weights.items() if k not in own or tuple(own[k].shape) != w.shape]
    if misfit or not weights:
        raise ValueError(
            f"init_from {cfg.init_from}: its network does not fit this run's policy "
            f"({', '.join(misfit) or 'no layers'}; the task's options and net_arch must match)"
        )
    state = {k: torch.tensor(w, device=own[k].device) for k, w in weights.items()}
    model.policy.load_state_dict(state, strict=False)


def _widened_first_layer(weight, meta: dict, cfg: TrainConfig, venv):
    """The exported actor's first layer ``weight`` (units × its observations) for the
    observations of the run's environments ``venv`` (read from its first): each of the
    policy's observations (by label, with the same normalisation bounds; a team's come scaled
    by fixed ranges, without bounds) keeps its column, every other observation of the run gets
    a column of zeros.

    Raises:
        ValueError: the policy does not record its observations, or one of them is not among
            the run's or is normalised differently (named).
    """
    import numpy as np

    labels = meta.get("observation_labels")
    # a task normalises its observations over bounds that both record; a team's come scaled
    # by fixed ranges (robocup_gym.soccer.observations) and neither records bounds
    bounded, run_bounded = "observation_raw_low" in meta, venv.has_attr("raw_bounds")
    if not labels or (run_bounded and not bounded):
        raise ValueError(
            f"init_from {cfg.init_from}: its observations differ from this run's and it does "
            "not record which they are"
        )
    if bounded and not run_bounded:
        raise ValueError(
            f"init_from {cfg.init_from}: a task's policy (its observations normalised over "
            "its task's bounds) cannot start a team run (observations scaled by the game's "
            "fixed ranges)"
        )
    scaled = not bounded
    mine = list(venv.get_attr("observation_labels", [0])[0])
    if scaled:
        lo = hi = np.zeros(len(mine))
    else:
        lo, hi = (np.asarray(b, float) for b in venv.get_attr("raw_bounds", [0])[0])
    missing = [lab for lab in labels if lab not in mine]
    if missing or len(mine) != len(lo):
        named = ", ".join(missing[:3]) + (
            f" and {len(missing) - 3} more" if len(missing) > 3 else ""
        )
        raise ValueError(
            f"init_from {cfg.init_from}: this run does not observe its "
            f"{named or 'observations as one frame'} (observations and frame_stack must include "
            "the policy's)"
        )
    widened = np.zeros((weight.shape[0], len(mine)), dtype=weight.dtype)
    for i, lab in enumerate(labels):
        j = mine.index(lab)
        if not scaled and not np.allclose(
            (meta["observation_raw_low"][i], meta["observation_raw_high"][i]), (lo[j], hi[j])
        ):
            raise ValueError(
                f"init_from {cfg.init_from}: its observation {lab} is normalised over "
                f"[{meta['observation_raw_low'][i]}, {meta['observation_raw_high'][i]}], "
                f"this run's over [{lo[j]}, {hi[j]}]"
            )
        widened[:, j] = weight[:, i]
    return widened


def _start_from_run(model, init, cfg: TrainConfig) -> None:
    """Give a fresh ``model`` the policy of run ``init`` (``TrainConfig.init_from``).

    Raises:
        ValueError: the runs' algorithms or observation/action spaces differ.
    """
    from robocup_gym.train.run import space_mismatch

    if init.config.algo != cfg.algo:
        raise ValueError(
            f"init_from {init.path} was trained with {init.config.algo}, this run uses {cfg.algo}"
        )
    source = algo_class(cfg.algo).load(init.model_path, device=cfg.device)
    mismatch = space_mismatch(model, source)
    if mismatch is not None:
        name, ours, theirs = mismatch
        raise ValueError(
            f"init_from {init.path}: its {name.replace('_', ' ')} has shape {theirs}, "
            f"this run's {ours} (the task and its options must match)"
        )
    model.set_parameters(str(init.model_path), exact_match=True, device=cfg.device)


def train(
    config: TrainConfig | None = None,
    *,
    out: str | os.PathLike = "runs",
    run_dir: str | os.PathLike | None = None,
    resume: str | os.PathLike | None = None,
    extra_timesteps: int | None = None,
    console=None,
    progress: bool = True,
    log_every_s: float = 30.0,
    curve_every: int | None = None,
    placement: dict[str, Any] | None = None,
) -> TrainResult:
    """Train a policy; returns where it went and how it did.

    Args:
        config: What to train (ignored with ``resume``, which reads the run's own config).
        out: Parent folder of new run folders.
        run_dir: Use exactly this folder instead of a new timestamped one.
        resume: A run folder to continue from its newest model/checkpoint up to its configured
            ``timesteps`` (or ``timesteps`` given in ``extra_timesteps``, as the new total).
        progress: Show the rich progress bar (or periodic lines when not on a terminal).
        curve_every: Steps between rows of ``progress.csv`` (default: 1/200 of the run, >= 1000).
        placement: With ``resume``: where the environments step now (``vec_env``,
            ``ray_address``, ``n_workers``), over the run's own config; what a run learns does not
            depend on it.
    """
    console = _console(console)
    created = False
    if resume is not None:
        info = load_run(resume)
        cfg, path = info.config, info.path
        if extra_timesteps is not None or placement:
            unknown = set(placement or {}) - {"vec_env", "ray_address", "n_workers"}
            if unknown:
                raise ValueError(f"placement takes vec_env, ray_address, n_workers: {unknown}")
            cfg = cfg.merged(timesteps=extra_timesteps, **(placement or {}))
            cfg.save(path / "config.yaml")
        start_from = info.latest_model_path()
    else:
        created = run_dir is None or not Path(run_dir).exists()
        cfg, path = prepare_run(config or TrainConfig(), out=out, run_dir=run_dir)
        start_from = None

    console.print(
        f"[bold]robocup-gym train[/bold] {cfg.task} ({cfg.env_id}) · {cfg.algo.upper()} · "
        f"{cfg.n_envs} env{'s' if cfg.n_envs != 1 else ''} · {cfg.timesteps:,} steps · "
        f"seed {cfg.seed} · backend {cfg.backend}"
    )
    console.print(f"run folder: [cyan]{path}[/cyan]" + (" (resuming)" if start_from else ""))
    saves = []
    if cfg.checkpoint_every_s > 0:
        t = cfg.checkpoint_every_s
        saves.append(f"every {t / 60:g} min" if t >= 60 else f"every {t:g} s")
    if cfg.checkpoint_freq > 0:
        saves.append(f"every {cfg.checkpoint_freq:,} steps")
    console.print(
        "checkpoints "
        + (" and ".join(saves) if saves else "off")
        + "; Ctrl-C, SIGTERM or SIGHUP stops and saves (continue with --resume)"
    )

    try:
        model, venv = _setup(cfg, path, start_from, console)
    except BaseException:
        if created:  # leave no half-made run folder behind
            shutil.rmtree(path, ignore_errors=True)
        raise

    remaining = cfg.timesteps - int(model.num_timesteps)
    curve = path / "progress.csv"
    wall0, episodes0 = curve_so_far(curve) if start_from is not None else (0.0, 0)
    from robocup_gym.train.callbacks import (
        CheckpointCallback,
        EpisodeStatsCallback,
        PeriodicEvalCallback,
        RichProgressCallback,
        StopOnSignal,
        TorchThreadsCallback,
        task_measure,
    )

    team = None
    if is_team_task(cfg.env_id):
        from robocup_gym.train.selfplay import SELFPLAY_FIELDS, SelfPlayCallback, SelfPlaySettings

        team = SelfPlayCallback(path / "opponents", SelfPlaySettings.of(cfg.selfplay))
    stats = EpisodeStatsCallback(
        curve_path=curve,
        curve_every=curve_every or max(1000, cfg.timesteps // 200),
        wall_offset_s=wall0,
        episodes_offset=episodes0,
        extra_fields=SELFPLAY_FIELDS if team is not None else (),
        extra=team.figures if team is not None else None,
    )
    stopper = StopOnSignal()
    callbacks: list = [stopper, stats] + ([team] if team is not None else [])
    if cfg.torch_threads != 1 and cfg.n_envs > 1 and cfg.vec_env != "dummy":
        # several threads for the gradient steps only, one while the environments run
        callbacks.append(TorchThreadsCallback(rollout_threads=1, train_threads=cfg.torch_threads))
    bar = None
    if progress:
        bar = RichProgressCallback(
            stats,
            cfg.timesteps,
            description=cfg.task,
            console=console,
            log_every_s=log_every_s,
        )
        callbacks.append(bar)

    def say(text: str) -> None:
        if bar is not None:
            bar.say(text)
        else:
            with contextlib.suppress(Exception):
                console.print(text, highlight=False)

    def saved(ckpt: Path, first: bool) -> None:
        say(("first checkpoint: " if first else "checkpoint: ") + str(ckpt))

    if cfg.checkpoint_freq > 0 or cfg.checkpoint_every_s > 0:
        callbacks.append(
            CheckpointCallback(
                path / "checkpoints",
                cfg.checkpoint_freq,
                cfg.algo == "sac",
                every_s=cfg.checkpoint_every_s,
                on_save=saved,
            )
        )
    evaluator = None
    if cfg.eval_freq > 0 and cfg.eval_episodes > 0 and team is None:
        evaluator = PeriodicEvalCallback(
            lambda: make_env(cfg.env_id, backend=cfg.backend, env_kwargs=cfg.env_options()),
            cfg.eval_freq,
            cfg.eval_episodes,
            path / "evaluations.jsonl",
            on_result=bar.report_eval if bar is not None else None,
        )
        callbacks.append(evaluator)

    interrupted = False
    lost: WorkersLostError | None = None
    t0 = time.perf_counter()
    try:
        with _stop_on_signals(stopper):
            if remaining > 0:
                model.learn(
                    total_timesteps=remaining, callback=callbacks, reset_num_timesteps=False
                )
            else:
                say(f"nothing to do: the run already has {model.num_timesteps:,} steps")
    except KeyboardInterrupt:
        interrupted = True
        say("[yellow]interrupted (Ctrl-C): saving the model…[/yellow]")
    except WorkersLostError as exc:
        lost = exc
    finally:
        model.save(path / "model.zip")
        vn = model.get_vec_normalize_env()
        if vn is not None:
            vn.save(str(path / "vecnormalize.pkl"))
        with contextlib.suppress(Exception):
            venv.close()
    if lost is not None:
        raise WorkersLostError(
            f"{lost}; the model is saved ({model.num_timesteps:,} steps): continue with "
            f"robocup-gym train --resume {path}"
        ) from None
    stopped_by = stopper.signal
    if stopped_by is not None:
        interrupted = True
        say(f"[yellow]stopped by {signal.Signals(stopped_by).name}: model saved[/yellow]")
    wall = time.perf_counter() - t0
    steps_done = int(model.num_timesteps)
    result = TrainResult(
        run_dir=path,
        timesteps=steps_done,
        wall_s=wall,
        steps_per_s=stats.overall_steps_per_s() if remaining > 0 else 0.0,
        interrupted=interrupted,
        signal=stopped_by,
        recent=stats.summary(),
        last_eval=evaluator.last if evaluator is not None else None,
    )
    s = result.recent
    ended = s.get("return_mean") is not None  # episodes ended recently: their measures
    say(
        f"[bold green]{'stopped' if interrupted else 'done'}[/bold green]: {steps_done:,} steps; "
        f"{steps_done - (cfg.timesteps - remaining):,} of them now, in {wall:,.0f} s "
        f"({result.steps_per_s:,.0f} steps/s)"
        + (f" · recent {task_measure(s)} · recent reward {s['return_mean']:.2f}" if ended else "")
    )
    say(f"model: [cyan]{path / 'model.zip'}[/cyan]")
    if interrupted and steps_done < cfg.timesteps:
        say(f"continue: robocup-gym train --resume {path}")
    if team is not None:
        from robocup_gym.train.selfplay import next_command

        say(f"next: {next_command(task_name(cfg.env_id), path)}")
    else:
        say(f"next: robocup-gym eval {path}")
    return result


def _setup(cfg: TrainConfig, path: Path, start_from: Path | None, console):
    """Start the environments and the learner (a fresh model, one from ``init_from``, or the
    run's newest checkpoint when resuming); returns ``(model, venv)``."""
    with console.status(f"starting {cfg.n_envs} environment(s) and the learner…"):
        import torch
        from stable_baselines3.common.logger import configure
        from stable_baselines3.common.utils import set_random_seed
        from stable_baselines3.common.vec_env import VecNormalize

        from robocup_gym.train.vecenv import make_vec_env

        from_run = cfg.init_from and not _from_exported(cfg.init_from)
        init = load_run(cfg.init_from) if start_from is None and from_run else None
        if init is not None and (init.vecnormalize_path is not None) != cfg.normalize_obs:
            raise ValueError(
                f"init_from {init.path} was trained with normalize_obs="
                f"{init.vecnormalize_path is not None}; this run must use the same"
            )
        if cfg.torch_threads > 0:
            torch.set_num_threads(cfg.torch_threads)
        set_random_seed(cfg.seed)
        seed = cfg.seed if start_from is None else cfg.seed + 7919 * (1 + _n_ckpt(path))
        placement = {
            "kind": cfg.vec_env,
            "n_workers": cfg.n_workers,
            "start_method": cfg.start_method,
            "ray_address": cfg.ray_address,
            "ray_start_timeout_s": cfg.ray_start_timeout_s,
        }
        if is_team_task(cfg.env_id):
            from robocup_gym.train.selfplay import (
                OpponentPool,
                SelfPlaySettings,
                make_team_vec_env,
            )

            venv = make_team_vec_env(
                task_name(cfg.env_id),
                cfg.n_envs,
                options=cfg.env_options(),
                pool=OpponentPool(path / "opponents", SelfPlaySettings.of(cfg.selfplay)),
                seed=seed,
                **placement,
            )
        else:
            venv = make_vec_env(
                cfg.env_id,
                cfg.n_envs,
                backend=cfg.backend,
                env_kwargs=cfg.env_options(),
                seed=seed,
                **placement,
                assist={
                    "share": cfg.assist_force,
                    "decay_steps": cfg.assist_steps,
                    "start_step": _steps_done(start_from),
                    "max_tilt_deg": cfg.assist_max_tilt_deg,
                    "schedule": cfg.assist_schedule,
                }
                if cfg.assist_force > 0.0
                else None,
                robot_types=cfg.robot_types,
            )
        try:
            if cfg.normalize_obs:
                vn_path = path / "checkpoints" / "vecnormalize.pkl"
                if start_from is not None and (path / "vecnormalize.pkl").exists():
                    vn_path = path / "vecnormalize.pkl"
                if init is not None and init.vecnormalize_path is not None:
                    venv = VecNormalize.load(str(init.vecnormalize_path), venv)
                    venv.training = True
                elif start_from is not None and vn_path.exists():
                    venv = VecNormalize.load(str(vn_path), venv)
                    venv.training = True
                else:
                    venv = VecNormalize(venv, norm_obs=True, norm_reward=False)
            cls = algo_class(cfg.algo)
            if start_from is None:
                model = cls(
                    "MlpPolicy",
                    venv,
                    seed=cfg.seed,
                    device=cfg.device,
                    verbose=0,
                    **cfg.resolved_algo_kwargs(),
                )
                if init is not None:
                    _start_from_run(model, init, cfg)
                elif cfg.init_from:
                    _start_from_exported(model, cfg)
            else:
                model = cls.load(start_from, env=venv, device=cfg.device)
                rb = path / "checkpoints" / "replay_buffer.pkl"
                if hasattr(model, "load_replay_buffer") and rb.exists():
                    model.load_replay_buffer(rb)
            model.set_logger(configure(str(path / "tb"), ["tensorboard"]))
        except BaseException:
            with contextlib.suppress(Exception):
                venv.close()  # the environment workers go with the refused run
            raise
    return model, venv


def _steps_done(model_zip: Path | None) -> int:
    """The training steps a saved SB3 model has behind it (0 for none): its ``num_timesteps``,
    read from the zip's ``data`` without loading the policy."""
    if model_zip is None:
        return 0
    import json
    import zipfile

    with zipfile.ZipFile(model_zip) as z:
        return int(json.loads(z.read("data")).get("num_timesteps", 0))


def _n_ckpt(path: Path) -> int:
    return len(checkpoints(path))

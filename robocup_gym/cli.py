"""``robocup-gym``: train, evaluate, export and serve (see ``docs/training.md``).

Heavy libraries (torch, Stable-Baselines3, MuJoCo) are imported inside the commands, so
``robocup-gym --help`` answers at once and ``robocup-gym train`` prints where it is going before
the learner starts.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Annotated, Any

try:
    import typer
except ImportError:  # pragma: no cover - the CLI needs the train extra
    typer = None

_MISSING_EXTRA = (
    "robocup-gym's command line needs the training extra: pip install -e '.[train]' "
    "(typer, rich, torch, stable-baselines3, …)"
)


def _require_typer() -> None:
    if typer is None:  # pragma: no cover
        sys.stderr.write(_MISSING_EXTRA + "\n")
        raise SystemExit(1)


def _console():
    from rich.console import Console

    return Console(soft_wrap=True)


def _click():
    """``(exceptions, globals)`` of the click that typer runs on (typer >= 0.20 carries its
    own copy)."""
    try:
        from typer._click import exceptions, globals
    except ImportError:  # pragma: no cover - older typer with the click package
        from click import exceptions, globals
    return exceptions, globals


def _usage_error(message: str) -> Exception:
    """A usage error of the running command (exit status 2, one line naming its ``--help``),
    as click's own."""
    exceptions, globals_ = _click()
    return exceptions.UsageError(message, ctx=globals_.get_current_context(silent=True))


def _task_measure_rows() -> list[tuple[str, str]]:
    """(summary key, label) of the tasks' own measures: GetUp's success rate and
    :data:`~robocup_gym.train.metrics.TASK_MEASURES`."""
    from robocup_gym.train.metrics import TASK_MEASURES

    return [("success_rate", "success rate")] + [
        (f"{key}_mean", label) for key, label in TASK_MEASURES.items()
    ]


def _robot_types(types: str | None) -> list[int] | None:
    """``--types 0,1,2`` as numbers (``None`` stays ``None``); exits with a clear error."""
    if types is None:
        return None
    try:
        return [int(t) for t in types.split(",")]
    except ValueError:
        _fail(f"--types expects numbers like 0,1,2, got {types!r}")


def _fail(message: str, code: int = 1):
    from rich.console import Console
    from rich.markup import escape

    Console(stderr=True, soft_wrap=True).print(
        f"[bold red]error:[/bold red] {escape(message)}", highlight=False
    )
    raise typer.Exit(code)


def _single_thread_torch() -> None:
    """Inference of small MLPs is fastest (and immune to busy cores) on one thread."""
    import torch

    torch.set_num_threads(1)


def _backend(backend: str | None, engine: str | None) -> str | None:
    """``--backend``/``--engine`` as one backend name (``None`` when neither is given)."""
    if backend is None and engine is None:
        return None
    from robocup_gym.backends import BackendNotAvailableError, resolve_backend

    try:
        return resolve_backend(backend, engine)
    except BackendNotAvailableError as exc:
        _fail(str(exc))


_RESUME_OPTIONS = {"timesteps", "n_workers"}
"""TrainConfig options a resumed run takes (its new total; where its environments step)."""


def _placement(ray: bool | None, ray_address: str | None, n_workers: int | None) -> dict[str, Any]:
    """Where a run's environments step (``--ray/--no-ray``, ``--ray-address``, ``--n-workers``),
    as TrainConfig fields; only those given. Without Ray installed, ``--ray`` says how to get
    it."""
    out: dict[str, Any] = {}
    if n_workers is not None:
        out["n_workers"] = n_workers
    if ray is False:
        if ray_address:
            _fail("--no-ray and --ray-address contradict each other")
        out["vec_env"], out["ray_address"] = "auto", ""
    elif ray or ray_address:
        from robocup_gym.train.ray_vecenv import import_ray

        try:
            import_ray()
        except ImportError as exc:
            _fail(str(exc))
        out["vec_env"] = "ray"
        out["ray_address"] = ray_address or ""
    return out


def _parse_assignments(items: list[str] | None, what: str) -> dict[str, Any]:
    """``["a=1", "b=[1, 2]"]`` → ``{"a": 1, "b": [1, 2]}`` (values read as YAML; ``3e-4`` is a
    number)."""
    from robocup_gym.train.config import load_yaml

    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            _fail(f"{what} expects KEY=VALUE, got {item!r}")
        out[key.strip()] = load_yaml(value)
    return out


_NOT_TRAIN_OPTIONS = (
    "task",  # the command's argument
    "env_id",  # filled in by the trainer
    "env_config",
    "env_kwargs",  # --env KEY=VALUE
    "algo_kwargs",  # --hp KEY=VALUE
    "selfplay",  # --selfplay KEY=VALUE
    "backend",  # --engine / --backend
    "vec_env",  # --ray / --no-ray
    "ray_address",  # --ray-address (implies --ray)
)
"""TrainConfig fields the train command takes in its own way, not as ``--field-name``."""

_TRAIN_OPTION_EXTRAS: dict[str, dict[str, Any]] = {
    "init_from": {"type": Path, "exists": True, "file_okay": False},
    "assist_max_tilt_deg": {"flags": ("--assist-max-tilt-deg", "--assist-max-tilt")},
}
"""Option settings beyond the field's type: a path that must exist, an extra flag name."""


def _option_help(doc: str, default: Any) -> str:
    """A field's docstring as an option's help: its first sentence, without reST markup, with
    the default."""
    import re

    text = " ".join(doc.split())
    text = re.sub(r":\w+:`~?([\w.]*\.)?([^`]+)`", r"\2", text)
    text = text.replace("``", "")
    m = re.match(r"(.+?[.])(\s|$)", text)
    first = m.group(1) if m else text
    if default in ("", None):
        return first
    return f"{first.rstrip('.')} (default: {default})."


def _train_config_parameters() -> list:
    """One keyword parameter of the train command per :class:`TrainConfig` field (but
    :data:`_NOT_TRAIN_OPTIONS`): ``--field-name``, typed as the field, help from its docstring,
    ``None`` when not given (the config file's or the default value then holds)."""
    import dataclasses
    import inspect
    import typing

    from robocup_gym.train.config import TrainConfig

    hints = typing.get_type_hints(TrainConfig)
    docs = TrainConfig.field_docs()
    params = []
    for f in dataclasses.fields(TrainConfig):
        if f.name in _NOT_TRAIN_OPTIONS:
            continue
        extra = dict(_TRAIN_OPTION_EXTRAS.get(f.name, {}))
        kind = extra.pop("type", hints[f.name])
        flag = "--" + f.name.replace("_", "-")
        flags = extra.pop("flags", (flag,))
        if kind is bool:
            flags = (f"{flag}/--no-{f.name.replace('_', '-')}",)
        default = f.default if f.default is not dataclasses.MISSING else None
        option = typer.Option(
            *flags, help=_option_help(docs.get(f.name, ""), default), show_default=False, **extra
        )
        params.append(
            inspect.Parameter(
                f.name,
                inspect.Parameter.KEYWORD_ONLY,
                default=None,
                annotation=Annotated[kind | None, option],
            )
        )
    return params


def _with_config_options(func):
    """``func`` (which takes ``**config``) with a typed parameter per TrainConfig field added
    to its signature, so that typer makes an option of each."""
    import inspect

    sig = inspect.signature(func, eval_str=True)
    own = [p for p in sig.parameters.values() if p.kind is not inspect.Parameter.VAR_KEYWORD]
    own = [p.replace(kind=inspect.Parameter.KEYWORD_ONLY) for p in own]
    params = own + _train_config_parameters()
    func.__signature__ = sig.replace(parameters=params)
    func.__annotations__ = {p.name: p.annotation for p in params}
    return func


if typer is not None:
    app = typer.Typer(
        name="robocup-gym",
        help="Train RoboCup 3D Nao skills on SimSpark's physics (ODE; MuJoCo as the fast "
        "approximation): train, eval, export to ONNX, reproduce the paper, serve the "
        "rcssserver3d protocol.",
        no_args_is_help=True,
        add_completion=False,
        pretty_exceptions_enable=False,
    )
    experiments_app = typer.Typer(
        help="Reproduce the paper's experiments; learning curves of the locomotion tasks.",
        no_args_is_help=True,
        add_completion=False,
    )
    app.add_typer(experiments_app, name="experiments")

    # ------------------------------------------------------------------------------ train
    def train(
        task: Annotated[
            str | None,
            typer.Argument(
                help="Task: velocity-kick, simple-kick, walk, get-up, target-kick, long-kick, "
                "dribble (see `robocup-gym tasks`), or a team scenario: penalty, keepaway, "
                "game-2v2, game-3v3, …"
            ),
        ] = None,
        out: Annotated[Path, typer.Option(help="Parent folder of run folders.")] = Path("runs"),
        engine: Annotated[
            str | None,
            typer.Option(
                help="Physics engine: ode (SimSpark's own step, exact; the default) or mujoco "
                "(fast; its kicks do not work on rcssserver3d)."
            ),
        ] = None,
        backend: Annotated[
            str | None,
            typer.Option(help="Instead of --engine: ode, mujoco or rcssserver3d (a real server)."),
        ] = None,
        config: Annotated[
            Path | None,
            typer.Option(
                help="YAML file with any TrainConfig fields (CLI flags win).",
                exists=True,
                dir_okay=False,
            ),
        ] = None,
        resume: Annotated[
            Path | None,
            typer.Option(
                help="Continue this run folder from its newest checkpoint.",
                exists=True,
                file_okay=False,
            ),
        ] = None,
        env: Annotated[
            list[str] | None,
            typer.Option(
                "--env", help="Environment option KEY=VALUE (repeatable), e.g. --env wait_steps=20."
            ),
        ] = None,
        hp: Annotated[
            list[str] | None,
            typer.Option(
                "--hp",
                help="Algorithm hyperparameter KEY=VALUE (repeatable), e.g. "
                "--hp learning_rate=3e-4.",
            ),
        ] = None,
        selfplay: Annotated[
            list[str] | None,
            typer.Option(
                "--selfplay",
                help="Team scenarios: opponent setting KEY=VALUE (repeatable): snapshot_every, "
                "pool_size, scripted_share.",
            ),
        ] = None,
        ray: Annotated[
            bool | None,
            typer.Option(
                "--ray/--no-ray",
                help="Run the environment workers as Ray actors (an embedded Ray on this "
                "machine; needs the ray extra); --no-ray resumes a Ray run on local workers.",
                show_default=False,
            ),
        ] = None,
        ray_address: Annotated[
            str | None,
            typer.Option(
                "--ray-address",
                help="Join this Ray cluster (auto, or HOST:PORT of `ray start --head`); implies "
                "--ray.",
            ),
        ] = None,
        progress: Annotated[bool, typer.Option(help="Show the progress bar.")] = True,
        **options: Any,
    ) -> None:
        """Train a policy with Stable-Baselines3 (defaults: the paper's PPO setup), or a team
        on a team scenario (penalty, keepaway, game-2v2, …: one policy shared by the team's
        players, against the scripted team and the policy's earlier versions). Every
        TrainConfig field is an option (--n-envs, --timesteps, …).

        Writes runs/<task>-<algo>-<time>/ with config.yaml, model.zip, checkpoints/, tb/
        (TensorBoard), progress.csv (learning curve) and evaluations.jsonl; a team run also
        opponents/ (the snapshot pool and the ratings).
        """
        from robocup_gym.train.config import TrainConfig
        from robocup_gym.train.trainer import train as run_training

        given = {k: v for k, v in options.items() if v is not None}
        if "init_from" in given:
            given["init_from"] = str(given["init_from"])
        console = _console()
        try:
            if resume is not None:
                refused = ["TASK"] if task is not None else []
                refused += [
                    name
                    for name, value in (
                        ("--config", config),
                        ("--env", env),
                        ("--hp", hp),
                        ("--selfplay", selfplay),
                    )
                    if value
                ]
                refused += [
                    "--" + k.replace("_", "-") for k in sorted(set(given) - _RESUME_OPTIONS)
                ]
                if refused:
                    _fail(
                        f"--resume continues a run with its own config; {', '.join(refused)} "
                        "cannot change it (a resume takes --timesteps, --n-workers, "
                        "--ray/--no-ray and --ray-address)"
                    )
                result = run_training(
                    resume=resume,
                    extra_timesteps=given.get("timesteps"),
                    console=console,
                    progress=progress,
                    placement=_placement(ray, ray_address, given.get("n_workers")),
                )
            else:
                cfg = TrainConfig.load(config) if config is not None else TrainConfig()
                env_kw = {**cfg.env_kwargs, **_parse_assignments(env, "--env")}
                algo_kw = dict(cfg.algo_kwargs)
                algo = given.get("algo")
                if algo is not None and algo.lower() != cfg.algo:
                    algo_kw = {}  # hyperparameters of another algorithm do not carry over
                algo_kw.update(_parse_assignments(hp, "--hp"))
                selfplay_kw = {**cfg.selfplay, **_parse_assignments(selfplay, "--selfplay")}
                given.pop("n_workers", None)
                cfg = cfg.merged(
                    task=task,
                    backend=_backend(backend, engine),
                    env_kwargs=env_kw,
                    algo_kwargs=algo_kw,
                    selfplay=selfplay_kw,
                    **given,
                    **_placement(ray, ray_address, options.get("n_workers")),
                )
                result = run_training(cfg, out=out, console=console, progress=progress)
        except typer.Exit:
            raise
        except (ValueError, FileNotFoundError, RuntimeError, OSError, ImportError) as exc:
            _fail(str(exc))
        if result.interrupted:  # 128 + the signal, as a shell reports a process it stopped
            raise typer.Exit(128 + (result.signal or 2))

    app.command()(_with_config_options(train))

    # ------------------------------------------------------------------------------ eval
    @app.command("eval")
    def eval_(
        run: Annotated[
            Path | None,
            typer.Argument(help="Run folder (or --pretrained).", exists=True, file_okay=False),
        ] = None,
        pretrained: Annotated[
            str | None,
            typer.Option(
                "--pretrained",
                help="Evaluate a policy shipped with the package instead of a run (e.g. "
                "get-up; `robocup-gym tasks` lists them).",
            ),
        ] = None,
        episodes: Annotated[int, typer.Option(help="Episodes to run (>= 1).")] = 10,
        video: Annotated[
            Path | None,
            typer.Option(help="Record episodes to this .mp4 (or .gif); headless: MUJOCO_GL=egl."),
        ] = None,
        video_episodes: Annotated[int, typer.Option(help="Episodes in the video (>= 1).")] = 1,
        seed: Annotated[int, typer.Option(help="Seed of the first episode.")] = 100_000,
        checkpoint: Annotated[
            Path | None, typer.Option(help="Evaluate this checkpoint instead of model.zip.")
        ] = None,
        deterministic: Annotated[
            bool, typer.Option(help="Deterministic actions (the policy's mean).")
        ] = True,
        engine: Annotated[
            str | None,
            typer.Option(
                help="Evaluate on this physics engine instead of the run's: ode (SimSpark's "
                "own step) or mujoco."
            ),
        ] = None,
        backend: Annotated[
            str | None,
            typer.Option(
                help="Instead of --engine: ode, mujoco or rcssserver3d (a real server, "
                "closed-loop)."
            ),
        ] = None,
    ) -> None:
        """Evaluate a run (or a shipped policy) deterministically; the last line of output is one
        JSON object."""
        from rich.table import Table

        from robocup_gym.train.evaluate import check_renderer, ensure_gl_backend, evaluate_run

        _single_thread_torch()
        console = _console()
        if run is None and pretrained is None:
            raise _usage_error("Missing argument 'run' (a run folder, or --pretrained NAME)")
        if run is not None and pretrained is not None:
            _fail("give a run folder or --pretrained NAME, not both")
        if pretrained is not None:
            if video is not None or checkpoint is not None or not deterministic:
                _fail(
                    "--pretrained evaluates the shipped ONNX policy: no --video/--checkpoint/"
                    "--no-deterministic"
                )
            _eval_pretrained(console, pretrained, episodes, seed, _backend(backend, engine))
            return
        try:
            if video is not None:
                ensure_gl_backend()
                check_renderer()
            with console.status(f"evaluating {run} ({episodes} episodes)…"):
                summary = evaluate_run(
                    run,
                    episodes=episodes,
                    seed=seed,
                    deterministic=deterministic,
                    video=video,
                    video_episodes=video_episodes,
                    checkpoint=checkpoint,
                    backend=_backend(backend, engine),
                )
        except typer.Exit:
            raise
        except (ValueError, FileNotFoundError, RuntimeError) as exc:
            _fail(str(exc))
        table = Table(
            title=f"{summary['task']} · {summary['algo'].upper()} · {summary['backend']} · "
            f"{summary['timesteps_trained']:,} steps · {summary['episodes']} episodes"
        )
        table.add_column("metric")
        table.add_column("mean", justify="right")
        table.add_column("std", justify="right")

        def fmt(x):
            return "–" if x is None else f"{x:.3f}"

        table.add_row(
            "ball x-displacement (m)", fmt(summary["ball_dx_mean"]), fmt(summary["ball_dx_std"])
        )
        table.add_row(
            "ball distance (m)",
            fmt(summary["ball_distance_mean"]),
            fmt(summary["ball_distance_std"]),
        )
        table.add_row("episode return", fmt(summary["return_mean"]), fmt(summary["return_std"]))
        table.add_row("fall rate", fmt(summary["fall_rate"]), "")
        table.add_row("episode length (steps)", fmt(summary["length_mean"]), "")
        for key, label in _task_measure_rows():  # the task's own measures, where it has them
            if summary.get(key) is not None:
                table.add_row(label, fmt(summary[key]), "")
        console.print(table)
        if summary.get("video"):
            console.print(f"video: {summary['video']}")
        if summary.get("written"):
            console.print(f"written: {summary['written']}")
        print(json.dumps(summary), flush=True)

    def _eval_pretrained(console, name: str, episodes: int, seed: int, backend) -> None:
        from robocup_gym.train.pretrained import evaluate_pretrained

        try:
            with console.status(f"evaluating the shipped policy {name} ({episodes} episodes)…"):
                summary = evaluate_pretrained(name, episodes=episodes, seed=seed, backend=backend)
        except typer.Exit:
            raise
        except (ValueError, FileNotFoundError, RuntimeError) as exc:
            _fail(str(exc))
        keys = (
            ("return_mean", "episode return"),
            ("fall_rate", "fall rate"),
            ("length_mean", "episode length (steps)"),
            *_task_measure_rows(),
            ("ball_dx_mean", "ball x-displacement (m)"),
        )
        console.print(
            f"[bold]{summary['pretrained']}[/bold] ({summary['env_id']}) · {summary['backend']}"
            f" · {summary['episodes']} episodes"
        )
        for key, label in keys:
            if summary.get(key) is not None:
                console.print(f"  {label}: {summary[key]:.3f}")
        print(json.dumps(summary), flush=True)

    # ------------------------------------------------------------------------------ export
    @app.command()
    def export(
        run: Annotated[Path, typer.Argument(help="Run folder.", exists=True, file_okay=False)],
        onnx: Annotated[Path, typer.Option("--onnx", help="Output .onnx file.")],
        checkpoint: Annotated[
            Path | None, typer.Option(help="Export this checkpoint instead of model.zip.")
        ] = None,
        atol: Annotated[float, typer.Option(help="Verification tolerance.")] = 1e-5,
        env: Annotated[
            list[str] | None,
            typer.Option(
                "--env",
                help="Environment option KEY=VALUE the policy is meant for, over the run's "
                "(repeatable), e.g. --env start_side=front for a get-up from the front.",
            ),
        ] = None,
    ) -> None:
        """Export the policy to ONNX (verified against the SB3 policy) + a JSON description."""
        from robocup_gym.train.export import ExportError, export_onnx

        _single_thread_torch()
        console = _console()
        try:
            overrides = _parse_assignments(env, "--env")
            with console.status("exporting and verifying…"):
                meta = export_onnx(
                    run, onnx, checkpoint=checkpoint, atol=atol, env_overrides=overrides
                )
        except (ExportError, ValueError, FileNotFoundError) as exc:
            _fail(str(exc))
        v = meta["verification"]
        console.print(
            f"[bold green]exported[/bold green] {onnx} (+ {onnx.with_suffix('.json')}): "
            f"obs {meta['input']['shape'][1]} → action {meta['output']['shape'][1]}; matches the "
            f"SB3 policy to {v['max_abs_diff']:.2e} on {v['samples']} observations"
        )
        if str(meta.get("env_id", "")).startswith("soccer/"):
            from robocup_gym.train.selfplay import next_command
            from robocup_gym.train.tasks import task_name

            console.print(f"play it: {next_command(task_name(meta['env_id']), onnx)}")
        else:
            console.print(f"run it on a server: robocup-gym agent {onnx} --port 3100")
        print(
            json.dumps(
                {
                    "onnx": str(onnx),
                    "verification": v,
                    "env_id": meta["env_id"],
                    "obs_size": meta["input"]["shape"][1],
                    "action_size": meta["output"]["shape"][1],
                }
            ),
            flush=True,
        )

    # ------------------------------------------------------------------------------ agent
    @app.command()
    def agent(
        onnx: Annotated[
            Path | None,
            typer.Argument(help="Exported policy (.onnx), or --pretrained.", exists=True),
        ] = None,
        pretrained: Annotated[
            str | None,
            typer.Option(
                "--pretrained", help="Run a policy shipped with the package (e.g. get-up)."
            ),
        ] = None,
        host: Annotated[str, typer.Option(help="Server address.")] = "127.0.0.1",
        port: Annotated[int, typer.Option(help="Agent port.")] = 3100,
        monitor_port: Annotated[
            int | None,
            typer.Option(help="Monitor/trainer port to reset episodes (e.g. 3200)."),
        ] = None,
        episodes: Annotated[int, typer.Option(help="Episodes to run.")] = 1,
        team: Annotated[str, typer.Option(help="Team name.")] = "RoboCupGym",
        unum: Annotated[int, typer.Option(help="Uniform number (0 = server's choice).")] = 0,
        sync: Annotated[bool, typer.Option(help="Send (syn) every cycle.")] = True,
        monitor_interval: Annotated[
            int,
            typer.Option(
                help="The server's cycles per monitor frame (2: rcssserver3d's default and "
                "robocup-gym serve's)."
            ),
        ] = 2,
        seed: Annotated[int, typer.Option(help="Seed of the first episode (as eval).")] = 100_000,
        env: Annotated[
            list[str] | None,
            typer.Option(
                "--env",
                help="Environment option KEY=VALUE over the policy's own (repeatable; not one "
                "that changes the observation), e.g. --env max_episode_steps=1000.",
            ),
        ] = None,
        command: Annotated[
            str | None,
            typer.Option(
                "--command",
                help="A Walk policy's velocity command, 'FORWARD,LEFT,TURN' in m/s, m/s and "
                "deg/s (CCW positive), held for the whole episode, e.g. --command 0.5,0,0.",
            ),
        ] = None,
    ) -> None:
        """Drive a robot with an exported policy over the rcssserver3d protocol.

        With --monitor-port the episodes start as in training and ground truth comes from the
        monitor stream (the policy sees what it sees in `eval`); without it, from the See
        extensions of a server started with ground truth. A walk goes where --command says."""
        from robocup_gym.train.agent import run_onnx_agent

        console = _console()
        if onnx is None and pretrained is None:
            raise _usage_error("Missing argument 'onnx' (an exported policy, or --pretrained)")
        if onnx is not None and pretrained is not None:
            _fail("give an exported policy (.onnx) or --pretrained NAME, not both")
        if pretrained is not None:
            from robocup_gym.train.pretrained import pretrained_path

            try:
                onnx = pretrained_path(pretrained)
            except ValueError as exc:
                _fail(str(exc))

        overrides = _parse_assignments(env, "--env")
        reset_options: dict[str, Any] = {}
        if command is not None:
            parts = command.split(",")
            try:
                velocity = [float(p) for p in parts]
            except ValueError:
                velocity = []
            if len(velocity) != 3 or not all(math.isfinite(v) for v in velocity):
                raise _usage_error(
                    f"--command expects FORWARD,LEFT,TURN (m/s, m/s, deg/s), got {command!r}"
                )
            from robocup_gym.train.onnx_policy import read_metadata
            from robocup_gym.train.pretrained import recorded_env_options

            try:
                meta = read_metadata(onnx)
            except (OSError, ValueError) as exc:
                _fail(str(exc))
            if "command_change_steps" not in recorded_env_options(meta):
                _fail(
                    f"--command gives a Walk policy its velocity_command; {onnx} is a "
                    f"{meta.get('env_id')} policy, which takes none"
                )
            reset_options["velocity_command"] = tuple(velocity)
            overrides.setdefault("command_change_steps", 0)

        def report(rep) -> None:
            d, t = rep.ball_displacement, rep.torso_displacement
            console.print(
                f"episode: {rep.steps} steps, fallen={rep.fallen}, ball displacement "
                + ("–" if d is None else f"({d[0]:+.2f}, {d[1]:+.2f}) m")
                + ("" if t is None else f", torso moved ({t[0]:+.2f}, {t[1]:+.2f}) m")
                + ("" if rep.success is None else f", success={rep.success}")
                + ("" if rep.steps_to_up is None else f" (up at step {rep.steps_to_up})")
            )

        try:
            run_onnx_agent(
                str(onnx),
                host=host,
                port=port,
                monitor_port=monitor_port,
                episodes=episodes,
                team=team,
                unum=unum,
                sync=sync,
                monitor_interval=monitor_interval,
                seed=seed,
                on_episode=report,
                env_overrides=overrides,
                reset_options=reset_options,
            )
        except (OSError, RuntimeError, ValueError) as exc:
            _fail(str(exc))

    # ------------------------------------------------------------------------------ serve
    @app.command(
        context_settings={"allow_extra_args": True, "ignore_unknown_options": True},
        add_help_option=False,
    )
    def serve(ctx: typer.Context) -> None:
        """Serve the embedded world over the rcssserver3d protocol (agents, RoboViz); the
        options of `python -m robocup_gym.server` (see robocup-gym serve --help)."""
        try:
            from robocup_gym.server.__main__ import main as server_main
        except ImportError as exc:
            _fail(f"the server is not available in this installation (robocup_gym.server: {exc})")
        raise typer.Exit(server_main(list(ctx.args), prog="robocup-gym serve"))

    # ------------------------------------------------------------------------------ match
    @app.command()
    def match(
        team_a: Annotated[
            str,
            typer.Argument(
                help="A team: scripted, standing, a team run's folder, an exported team policy "
                "(.onnx) or pretrained:NAME."
            ),
        ],
        team_b: Annotated[str, typer.Argument(help="The other team.")],
        games: Annotated[int, typer.Option(help="Games to play (sides change every game).")] = 20,
        players: Annotated[
            int | None, typer.Option(help="Players a side (1-11; default 2, a penalty 1).")
        ] = None,
        seconds: Annotated[
            float | None,
            typer.Option(help="Game time of each game, s (default 120; a penalty's 10)."),
        ] = None,
        scenario: Annotated[
            str,
            typer.Option(
                help="game, or penalty: the first team's striker against the second's "
                "goalkeeper in every game."
            ),
        ] = "game",
        types: Annotated[
            str | None,
            typer.Option(help="Each team's robot types, e.g. 0,1 (default 0,1,2,3,4 in turn)."),
        ] = None,
        engine: Annotated[str, typer.Option(help="ode (SimSpark's physics) or mujoco.")] = "ode",
        seed: Annotated[int, typer.Option(help="Game k is seeded with seed + k.")] = 0,
        video: Annotated[
            Path | None,
            typer.Option(
                help="Record the first game to this .mp4 (or .gif) file, from the side, "
                "following the ball (headless: MUJOCO_GL=egl)."
            ),
        ] = None,
        on: Annotated[
            str,
            typer.Option(
                help="in-process, serve (a fresh robocup-gym serve each game) or rcssserver3d "
                "(a real one: RCSSSERVER3D or PATH); on a server each player is its own "
                "connection acting on its own perceptors."
            ),
        ] = "in-process",
    ) -> None:
        """Play two teams against each other, in-process (multi-agent soccer with skill
        actions) or on a server; a table, then one JSON object from the first team's side."""
        import json

        from rich.table import Table

        try:
            from robocup_gym.soccer.match import SERVERS, play_match, play_server_match
        except ImportError as exc:
            _fail(str(exc))
        if on not in ("in-process", *SERVERS):
            _fail(f"--on must be in-process, {', '.join(SERVERS)}; got {on!r}")
        if on != "in-process" and (scenario != "game" or video is not None):
            _fail(f"on {on} a match plays games (no --scenario penalty, no --video)")
        robot_types = _robot_types(types)
        console = _console()

        def progress(k: int, g) -> None:
            console.print(
                f"game {k + 1}/{games}: {team_a} ({g.a_side}) {g.goals_for} : "
                f"{g.goals_against} {team_b}"
                + (" (the simulation diverged)" if g.diverged else ""),
                highlight=False,
            )

        try:
            if on == "in-process":
                result = play_match(
                    team_a,
                    team_b,
                    games=games,
                    players=players,
                    seconds=seconds,
                    robot_types=robot_types,
                    engine=engine,
                    seed=seed,
                    on_game=progress,
                    video=video,
                    scenario=scenario,
                )
            else:
                result = play_server_match(
                    team_a,
                    team_b,
                    server=on,
                    games=games,
                    players=2 if players is None else players,
                    seconds=120.0 if seconds is None else seconds,
                    robot_types=robot_types,
                    engine=engine,
                    seed=seed,
                    on_game=progress,
                )
        except (ValueError, RuntimeError, OSError) as exc:
            _fail(str(exc))
        summary = result.summary
        first = result.games[0]
        if scenario == "penalty":
            title = f"{team_a}'s striker against {team_b}'s goalkeeper: {first.seconds:g} s each"
        else:
            per_side = players if players is not None else 2
            title = f"{team_a} against {team_b}: {per_side} a side, {first.seconds:g} s a game"
        table = Table(title=title)
        for col in ("games", "wins", "draws", "losses", "goals for", "goals against", "ci95"):
            table.add_column(col, justify="right")
        table.add_row(
            *map(
                str,
                (
                    summary["games"],
                    summary["wins"],
                    summary["draws"],
                    summary["losses"],
                    summary["goals_for"],
                    summary["goals_against"],
                    summary["goal_difference_ci95"],
                ),
            )
        )
        console.print(table)
        print(json.dumps(summary))

    # ------------------------------------------------------------------------------ team
    @app.command()
    def team(
        policy: Annotated[
            str,
            typer.Argument(
                help="The team: scripted, standing, a team run's folder, an exported team "
                "policy (.onnx) or pretrained:NAME."
            ),
        ],
        host: Annotated[str, typer.Option(help="The server's address.")] = "127.0.0.1",
        port: Annotated[int, typer.Option(help="The server's agent port.")] = 3100,
        team_name: Annotated[
            str, typer.Option("--team", help="The team's name on the server.")
        ] = "RoboCupGym",
        players: Annotated[int, typer.Option(help="Players (1-11), each its own connection.")] = 2,
        types: Annotated[
            str | None,
            typer.Option(help="The players' robot types, e.g. 0,1 (default 0,1,2,3 in turn)."),
        ] = None,
        seconds: Annotated[
            float | None,
            typer.Option(help="Stop after this much game time, s (default: until GameOver)."),
        ] = None,
        timeout: Annotated[
            float,
            typer.Option(
                help="Seconds without a percept before the server counts as gone (and, up to "
                "5 s, to wait for a starting server)."
            ),
        ] = 10.0,
    ) -> None:
        """Play a team on a server (robocup-gym serve or rcssserver3d): each player its own
        agent connection, acting on its own perceptors (it places itself from the landmarks it
        sees) with the shipped skills; the server's referee starts the game. Prints the goals
        as they come and, last, one JSON object."""
        import json

        if not 1 <= port <= 65535:
            _fail(f"port {port} is not a port number (1-65535)")
        if not timeout > 0:
            _fail(f"--timeout must be a positive number of seconds, got {timeout}")
        robot_types = _robot_types(types)
        try:
            from robocup_gym.soccer.match import make_team
            from robocup_gym.soccer.remote import ServerTeam
        except ImportError as exc:
            _fail(str(exc))
        console = _console()
        try:
            chosen = make_team(policy)
            check = getattr(chosen, "check_fits", None)
            if check is not None:
                check("game", players, penalties=False)
            with ServerTeam(
                chosen, host, port, team_name, players, robot_types, timeout=timeout
            ) as playing:
                console.print(
                    f"{team_name}: {players} player(s) on {host}:{port}, playing "
                    f"{playing.side}; waiting for the kick-off",
                    highlight=False,
                )
                result = playing.play(seconds, on_event=lambda e: console.print(e, highlight=False))
        except (OSError, ValueError, RuntimeError) as exc:
            _fail(str(exc))
        print(json.dumps(result.summary))
        if result.end not in ("GameOver", "time"):
            _fail(result.end)

    # ------------------------------------------------------------------------------ tasks
    @app.command()
    def tasks() -> None:
        """List the registered tasks and the robots they run on."""
        from robocup_gym.robot.league import RcsssmjUnavailableError, league_robot_names
        from robocup_gym.train.tasks import registered_tasks

        for name, env_id in registered_tasks().items():
            print(f"{name:20s} {env_id}")
        print(
            "\nteam scenarios (one policy for a team's players; the soccer extra): penalty, "
            "keepaway, game-1v1 … game-11v11"
        )
        try:
            league = ", ".join(league_robot_names()) + " (--env robot=NAME)"
        except RcsssmjUnavailableError:
            league = "not installed (pip install 'robocup-gym[mj]')"
        print(f"\nrobots: the Nao, types 0-4 (--env robot_type=N); the league's: {league}")
        from robocup_gym.train.pretrained import pretrained_names

        shipped = ", ".join(pretrained_names()) or "none yet"
        print(f"pretrained policies (eval/agent --pretrained NAME): {shipped}")

    # ------------------------------------------------------------------------------ experiments
    @experiments_app.command("paper")
    def experiments_paper(
        scale: Annotated[
            str,
            typer.Option(help="quick (11–25 min on 2 cores) or full (5M steps)."),
        ] = "quick",
        out: Annotated[Path, typer.Option(help="Output folder.")] = Path("runs/paper"),
        only: Annotated[
            list[str] | None,
            typer.Option(help="Run only these figures: algos, tasks, workers (repeatable)."),
        ] = None,
        seeds: Annotated[
            int | None, typer.Option(help="Seeds per curve (default by scale).")
        ] = None,
        timesteps: Annotated[
            int | None, typer.Option(help="Override the steps per run of the scale.")
        ] = None,
        engine: Annotated[
            str, typer.Option(help="Physics engine: ode (the default) or mujoco.")
        ] = "ode",
    ) -> None:
        """Reproduce the paper's three figures as CSV + PNG (PPO vs SAC, SimpleKick vs
        VelocityKick, wall-clock vs workers)."""
        from robocup_gym.train.experiments import SCALES, run_paper

        if scale not in SCALES:
            _fail(f"--scale must be one of {', '.join(SCALES)}")
        try:
            summary = run_paper(
                scale,
                out,
                only=only,
                seeds=seeds,
                timesteps=timesteps,
                engine=engine,
                console=_console(),
            )
        except (ValueError, FileNotFoundError) as exc:
            _fail(str(exc))
        print(json.dumps(summary), flush=True)

    @experiments_app.command("locomotion")
    def experiments_locomotion(
        scale: Annotated[
            str, typer.Option(help="quick (100k steps per run) or full (5M).")
        ] = "quick",
        out: Annotated[Path, typer.Option(help="Output folder.")] = Path("runs/locomotion"),
        task: Annotated[
            list[str] | None,
            typer.Option(help="Run only these tasks: walk, get-up (repeatable)."),
        ] = None,
        seeds: Annotated[int, typer.Option(help="Seeds per task.")] = 1,
        timesteps: Annotated[
            int | None, typer.Option(help="Override the steps per run of the scale.")
        ] = None,
        evaluations: Annotated[
            int, typer.Option(help="Deterministic evaluations per run (the curve's points).")
        ] = 8,
        engine: Annotated[
            str, typer.Option(help="Physics engine: ode (the default) or mujoco.")
        ] = "ode",
    ) -> None:
        """Learning curves of the locomotion tasks as CSV + PNG, in the paper figures' style
        (Walk: mean forward speed; GetUp: success rate; both with return and wall-clock)."""
        from robocup_gym.train.experiments import run_locomotion

        try:
            summary = run_locomotion(
                scale,
                out,
                tasks=task,
                seeds=seeds,
                timesteps=timesteps,
                evaluations=evaluations,
                engine=engine,
                console=_console(),
            )
        except (ValueError, FileNotFoundError) as exc:
            _fail(str(exc))
        print(json.dumps(summary), flush=True)

    @experiments_app.command("team")
    def experiments_team(
        runs: Annotated[list[Path], typer.Argument(help="Team run folders (train game-2v2 …).")],
        out: Annotated[Path, typer.Option(help="Output folder.")] = Path("runs/team"),
    ) -> None:
        """Learning curves of team runs as CSV + PNG: the goal difference and win rate against
        the scripted team and the TrueSkill rating against steps."""
        from robocup_gym.train.experiments import team_curves

        try:
            summary = team_curves(list(runs), out)
        except (ValueError, FileNotFoundError) as exc:
            _fail(str(exc))
        print(json.dumps(summary), flush=True)


def main(argv: list[str] | None = None) -> None:
    """Entry point of the ``robocup-gym`` script. Usage errors (an unknown command or option, a
    value of the wrong type, a missing argument) are one line on stderr, exit status 2."""
    _require_typer()
    cx = _click()[0]

    try:
        code = app(args=argv, standalone_mode=False)
    except getattr(cx, "NoArgsIsHelpError", ()) as exc:  # `robocup-gym` alone: the help
        sys.stdout.write(exc.ctx.get_help() + "\n")
        raise SystemExit(0) from None
    except cx.UsageError as exc:
        where = exc.ctx.command_path if exc.ctx is not None else "robocup-gym"
        message = " ".join(exc.format_message().split())
        sys.stderr.write(f"error: {message} (see {where} --help)\n")
        raise SystemExit(2) from None
    except cx.ClickException as exc:
        sys.stderr.write(f"error: {' '.join(exc.format_message().split())}\n")
        raise SystemExit(exc.exit_code) from None
    except (KeyboardInterrupt, getattr(cx, "Abort", KeyboardInterrupt)):
        sys.stderr.write("aborted\n")
        raise SystemExit(130) from None
    raise SystemExit(code if isinstance(code, int) else 0)


if __name__ == "__main__":
    main()

"""The commands that train and measure skills: ``train``, ``eval``, ``export``, ``tasks`` and
``experiments``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import typer

from robocup_gym.cli.app import app, experiments_app
from robocup_gym.cli.common import (
    _RESUME_OPTIONS,
    _backend,
    _console,
    _fail,
    _parse_assignments,
    _placement,
    _single_thread_torch,
    _task_measure_rows,
    _usage_error,
)
from robocup_gym.cli.options import _with_config_options


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
            help="Algorithm hyperparameter KEY=VALUE (repeatable), e.g. --hp learning_rate=3e-4.",
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
            help="Join this Ray cluster (auto, or HOST:PORT of `ray start --head`); implies --ray.",
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
            refused += ["--" + k.replace("_", "-") for k in sorted(set(given) - _RESUME_OPTIONS)]
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
            help="Instead of --engine: ode, mujoco or rcssserver3d (a real server, closed-loop)."
        ),
    ] = None,
    robot_type: Annotated[
        int | None,
        typer.Option(
            "--robot-type",
            help="On this Nao type (0-4) instead of the policy's own; a shipped policy with "
            "a policy of its own for the type runs that.",
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
        _eval_pretrained(console, pretrained, episodes, seed, _backend(backend, engine), robot_type)
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
                robot_type=robot_type,
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


def _eval_pretrained(
    console, name: str, episodes: int, seed: int, backend, robot_type: int | None
) -> None:
    from robocup_gym.train.pretrained import evaluate_pretrained

    try:
        with console.status(f"evaluating the shipped policy {name} ({episodes} episodes)…"):
            summary = evaluate_pretrained(
                name, episodes=episodes, seed=seed, backend=backend, robot_type=robot_type
            )
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
        + ("" if summary["robot_type"] is None else f" · Nao type {summary['robot_type']}")
        + f" · {summary['episodes']} episodes"
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
            meta = export_onnx(run, onnx, checkpoint=checkpoint, atol=atol, env_overrides=overrides)
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
    from robocup_gym.soccer.motions import motion_skills

    print(
        "motion skills of the game's skill actions (--env skills=[NAME, ...]): "
        + ", ".join(motion_skills())
    )
    try:
        league = ", ".join(league_robot_names()) + " (--env robot=NAME)"
    except RcsssmjUnavailableError:
        league = "not installed (pip install 'robocup-gym[mj]')"
    print(f"\nrobots: the Nao, types 0-4 (--env robot_type=N); the league's: {league}")
    from robocup_gym.train.pretrained import pretrained_names, pretrained_types

    def listed(name: str) -> str:
        types = pretrained_types(name)
        own = ", ".join(str(t) for t in types)
        return f"{name} (Nao types {own}: their own)" if types else name

    shipped = ", ".join(listed(n) for n in pretrained_names()) or "none yet"
    print(f"pretrained policies (eval/agent --pretrained NAME): {shipped}")


# ------------------------------------------------------------------------------ experiments
def _print_summary(experiment, *args, **kwargs) -> None:
    """Run ``experiment(*args, **kwargs)`` and print its summary as one JSON line (a bad
    argument or a missing run folder: one line on stderr, exit status 1)."""
    try:
        summary = experiment(*args, **kwargs)
    except (ValueError, FileNotFoundError) as exc:
        _fail(str(exc))
    print(json.dumps(summary), flush=True)


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
    seeds: Annotated[int | None, typer.Option(help="Seeds per curve (default by scale).")] = None,
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
    _print_summary(
        run_paper,
        scale,
        out,
        only=only,
        seeds=seeds,
        timesteps=timesteps,
        engine=engine,
        console=_console(),
    )


@experiments_app.command("locomotion")
def experiments_locomotion(
    scale: Annotated[str, typer.Option(help="quick (100k steps per run) or full (5M).")] = "quick",
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

    _print_summary(
        run_locomotion,
        scale,
        out,
        tasks=task,
        seeds=seeds,
        timesteps=timesteps,
        evaluations=evaluations,
        engine=engine,
        console=_console(),
    )


@experiments_app.command("team")
def experiments_team(
    runs: Annotated[list[Path], typer.Argument(help="Team run folders (train game-2v2 …).")],
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("runs/team"),
) -> None:
    """Learning curves of team runs as CSV + PNG: the goal difference and win rate against
    the scripted team and the TrueSkill rating against steps."""
    from robocup_gym.train.experiments import team_curves

    _print_summary(team_curves, list(runs), out)

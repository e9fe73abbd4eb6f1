"""Deterministic evaluation of a trained run, with an optional video.

Video frames come from MuJoCo's offscreen renderer. On a machine without a display set
``MUJOCO_GL=egl`` (GPU or Mesa's software EGL) or ``MUJOCO_GL=osmesa`` before starting Python;
``robocup-gym eval --video`` picks ``egl`` itself when no display is set. MP4 files need the
``imageio-ffmpeg`` package; a ``.gif`` file name writes a GIF with Pillow instead.
"""

from __future__ import annotations

import json
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from robocup_gym.backends import DEFAULT_ENGINE
from robocup_gym.envs.config import nao_type
from robocup_gym.train.episodes import run_episodes
from robocup_gym.train.metrics import summarize
from robocup_gym.train.pretrained import pretrained_env, pretrained_policy
from robocup_gym.train.run import RunInfo, load_model, load_run
from robocup_gym.train.tasks import make_env


def policy_and_env(
    policy: str,
    env_id: str,
    engine: str | None = None,
    env_overrides: dict[str, Any] | None = None,
):
    """``(env, act)`` for a benchmark: ``policy`` is a run folder (its task's environment with
    its options, on ``engine`` or the run's own simulator; ``act(obs)`` its deterministic
    action, observation statistics applied), ``"pretrained:NAME"`` (a shipped policy, on its
    own options) or ``"zero"`` (``env_id`` on ``engine``, default the default engine, and an
    action of zeros: a baseline). ``env_overrides`` replace some of the environment's options
    (a benchmark's harder starts, say)."""

    extra = dict(env_overrides or {})
    if policy == "zero":
        env = make_env(env_id, backend=engine or DEFAULT_ENGINE, env_kwargs=extra)
        zeros = np.zeros(env.action_space.shape)
        return env, lambda obs: zeros
    if policy.startswith("pretrained:"):
        onnx = pretrained_policy(policy.split(":", 1)[1], extra.get("robot_type"))
        return pretrained_env(onnx, engine, extra), onnx
    info = load_run(policy)
    model = load_model(info)
    normalize = info.obs_normalizer()
    cfg = info.config
    env = make_env(cfg.env_id, backend=engine or cfg.backend, env_kwargs=cfg.env_options(**extra))

    def act(obs):
        o = normalize(obs) if normalize is not None else obs
        return model.predict(o, deterministic=True)[0]

    return env, act


def add_benchmark_options(parser, task: str, episodes: int) -> None:
    """The options every skill benchmark (``benchmarks/walk.py``, ``getup.py``, ``kick.py``,
    ``dribble.py``) takes, on an ``argparse`` parser: the policy (a ``task`` run folder,
    ``pretrained:NAME`` or ``zero``), ``--episodes`` (default ``episodes``), ``--seed``,
    ``--backend`` (also ``--engine``: ode, mujoco, rcssserver3d or serve), ``--robot-type`` and
    ``--self-collisions``."""
    parser.add_argument(
        "policy",
        help=f"a {task} run folder, 'pretrained:NAME' (a shipped policy) or 'zero' (a "
        "zero-action baseline)",
    )
    parser.add_argument("--episodes", type=int, default=episodes)
    parser.add_argument("--seed", type=int, default=100_000)
    parser.add_argument(
        "--backend",
        "--engine",
        dest="backend",
        choices=("ode", "mujoco", "rcssserver3d", "serve"),
        default=None,
        help="the simulator: ode, mujoco, rcssserver3d (a real server, RCSSSERVER3D names "
        "its binary) or serve (robocup-gym serve on ODE, started for the benchmark, reached "
        "as a real server is); default: the run's own (ode for 'zero')",
    )
    parser.add_argument(
        "--robot-type",
        type=int,
        default=None,
        help="Nao type 0-4 (default: the run's own; a policy takes only types with its joints)",
    )
    parser.add_argument(
        "--self-collisions",
        action="store_true",
        help="run rcssserver3d's self-collision rule in-process (EnvConfig.self_collisions; a "
        "real server always applies it)",
    )
    parser.add_argument(
        "--env",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="an environment option over the policy's own (repeatable; values read as YAML), "
        "e.g. --env joint_start_noise_deg=0.5",
    )


def benchmark_policy_and_env(args, env_id: str, env_overrides: dict[str, Any] | None = None):
    """:func:`policy_and_env` for the options of :func:`add_benchmark_options` (``env_id`` for
    ``zero``), ``--env`` and ``--robot-type`` among the overrides.

    Raises:
        SystemExit: ``--episodes`` below 1, an ``--env`` without ``=``, or a policy or option
            that cannot be run (a shipped policy that does not exist, a run folder that is
            not one, an option's bad value): one line naming it, as the CLI's errors.
    """
    from robocup_gym.train.config import parse_assignments

    if args.episodes < 1:
        raise SystemExit(f"--episodes must be at least 1, got {args.episodes}")
    extra = dict(env_overrides or {})
    try:
        extra.update(parse_assignments(getattr(args, "env", None), "--env"))
    except ValueError as exc:
        raise SystemExit(str(exc)) from None
    if args.robot_type is not None:
        extra["robot_type"] = args.robot_type
    if getattr(args, "self_collisions", False):
        extra["self_collisions"] = True
    try:
        if args.backend != "serve":
            return policy_and_env(args.policy, env_id, args.backend, extra)
        return _on_serve(args.policy, env_id, extra)
    except (ValueError, FileNotFoundError) as exc:  # EnvConfigError is a ValueError
        raise SystemExit(f"error: {exc}") from None


def _on_serve(policy: str, env_id: str, extra: dict[str, Any]):
    """:func:`policy_and_env` on a ``robocup-gym serve`` (ODE, sync mode, real time off) started
    on free loopback ports and reached through the real-server backend in connect mode; closing
    the environment stops the server (which also ends with this process)."""
    from robocup_gym.server.bench import start_server_process, stop_server_process

    proc, agent_port, monitor_port = start_server_process(
        "--sync", "--no-real-time", "--engine", "ode"
    )
    ports = {"host": "127.0.0.1", "agent_port": agent_port, "monitor_port": monitor_port}
    try:
        env, act = policy_and_env(
            policy, env_id, "rcssserver3d", {**extra, "backend_options": ports}
        )
    except BaseException:
        stop_server_process(proc)
        raise
    close = env.close

    def close_env_and_server() -> None:
        try:
            close()
        finally:
            stop_server_process(proc)

    env.close = close_env_and_server
    return env, act


# ---------------------------------------------------------------------------------- video
def ensure_gl_backend() -> str:
    """Choose a headless OpenGL backend for MuJoCo when none is configured.

    Returns the ``MUJOCO_GL`` value in force. Must run before ``mujoco`` creates a context.
    """
    if not os.environ.get("MUJOCO_GL") and not os.environ.get("DISPLAY"):
        os.environ["MUJOCO_GL"] = "egl"
        os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    return os.environ.get("MUJOCO_GL", "glfw")


def _tiny_render() -> None:
    import mujoco

    model = mujoco.MjModel.from_xml_string(
        "<mujoco><worldbody><geom size='.1'/></worldbody></mujoco>"
    )
    renderer = mujoco.Renderer(model, 16, 16)
    renderer.close()


def check_renderer() -> None:
    """Make sure MuJoCo can render here (a tiny offscreen frame), before any episode runs.

    Raises:
        RuntimeError: one sentence naming ``MUJOCO_GL``/``DISPLAY`` as found, what failed, and
            what works instead.
    """
    gl = os.environ.get("MUJOCO_GL") or "glfw (default)"
    display = os.environ.get("DISPLAY")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # GLFW's warnings repeat what the error says
            _tiny_render()
    except Exception as exc:  # every GL failure becomes one clear error
        where = f"MUJOCO_GL={gl}" + (f", DISPLAY={display}" if display else ", no DISPLAY")
        detail = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        raise RuntimeError(
            f"cannot render the video with {where} ({type(exc).__name__}"
            + (f": {detail}" if detail else "")
            + "). Headless: MUJOCO_GL=egl (libEGL and a GPU driver) or MUJOCO_GL=osmesa "
            "(apt-get install libosmesa6); with a desktop, a DISPLAY whose X server is running; "
            "or leave out --video"
        ) from None


class FrameRecorder:
    """Collects RGB frames of an environment for a kick video.

    With the embedded world behind the environment, a free camera frames both the robot and the
    ball (it pulls back as the ball rolls away); otherwise ``env.render()`` is used (an
    environment made with ``render_mode="rgb_array"``).
    """

    def __init__(self, width: int = 480, height: int = 360, every: int = 1) -> None:
        self.width, self.height, self.every = width, height, max(1, every)
        self.frames: list[np.ndarray] = []
        self._renderer = None
        self._camera = None
        self._count = 0

    def __call__(self, env) -> None:
        self._count += 1
        if (self._count - 1) % self.every:
            return
        world = _find_world(env)
        if world is not None:
            frame = self._render_world(world)
        elif getattr(env, "render_mode", None) == "rgb_array":
            frame = env.render()
        else:
            raise RuntimeError(
                "this environment cannot be rendered: it has no render_mode='rgb_array' and no "
                "in-process world (video needs the ode or mujoco engine, not a real server)"
            )
        self.frames.append(np.asarray(frame, dtype=np.uint8))

    def _render_world(self, world) -> np.ndarray:
        import mujoco

        if self._renderer is None:
            self._renderer = mujoco.Renderer(world.model, self.height, self.width)
            cam = mujoco.MjvCamera()
            cam.type = mujoco.mjtCamera.mjCAMERA_FREE
            cam.azimuth, cam.elevation = 125.0, -20.0
            self._camera = cam
        torso = world.data.xpos[world.robot(0).torso_body]
        ball = world.ball_position()
        gap = float(np.linalg.norm((ball - torso)[:2]))
        self._camera.lookat[:] = 0.5 * (torso + ball)
        self._camera.lookat[2] = 0.2
        self._camera.distance = max(2.0, 1.2 * gap + 1.0)
        self._renderer.update_scene(world.data, camera=self._camera)
        return self._renderer.render().copy()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def save(self, path: str | os.PathLike, fps: float) -> Path:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        if not self.frames:
            raise RuntimeError("no frames were recorded")
        if path.suffix.lower() == ".gif":
            from PIL import Image

            imgs = [Image.fromarray(f) for f in self.frames]
            imgs[0].save(
                path, save_all=True, append_images=imgs[1:], duration=int(1000 / fps), loop=0
            )
            return path
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise RuntimeError(
                "writing MP4 needs the imageio-ffmpeg package (pip install imageio-ffmpeg); "
                "or give a .gif file name"
            ) from None
        import imageio.v2 as imageio

        with imageio.get_writer(path, fps=fps, codec="libx264", macro_block_size=8) as w:
            for f in self.frames:
                w.append_data(f)
        return path


def _find_world(env):
    """A MuJoCo :class:`robocup_gym.sim.engines.mujoco.world.World` showing the state behind
    ``env`` (the
    MuJoCo engine's own world, or one posed like the ODE engine's), if any."""
    e = env
    for _ in range(16):
        for attr in ("world", "_world", "sim"):
            w = getattr(e, attr, None)
            if w is not None and hasattr(w, "model") and hasattr(w, "data"):
                return w
        backend = getattr(e, "backend", None)
        if backend is not None and hasattr(backend, "scene_world"):
            return backend.scene_world()  # a MuJoCo world showing the backend's state
        if backend is not None and not isinstance(backend, str):
            w = getattr(backend, "world", None)
            if w is not None and hasattr(w, "model"):
                return w
        if not hasattr(e, "env"):
            break
        e = e.env
    return None


# ---------------------------------------------------------------------------------- runs
def evaluate_run(
    run: str | os.PathLike,
    *,
    episodes: int = 10,
    seed: int = 100_000,
    deterministic: bool = True,
    video: str | os.PathLike | None = None,
    video_episodes: int = 1,
    checkpoint: str | os.PathLike | None = None,
    write: bool = True,
    backend: str | None = None,
    robot_type: int | None = None,
) -> dict[str, Any]:
    """Evaluate a run folder's policy; returns (and writes to ``eval.json``, or to
    ``eval-<backend>.json`` for another backend than the run's, ``eval[-<backend>]-type<N>.json``
    on another Nao type) the summary.

    ``backend`` evaluates on another simulator than the run trained on (e.g. ``"ode"``:
    SimSpark's physics on ODE itself, closed-loop); ``robot_type`` on another Nao type than the
    run's. The video, if any, is recorded on the run's own backend."""

    if int(episodes) < 1:
        raise ValueError(f"episodes must be >= 1, got {episodes}")
    if video is not None and int(video_episodes) < 1:
        raise ValueError(f"video episodes must be >= 1, got {video_episodes}")
    info: RunInfo = load_run(run)
    cfg = info.config
    model = load_model(info, checkpoint=checkpoint)
    normalizer = info.obs_normalizer()
    backend = backend or cfg.backend
    on_type = {} if robot_type is None else {"robot_type": int(robot_type)}
    env = make_env(cfg.env_id, backend=backend, env_kwargs=cfg.env_options(**on_type))
    try:
        records = run_episodes(
            model, env, episodes, seed=seed, deterministic=deterministic, obs_normalizer=normalizer
        )
    finally:
        env.close()
    summary: dict[str, Any] = {
        "run": str(info.path),
        "task": cfg.task,
        "env_id": cfg.env_id,
        "algo": cfg.algo,
        "model": str(info.model_path if checkpoint is None else checkpoint),
        "timesteps_trained": int(model.num_timesteps),
        "deterministic": deterministic,
        "backend": backend,
        "robot_type": nao_type(env.unwrapped.config),
        **summarize(records),
    }
    if video is not None:
        summary["video"] = str(record_video(info, model, video, episodes=video_episodes, seed=seed))
    if write:
        name = "eval" if backend == cfg.backend else f"eval-{backend}"
        name += "" if robot_type is None else f"-type{int(robot_type)}"
        name += ".json"
        summary["written"] = str(info.path / name)
        (info.path / name).write_text(json.dumps(summary, indent=2) + "\n")
    return summary


def record_video(
    info: RunInfo,
    model,
    path: str | os.PathLike,
    *,
    episodes: int = 1,
    seed: int = 100_000,
    roll_s: float = 2.0,
) -> Path:
    """Record ``episodes`` deterministic episodes to ``path`` (MP4 or GIF).

    The kick tasks let the ball roll for ``wait_steps`` cycles inside their last step; to show
    that roll, the video environment is made with ``wait_steps=0`` and the world is then run on
    here with the joints stopped (exactly as the environment's wait) for at least ``roll_s``
    seconds, and drawn.
    """

    ensure_gl_backend()
    cfg = info.config
    env_kwargs = cfg.env_options()
    wait = 0
    probe = make_env(cfg.env_id, backend=cfg.backend, env_kwargs=env_kwargs)
    base_cfg = getattr(probe.unwrapped, "config", None)
    if base_cfg is not None and getattr(probe.unwrapped, "backend", None) is not None:
        wait = int(getattr(base_cfg, "wait_steps", 0) or 0)
    probe.close()
    if wait:
        env_kwargs["wait_steps"] = 0
    try:
        env = make_env(
            cfg.env_id, backend=cfg.backend, env_kwargs=env_kwargs, render_mode="rgb_array"
        )
    except TypeError:
        env = make_env(cfg.env_id, backend=cfg.backend, env_kwargs=env_kwargs)
    fps = float(env.metadata.get("render_fps") or 50)
    every = max(1, round(fps / 25))
    recorder = FrameRecorder(every=every)
    normalizer = info.obs_normalizer()
    try:
        for k in range(episodes):
            run_episodes(model, env, 1, seed=seed + k, obs_normalizer=normalizer, on_step=recorder)
            if wait:
                from robocup_gym.types import AgentCommand

                base = env.unwrapped
                stop = AgentCommand(np.zeros(len(base.robot_model.joints)))
                base.backend.step(stop)
                recorder(env)
                for _ in range(max(wait, round(roll_s / 0.02)) - 1):
                    base.backend.step(AgentCommand())
                    recorder(env)
        return recorder.save(path, fps=fps / every)
    finally:
        recorder.close()
        env.close()

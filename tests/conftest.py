"""Fixtures shared by the test folders: an in-process ``robocup-gym serve`` on OS-chosen ports."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import pytest

from robocup_gym.server import SimServer
from robocup_gym.sim import ENGINES

HOST = "127.0.0.1"


@pytest.fixture(autouse=True, scope="session")
def _private_tempdir(tmp_path_factory):
    """Temporary files of the session under pytest's own folder, for this process and every
    child (``TMPDIR``): Stable-Baselines3 makes a ``SB3-<time>`` folder in the temporary
    directory for every model that learns without a logger of its own, which would otherwise
    pile up in /tmp run after run."""
    old, old_env = tempfile.tempdir, os.environ.get("TMPDIR")
    tempfile.tempdir = os.environ["TMPDIR"] = str(tmp_path_factory.mktemp("tmp"))
    yield
    tempfile.tempdir = old
    if old_env is None:
        os.environ.pop("TMPDIR", None)
    else:
        os.environ["TMPDIR"] = old_env


@pytest.fixture(params=ENGINES)
def make_server(request):
    """``make_server(**options)`` → a started :class:`SimServer` on free loopback ports
    (sync mode, real time off unless overridden); stopped after the test, even on failure.
    Every test that uses it runs once per physics engine (``server.engine`` says which)."""
    servers: list[SimServer] = []

    def factory(**options) -> SimServer:
        opts = {"sync": True, "real_time": False, "seed": 1, "engine": request.param}
        opts.update(options)
        server = SimServer(0, 0, HOST, **opts)
        servers.append(server)
        server.start_in_thread()
        return server

    yield factory
    for server in servers:
        server.stop()
        assert server.stopped, "server thread did not stop"
    leftover = [t for t in threading.enumerate() if t.name == "robocup-gym-serve"]
    assert not leftover, f"server threads still running: {leftover}"


@pytest.fixture(scope="session")
def offscreen_gl() -> dict[str, str]:
    """The environment variables under which MuJoCo renders offscreen here (``MUJOCO_GL``,
    egl unless set); skips where no OpenGL context can be made (checked in a child process,
    as a failing GL library can take its process down)."""
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    code = "import mujoco; r = mujoco.Renderer(mujoco.MjModel.from_xml_string('<mujoco/>'), 8, 8)"
    try:
        ok = (
            subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, timeout=60)
        ).returncode == 0
    except subprocess.TimeoutExpired:
        ok = False
    if not ok:
        pytest.skip("no OpenGL for MuJoCo's offscreen renderer here (set MUJOCO_GL=egl/osmesa)")
    return env


BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="session")
def run_benchmark():
    """``run_benchmark("soccer.py", "--quick", timeout=300)`` runs ``benchmarks/<script>`` with
    these arguments from the repository's root and returns ``(the JSON object of its last line,
    the lines before it)``; a non-zero exit fails the test with the end of its stderr."""

    def run(script: str, *args: object, timeout: float = 300, env: dict | None = None):
        proc = subprocess.run(
            [sys.executable, str(BENCHMARKS / script), *map(str, args)],
            capture_output=True,
            text=True,
            timeout=timeout,
            cwd=BENCHMARKS.parent,
            env=env,
        )
        assert proc.returncode == 0, proc.stderr[-2000:]
        lines = proc.stdout.strip().splitlines()
        return json.loads(lines[-1]), lines[:-1]

    return run


@pytest.fixture
def real_rcssserver3d() -> str:
    """The real rcssserver3d binary (``RCSSSERVER3D`` or on ``PATH``); the test is skipped, with
    the reason, where there is none (or only the other tests' fake script)."""
    from robocup_gym.backends.process import RcssServerNotFoundError, find_binary

    try:
        binary = find_binary()
    except RcssServerNotFoundError as exc:
        pytest.skip(f"no real rcssserver3d here: {str(exc).split('. ')[0]}")
    with open(binary, "rb") as f:
        if f.read(2) == b"#!":
            pytest.skip(f"{binary} is a script, not a real rcssserver3d")
    return binary


@pytest.fixture(scope="session")
def child_pids():
    """``child_pids(pid)``: the PIDs of process ``pid``'s children (read from ``/proc``: Linux)."""

    def children(pid: int) -> list[int]:
        out = []
        for d in Path("/proc").iterdir():
            if d.name.isdigit():
                try:
                    stat = (d / "stat").read_text()
                except OSError:
                    continue  # a process that ended meanwhile
                if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                    out.append(int(d.name))
        return out

    return children


@pytest.fixture(scope="session")
def process_ends():
    """``process_ends(pid, within=10.0)``: whether process ``pid`` is gone within ``within``
    seconds (polled every 50 ms)."""

    def ends(pid: int, within: float = 10.0) -> bool:
        deadline = time.monotonic() + within
        while time.monotonic() < deadline:
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                return True
            time.sleep(0.05)
        return False

    return ends

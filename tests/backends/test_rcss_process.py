"""Launching rcssserver3d: finding the binary, free ports, the generated configuration, and that
the child is always stopped (close, garbage collection, interpreter exit, parent death)."""

from __future__ import annotations

import gc
import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from _waits import pid_alive, wait_until

from robocup_gym.backends import BackendNotAvailableError, make_backend
from robocup_gym.backends.process import (
    BUILTIN_SCRIPT,
    RcssServerNotFoundError,
    ServerProcess,
    find_binary,
    free_ports,
    render_server_script,
    sweep_stale_folders,
)

# --------------------------------------------------------------------------- finding the binary


def test_missing_binary_env_var_points_nowhere(monkeypatch, tmp_path):
    missing = tmp_path / "nowhere" / "rcssserver3d"
    monkeypatch.setenv("RCSSSERVER3D", str(missing))
    with pytest.raises(RcssServerNotFoundError) as e:
        find_binary()
    msg = str(e.value)
    assert "RCSSSERVER3D" in msg and str(missing) in msg and "does not exist" in msg
    assert "Install rcssserver3d" in msg and "engine='ode'" in msg and "engine='mujoco'" in msg
    # through the registry: a BackendNotAvailableError like any unavailable backend
    with pytest.raises(BackendNotAvailableError, match="RCSSSERVER3D"):
        make_backend("rcssserver3d")


def test_missing_binary_empty_path(monkeypatch):
    monkeypatch.delenv("RCSSSERVER3D", raising=False)
    monkeypatch.setenv("PATH", "")
    with pytest.raises(RcssServerNotFoundError) as e:
        make_backend("rcssserver3d", robot_type=0)
    msg = str(e.value)
    assert "not on PATH" in msg or "no rcssserver3d on PATH" in msg
    assert "RCSSSERVER3D" in msg and "mujoco" in msg


def test_binary_not_executable(monkeypatch, tmp_path):
    f = tmp_path / "rcssserver3d"
    f.write_text("not a program")
    f.chmod(0o644)
    monkeypatch.setenv("RCSSSERVER3D", str(f))
    with pytest.raises(RcssServerNotFoundError, match="not an executable"):
        find_binary()


def test_binary_found_by_env_and_path(fake_server, monkeypatch):
    assert find_binary() == str(fake_server.binary.resolve())
    monkeypatch.delenv("RCSSSERVER3D")
    monkeypatch.setenv("PATH", str(fake_server.binary.parent))
    assert find_binary() == str(fake_server.binary.resolve())


# --------------------------------------------------------------------------- ports, config


def test_free_ports_are_distinct_and_bindable():
    ports = free_ports(4)
    assert len(set(ports)) == 4 and all(1024 <= p <= 65535 for p in ports)
    for p in ports:
        with socket.socket() as s:
            s.bind(("127.0.0.1", p))


def test_script_from_installed_template_is_rewritten():
    template = textwrap.dedent(
        """\
        # rcssserver3d.rb
        $recordLogfile = true
        $enableInternalMonitor = true
        $enableRealTimeMode = true
        sparkSetupServer()
        if ($enableRealTimeMode)
          sparkSetupTimer()
        end
        run "naosoccersim.rb"
        """
    )
    text = render_server_script(template, 41000, 42000)
    lines = text.splitlines()
    for expected in (
        "$agentSyncMode = true",
        "$monitorStep = 0.02",
        "$agentPort = 41000",
        "$serverPort = 42000",
        "$enableRealTimeMode = false",
        "$enableInternalMonitor = false",
        "$recordLogfile = false",
    ):
        assert expected in lines, expected
    assert "$enableRealTimeMode = true" not in lines
    # the header comes before the server's own setup call, which reads the spark.rb globals
    assert lines.index("$agentSyncMode = true") < lines.index("sparkSetupServer()")
    assert text.endswith('run "naosoccersim.rb"\n')


def test_builtin_script_when_nothing_is_installed():
    text = render_server_script(None, 1, 2, monitor_step=0.04)
    assert "$monitorStep = 0.04" in text and 'run "naosoccersim.rb"' in text
    assert BUILTIN_SCRIPT.splitlines()[-1] in text


# --------------------------------------------------------------------------- the child process


def test_launch_uses_private_home_generated_script_and_os_ports(fake_server):
    real_dot = Path.home() / ".simspark"
    before = sorted(p.name for p in real_dot.iterdir()) if real_dot.exists() else None
    sp = ServerProcess()
    try:
        agent_port, monitor_port = sp.start()
        start = fake_server.wait_event("start")
        assert agent_port != monitor_port and {agent_port, monitor_port}.isdisjoint({3100, 3200})
        argv = start["argv"]
        assert argv[argv.index("--agent-port") + 1] == str(agent_port)
        assert argv[argv.index("--server-port") + 1] == str(monitor_port)
        script = Path(argv[argv.index("--script-path") + 1])
        assert script == sp.script_path and script.is_absolute()
        assert start["home"] == str(sp.home) != os.environ.get("HOME")
        assert script.parent == sp.home / ".simspark"
        assert "$agentSyncMode = true" in start["script"]
        assert "$enableRealTimeMode = false" in start["script"]
        folder = sp.home
        assert sp.running
    finally:
        sp.stop()
    assert fake_server.wait_event("sigint")  # stopped with SIGINT (it ignores SIGTERM)
    assert not sp.running and sp.proc.returncode == 0
    assert not folder.exists()
    after = sorted(p.name for p in real_dot.iterdir()) if real_dot.exists() else None
    assert after == before, "the user's ~/.simspark must not be touched"
    sp.stop()  # idempotent


def test_stop_escalates_to_sigkill_when_sigint_is_ignored(fake_server):
    fake_server.use("stubborn")
    sp = ServerProcess(stop_grace_s=0.5)
    sp.start()
    fake_server.wait_event("start")
    t = time.monotonic()
    sp.stop()
    assert time.monotonic() - t < 5
    assert sp.proc.returncode == -signal.SIGKILL


def test_garbage_collection_stops_the_server(fake_server):
    sp = ServerProcess()
    sp.start()
    pid, folder = sp.pid, sp.home
    fake_server.wait_event("start")
    del sp
    gc.collect()
    fake_server.wait_event("sigint")
    wait_until(lambda: not pid_alive(pid), what="server exit")
    assert not folder.exists()


def _run_python(code: str, env: dict[str, str], timeout: float = 30) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        env={**os.environ, **env},
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def test_interpreter_exit_stops_the_server(fake_server):
    code = """
        from robocup_gym.backends.process import ServerProcess
        sp = ServerProcess()
        sp.start()
        print(sp.pid, sp.home, flush=True)
        import os, time
        path = os.environ["FAKE_RCSS_REPORT"]
        while not (os.path.exists(path) and '"start"' in open(path).read()):
            time.sleep(0.02)
        # no stop(): the finalizer's atexit hook must do it
    """
    proc = _run_python(code, {})
    assert proc.returncode == 0, proc.stderr
    pid, folder = proc.stdout.split()
    fake_server.wait_event("sigint")
    wait_until(lambda: not pid_alive(int(pid)), what="server exit")
    assert not Path(folder).exists()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux-only")
def test_parent_death_stops_the_server(fake_server):
    code = """
        import os, signal
        from robocup_gym.backends.process import ServerProcess
        sp = ServerProcess()
        sp.start()
        print(sp.pid, sp.home, flush=True)
        import time
        path = os.environ["FAKE_RCSS_REPORT"]
        while not (os.path.exists(path) and '"start"' in open(path).read()):
            time.sleep(0.02)
        os.kill(os.getpid(), signal.SIGKILL)  # no finalizer, no atexit
    """
    proc = _run_python(code, {})
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    pid, folder = int(proc.stdout.split()[0]), Path(proc.stdout.split()[1])
    fake_server.wait_event("sigint")
    wait_until(lambda: not pid_alive(pid), what="orphaned server exit")
    # nobody was left to delete the configuration folder; the next start sweeps it away
    assert folder.exists()
    wait_until(lambda: str(folder) in sweep_stale_folders() or not folder.exists(), what="sweep")
    assert not folder.exists()


def test_server_that_exits_reports_its_output(fake_server):
    from robocup_gym.backends import BackendError

    fake_server.use("crash")
    t = time.monotonic()
    with pytest.raises(BackendError) as e:
        make_backend("rcssserver3d", startup_timeout=20)
    msg = str(e.value)
    assert "exited with code 3" in msg and "cannot bind the agent port" in msg
    assert time.monotonic() - t < 20  # noticed at once (polling the process), not by a timeout

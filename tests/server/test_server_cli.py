"""``python -m robocup_gym.server``: ports, clean stop on SIGTERM/SIGINT, port in use, benchmark."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys

import pytest

from robocup_gym.protocol.perceptors import parse_perception
from robocup_gym.server.bench import (
    measure_sync_cycles_per_s,
    measure_team_cycles_per_s,
    start_server_process,
)
from robocup_gym.server.client import AgentClient

from .conftest import HOST


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_cli_serves_and_stops_cleanly(sig):
    proc, agent_port, _ = start_server_process("--sync")
    try:
        with AgentClient(HOST, agent_port) as agent:
            for msg in agent.handshake("Cli", 1):
                parse_perception(msg)
        proc.send_signal(sig)
        out, _ = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, out
    assert "stopped after" in out


def test_cli_port_in_use_is_a_clear_error():
    blocker = socket.socket()
    blocker.bind((HOST, 0))
    blocker.listen()
    port = blocker.getsockname()[1]
    try:
        res = subprocess.run(
            [
                sys.executable,
                "-m",
                "robocup_gym.server",
                "--host",
                HOST,
                "--agent-port",
                "0",
                "--monitor-port",
                str(port),
            ],
            capture_output=True,
            text=True,
            timeout=60,
        )
    finally:
        blocker.close()
    assert res.returncode == 2
    assert f"monitor port {port} is already in use" in res.stderr


def test_benchmark_runs():
    assert measure_sync_cycles_per_s(0.5) > 20


def test_team_benchmark_runs_a_sync_game_of_several_agents():
    """The full-game figure's code path (22 agents there): every agent steps, none stalls."""
    assert measure_team_cycles_per_s(0.5, engine="ode", n_agents=3) > 5


def test_without_libode_serve_says_so_in_one_line_and_names_the_other_engine(tmp_path):
    import os

    env = dict(os.environ, ROBOCUP_GYM_LIBODE=str(tmp_path / "no-libode.so"))
    args = [sys.executable, "-m", "robocup_gym.server", "--agent-port", "0", "--monitor-port", "0"]
    res = subprocess.run(args, capture_output=True, text=True, timeout=60, env=env)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Open Dynamics Engine" in lines[0], res.stderr
    assert "--engine mujoco" in lines[0] and "Traceback" not in res.stderr


@pytest.mark.skipif(
    not sys.platform.startswith("linux"), reason="the parent-death signal is Linux's"
)
def test_a_started_server_ends_with_its_parent(process_ends):
    """``start_server_process`` (matches on ``serve``, the benchmarks): a parent that dies
    without stopping its server does not leave it running."""
    code = (
        "import os\n"
        "from robocup_gym.server.bench import start_server_process\n"
        "proc, _, _ = start_server_process('--sync')\n"
        "print(proc.pid, flush=True)\n"
        "os._exit(0)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    pid = int(out.stdout.split()[-1])
    if not process_ends(pid):
        os.kill(pid, signal.SIGKILL)
        raise AssertionError(f"the server {pid} outlived its parent")

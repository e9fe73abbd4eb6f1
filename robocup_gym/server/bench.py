"""Throughput of ``robocup-gym serve`` in sync mode, measured like the real server's figure.

The reference (tests/data/rcssserver3d/README.md): rcssserver3d 0.7.3 in sync mode with real time
off runs 1,361 cycles/s on this machine class with one Nao whose client sends all 22 joint
velocities plus ``(syn)`` every cycle and parses every percept.

:func:`measure_sync_cycles_per_s` reproduces that: the server runs as a subprocess (as the real one
does, so server and client can use both cores), one agent does ``scene``/``init``/``beam`` and then
sends all 22 joints (FC Portugal's ``%.5f`` format) + ``(syn)`` per percept, parsing each percept
with :func:`robocup_gym.protocol.perceptors.parse_perception`.

Run it: ``python -m robocup_gym.server.bench [seconds]``.
"""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys
import time

from robocup_gym.protocol.perceptors import parse_perception
from robocup_gym.robot.nao import nao_model
from robocup_gym.server.client import AgentClient

_LISTEN = re.compile(r"agents on [^:\s]+:(\d+), monitors on [^:\s]+:(\d+)")


def start_server_process(
    *extra_args: str, timeout: float = 60.0
) -> tuple[subprocess.Popen[str], int, int]:
    """Start ``python -m robocup_gym.server`` on free loopback ports; returns (process, agent
    port, monitor port). The caller must terminate the process.

    Raises:
        RuntimeError: if it does not report its ports within ``timeout`` seconds.
    """
    cmd = [
        sys.executable,
        "-m",
        "robocup_gym.server",
        "--agent-port",
        "0",
        "--monitor-port",
        "0",
        "--host",
        "127.0.0.1",
        *extra_args,
    ]
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(
        cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env
    )
    deadline = time.monotonic() + timeout
    lines: list[str] = []
    assert proc.stdout is not None
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        lines.append(line)
        m = _LISTEN.search(line)
        if m:
            return proc, int(m.group(1)), int(m.group(2))
    stop_server_process(proc)
    raise RuntimeError("server did not start:\n" + "".join(lines[-20:]))


def stop_server_process(proc: subprocess.Popen[str], timeout: float = 10.0) -> int:
    """SIGTERM, wait, SIGKILL if needed; returns the exit code."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout)
    if proc.stdout is not None:
        proc.stdout.close()
    return proc.returncode


def run_agent(port: int, seconds: float, host: str = "127.0.0.1") -> tuple[int, float]:
    """Connect one type-0 agent and step for ``seconds``; returns (cycles, elapsed s)."""
    names = nao_model(0).effector_names
    with AgentClient(host, port) as agent:
        agent.handshake("Bench", 1, 0, syn=True)
        agent.send("(beam -3 0 0)(syn)")
        parse_perception(agent.recv(), 0)
        k = 0
        warm = 25
        start = time.perf_counter()
        end = None
        while True:
            # small sinusoidal head/arm motion keeps every joint command meaningful
            v = 0.5 * math.sin(k * 0.05)
            msg = "".join(f"({n} {v if n in ('he1', 'lae1', 'rae1') else 0.0:.5f})" for n in names)
            agent.send(msg + "(syn)")
            parse_perception(agent.recv(), 0)
            k += 1
            if k == warm:
                start = time.perf_counter()
            elif k > warm:
                end = time.perf_counter()
                if end - start >= seconds:
                    break
        return k - warm, (end or time.perf_counter()) - start


def measure_sync_cycles_per_s(seconds: float = 3.0) -> float:
    """Cycles per second of the server in sync mode with real time off (see module docstring).

    Starts the server as a subprocess on free loopback ports and stops it afterwards.
    """
    proc, agent_port, _ = start_server_process("--sync", "--no-real-time")
    try:
        cycles, elapsed = run_agent(agent_port, seconds)
    finally:
        stop_server_process(proc)
    return cycles / elapsed


if __name__ == "__main__":  # pragma: no cover
    secs = float(sys.argv[1]) if len(sys.argv) > 1 else 3.0
    print(f"serve_sync_cycles_per_s: {measure_sync_cycles_per_s(secs):.0f}")

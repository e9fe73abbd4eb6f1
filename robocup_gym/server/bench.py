"""Throughput of ``robocup-gym serve`` in sync mode, measured like the real server's figure.

The reference (tests/data/rcssserver3d/README.md): rcssserver3d 0.7.3 in sync mode with real time
off runs 1,361 cycles/s on this machine class with one Nao whose client sends all 22 joint
velocities plus ``(syn)`` every cycle and parses every percept.

:func:`measure_sync_cycles_per_s` reproduces that: the server runs as a subprocess (as the real one
does, so server and client can use both cores), one agent does ``scene``/``init``/``beam`` and then
sends all 22 joints (FC Portugal's ``%.5f`` format) + ``(syn)`` per percept, parsing each percept
with :func:`robocup_gym.protocol.perceptors.parse_perception`.

:func:`measure_team_cycles_per_s` is the full-game figure: 22 agents (11 a side, types 0–4
mixed), each a thread with its own connection that beams to its own spot and then sends 22 joint
velocities + ``(syn)`` per percept and parses every percept; the server steps when all 22 have
synced, so this is the cycle rate of a whole game in sync mode.

Where a real rcssserver3d is installed (``RCSSSERVER3D`` or on ``PATH``) the one-agent figure is
also measured on it, in the same run (``real_sync_cycles_per_s``, ``serve_vs_real``).

Run it: ``python -m robocup_gym.server.bench [seconds] [--engine ode|mujoco] [--agents N]``
(prints one JSON line).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import signal
import subprocess
import sys
import threading
import time

from robocup_gym.protocol.perceptors import parse_perception
from robocup_gym.robot.nao import nao_model
from robocup_gym.server.client import AgentClient

_LISTEN = re.compile(r"agents on [^:\s]+:(\d+), monitors on [^:\s]+:(\d+)")


def start_server_process(
    *extra_args: str, timeout: float = 60.0
) -> tuple[subprocess.Popen[str], int, int]:
    """Start ``python -m robocup_gym.server`` on free loopback ports; returns (process, agent
    port, monitor port). The caller must terminate the process (on Linux it also ends when
    its parent dies).

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
    from robocup_gym.backends.process import _death_signal_preexec

    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(
        cmd,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        preexec_fn=_death_signal_preexec(signal.SIGTERM),  # ends with its parent (Linux)
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


def measure_sync_cycles_per_s(seconds: float = 3.0, engine: str = "ode") -> float:
    """Cycles per second of the server in sync mode with real time off (see module docstring).

    Starts the server as a subprocess on free loopback ports and stops it afterwards.
    """
    proc, agent_port, _ = start_server_process("--sync", "--no-real-time", "--engine", engine)
    try:
        cycles, elapsed = run_agent(agent_port, seconds)
    finally:
        stop_server_process(proc)
    return cycles / elapsed


def measure_real_sync_cycles_per_s(seconds: float = 3.0) -> float | None:
    """The same one-agent figure on a real rcssserver3d where one is installed (``RCSSSERVER3D``
    or on ``PATH``; launched in sync mode, real time off, on OS-chosen ports), else ``None``."""
    from robocup_gym.backends.process import RcssServerNotFoundError, ServerProcess

    try:
        proc = ServerProcess(sync=True, real_time=False)
    except RcssServerNotFoundError:
        return None
    proc.start()
    try:
        cycles, elapsed = run_agent(proc.agent_port, seconds)
    finally:
        proc.stop()
    return cycles / elapsed


def run_team(
    port: int, n_agents: int, seconds: float, host: str = "127.0.0.1"
) -> tuple[int, float]:
    """Connect ``n_agents`` agents (one thread each; left team first, robot types 0–4 in turn),
    beam them apart and step them all for ``seconds``; returns (cycles of agent 0, elapsed s).

    Raises:
        RuntimeError: an agent's thread failed (its error is chained).
    """
    names = nao_model(0).effector_names
    stop = threading.Event()
    everyone_in = threading.Event()
    joined: list[int] = []
    counts = [0] * n_agents
    errors: list[BaseException] = []
    window: list[float] = []

    def agent_main(i: int) -> None:
        side, k = ("Left", i) if i < (n_agents + 1) // 2 else ("Right", i - (n_agents + 1) // 2)
        try:
            with AgentClient(host, port) as agent:
                agent.handshake(side, k + 1, i % 5, syn=True)
                agent.send(f"(beam {-1.0 - 1.5 * (k % 4):.2f} {-7.5 + 1.4 * k:.2f} 0)(syn)")
                parse_perception(agent.recv(), i % 5)
                joined.append(i)
                # answering every percept while the others join: a sync-mode server waits for
                # this agent once its first cycles are past, and the others join only while
                # cycles run
                while not everyone_in.is_set() and not stop.is_set():
                    agent.send("(syn)")
                    agent.recv()
                while not stop.is_set():
                    v = 0.5 * math.sin(counts[i] * 0.05)
                    msg = "".join(
                        f"({n} {v if n in ('he1', 'lae1', 'rae1') else 0.0:.5f})" for n in names
                    )
                    agent.send(msg + "(syn)")
                    parse_perception(agent.recv(), i % 5)
                    counts[i] += 1
        except BaseException as exc:  # reported by the caller
            errors.append(exc)
            stop.set()

    threads = [threading.Thread(target=agent_main, args=(i,), daemon=True) for i in range(n_agents)]
    for t in threads:
        t.start()
    try:
        deadline = time.monotonic() + 120.0
        while len(joined) < n_agents and not stop.is_set() and time.monotonic() < deadline:
            time.sleep(0.01)
        if len(joined) == n_agents:
            everyone_in.set()
            time.sleep(0.5)  # warm-up
            c0, t0 = counts[0], time.perf_counter()
            time.sleep(seconds)
            c1, t1 = counts[0], time.perf_counter()
            window.extend((c1 - c0, t1 - t0))
    finally:
        stop.set()
        for t in threads:
            t.join(30.0)
    if errors or not window:
        raise RuntimeError(f"an agent failed: {errors[0] if errors else 'no start'}") from (
            errors[0] if errors else None
        )
    return int(window[0]), window[1]


def measure_team_cycles_per_s(
    seconds: float = 5.0, engine: str = "ode", n_agents: int = 22
) -> float:
    """Cycles per second of a sync-mode game with ``n_agents`` agents (see module docstring),
    server as a subprocess on free loopback ports, real time off."""
    proc, agent_port, _ = start_server_process(
        "--sync", "--no-real-time", "--no-type-limits", "--engine", engine
    )
    try:
        cycles, elapsed = run_team(agent_port, n_agents, seconds)
    finally:
        stop_server_process(proc)
    return cycles / elapsed


if __name__ == "__main__":  # pragma: no cover
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("seconds", type=float, nargs="?", default=3.0)
    parser.add_argument("--engine", choices=("ode", "mujoco"), default="ode")
    parser.add_argument("--agents", type=int, default=22, help="agents of the full-game figure")
    args = parser.parse_args()
    one = measure_sync_cycles_per_s(args.seconds, args.engine)
    real = measure_real_sync_cycles_per_s(args.seconds)
    team = measure_team_cycles_per_s(args.seconds, args.engine, args.agents)
    out = {
        "engine": args.engine,
        "serve_sync_cycles_per_s": round(one),
        f"serve_{args.agents}_agents_cycles_per_s": round(team, 1),
        f"serve_{args.agents}_agents_x_real_time": round(team / 50.0, 2),
    }
    if real is not None:
        out["real_sync_cycles_per_s"] = round(real)
        out["serve_vs_real"] = round(one / real, 2)
    print(json.dumps(out))

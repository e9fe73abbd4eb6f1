"""A stand-in for the rcssserver3d executable, for the launch-mode tests.

Run through a small shell wrapper (see ``conftest.fake_binary``) with the real server's command
line (``--agent-port N --server-port M --script-path FILE``). What it does depends on
``FAKE_RCSS_MODE``:

* ``serve``: checks the generated script (sync mode on, real-time mode off) and runs the
  project's own protocol server (:class:`robocup_gym.server.SimServer`) on the given ports, so
  the backend's launch mode is exercised end to end;
* ``idle``: only waits (standard library only: starts fast);
* ``stubborn``: waits and ignores SIGINT too (to test the escalation to SIGKILL);
* ``crash``: prints an error and exits with code 3.

Like the real server it ignores SIGTERM and stops on SIGINT. Every event is appended as a JSON
line to the file named by ``FAKE_RCSS_REPORT``.
"""

from __future__ import annotations

import json
import os
import re
import signal
import sys
import threading


def report(event: str, **data: object) -> None:
    path = os.environ.get("FAKE_RCSS_REPORT")
    if not path:
        return
    with open(path, "a", encoding="utf-8") as f:
        f.write(json.dumps({"event": event, "pid": os.getpid(), **data}) + "\n")


def _peer_open(conn) -> bool:
    """Whether the agent at the other end still has its connection open (its FIN is not in)."""
    import socket

    if not conn.alive or conn.sock is None:
        return False
    try:
        return conn.sock.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT) != b""
    except BlockingIOError:
        return True  # open, nothing to read
    except OSError:
        return False


def arg(name: str) -> str | None:
    argv = sys.argv[1:]
    return argv[argv.index(name) + 1] if name in argv else None


def main() -> int:
    mode = os.environ.get("FAKE_RCSS_MODE", "idle")
    script_path = arg("--script-path")
    script = ""
    if script_path and os.path.exists(script_path):
        with open(script_path, encoding="latin-1") as f:
            script = f.read()
    stop = threading.Event()
    serving: list = []  # the protocol server, in "serve" mode
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # the real server ignores SIGTERM
    if mode == "stubborn":
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    else:

        def on_sigint(*_: object) -> None:
            # how many agents were still connected when SIGINT came (a client should close
            # its connections first: rcssserver3d serving a connected agent ignores SIGINT)
            connected = sum(1 for a in serving[0].agents if _peer_open(a.conn)) if serving else None
            report("sigint", connected_agents=connected)
            stop.set()

        signal.signal(signal.SIGINT, on_sigint)
    report(
        "start",
        mode=mode,
        argv=sys.argv[1:],
        home=os.environ.get("HOME"),
        cwd=os.getcwd(),
        script_path=script_path,
        script=script,
    )
    if mode == "crash":
        print("fake rcssserver3d: (SimulationServer) ERROR: cannot bind the agent port", flush=True)
        return 3

    if mode == "serve":
        sync = re.search(r"^\$agentSyncMode = true$", script, re.M) is not None
        real_time = re.search(r"^\$enableRealTimeMode = false$", script, re.M) is None
        step = re.search(r"^\$monitorStep = ([0-9.]+)$", script, re.M)
        if not sync or real_time or step is None:
            print("fake rcssserver3d: script does not set sync mode / real time off", flush=True)
            return 4
        from robocup_gym.server import SimServer

        server = SimServer(
            int(arg("--agent-port")),
            int(arg("--server-port")),
            "127.0.0.1",
            sync=True,
            real_time=False,
            seed=1,
            monitor_interval=max(1, round(float(step.group(1)) / 0.02)),
        )
        server.start_in_thread()
        serving.append(server)
        report("listening")
        while not stop.wait(0.05):
            pass
        server.stop()
    else:
        while not stop.wait(0.05):
            pass
    report("exit")
    return 0


if __name__ == "__main__":
    sys.exit(main())

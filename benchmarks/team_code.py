"""A published team's own skills on ``robocup-gym serve``: FC Portugal's walk, kick and get-up.

Does a team's unchanged agent behave on ``serve`` as on rcssserver3d? This runs
FC Portugal's public codebase (https://github.com/m-abr/FCPCodebase; not part of this project,
see below for what it needs) against an in-process ``robocup-gym serve``
(sync mode, real time off, the server's default noise) on each engine and robot type, and
measures, from the server's ground truth:

* **walk**: distance covered in 10 s (500 cycles) of its ``Walk`` skill towards a far target,
  standing start; a fall ends the trial (counted);
* **kick**: ball travel of its ``Basic_Kick`` (walk up to the ball, kick towards +x), measured
  3 s after the kick motion ends;
* **get-up**: cycles of its ``Get_Up`` skill from lying on the front / on the back (after its
  ``Fall_Front`` / ``Fall_Back`` poses and a settle), and whether the robot is still up 1 s later.

Anchors from a real rcssserver3d 0.7.3 (the same codebase, measured elsewhere): walk 8.14 m in
10 s on type 0 (0.76–0.85 m/s on types 1–4), kick median 3.05 m, get-up ~66 cycles from the front
and ~55 from the back (up in 12 of 17 tries from the back).

It needs an FCPCodebase checkout that runs (its C++ modules built, as its own scripts do on
their first run) and an interpreter that runs it (numpy < 2, which the codebase was written
for, and pybind11)::

    python benchmarks/team_code.py --fcp /path/to/FCPCodebase --python /path/to/its/python
    python benchmarks/team_code.py ... --engines real      # a real rcssserver3d (RCSSSERVER3D)
    python benchmarks/team_code.py ... --engines real,ode --fork   # the SPL fork, like for like

``--engines`` lists what to run on: ``ode`` and ``mujoco`` are ``robocup-gym serve`` in-process
on that engine (ground truth read from its world every cycle), ``real`` a real rcssserver3d
launched by :class:`robocup_gym.backends.process.ServerProcess` (sync mode, real time off;
ground truth from its monitor stream, every cycle).

Prints one line per engine × type and the whole result as one JSON object last. The agent runs
in a child process with the codebase's interpreter (this file in ``--child`` mode imports only
the codebase's modules); the server runs here, where every cycle's ground truth is recorded.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

WALK_CYCLES = 500
SETTLE_CYCLES = 30
KICK_WAIT_CYCLES = 150
UP_CHECK_CYCLES = 50


# ---------------------------------------------------------------------------------- the agent side
def _child(args: argparse.Namespace) -> None:  # pragma: no cover - runs FC Portugal's code
    """Run the trials with FC Portugal's agent; print one JSON line per trial (game times:
    the play mode is PlayOn throughout, so the game clock runs with every cycle)."""
    os.chdir(args.fcp)
    sys.path.insert(0, args.fcp)
    sys.argv = [sys.argv[0]]
    from agent.Base_Agent import Base_Agent  # the codebase's own modules

    player = Base_Agent("127.0.0.1", args.port, args.mport, 1, args.type, "FCP", False, False)
    w, r, b, scom = player.world, player.world.robot, player.behavior, player.scom

    def cycle() -> None:
        scom.commit_and_send(r.get_command())
        scom.receive()

    def hold(pose: str, cycles: int) -> None:
        for _ in range(cycles):
            b.execute(pose)
            cycle()

    def emit(**fields) -> None:
        print(json.dumps(fields), flush=True)

    scom.unofficial_set_play_mode("PlayOn")
    for trial in range(args.trials):
        y = -6.0 + 3.0 * (trial % 5)
        if "walk" in args.tests:
            scom.unofficial_beam((-8.0, y, r.beam_height), 0)
            hold("Zero_Bent_Knees", SETTLE_CYCLES)
            t0, fell = w.time_game, False
            for _ in range(WALK_CYCLES):
                b.execute("Walk", (15.0, y), True, 0, True, None)
                cycle()
                if b.is_ready("Get_Up"):
                    fell = True
                    break
            emit(
                test="walk",
                t0=t0,
                t1=w.time_game,
                fell=fell,
                own_xy=[round(float(v), 3) for v in r.loc_head_position[:2]],
            )
            if fell:
                b.execute_to_completion("Get_Up")
        if "kick" in args.tests:
            scom.unofficial_move_ball((0.0, y, 0.042))
            scom.unofficial_beam((-0.6, y + 0.1, r.beam_height), 0)
            hold("Zero_Bent_Knees", SETTLE_CYCLES)
            t0, done = w.time_game, False
            for _ in range(600):
                done = b.execute("Basic_Kick", 0)
                cycle()
                if done or b.is_ready("Get_Up"):
                    break
            t_kick = w.time_game
            hold("Zero_Bent_Knees", KICK_WAIT_CYCLES)
            emit(test="kick", t0=t0, t_kick=t_kick, t1=w.time_game, done=bool(done))
            if b.is_ready("Get_Up"):
                b.execute_to_completion("Get_Up")
        if "getup" in args.tests:
            for side in ("front", "back"):
                scom.unofficial_beam((5.0, y, r.beam_height), 0)
                hold("Zero_Bent_Knees", SETTLE_CYCLES)
                pose = "Fall_Front" if side == "front" else "Fall_Back"
                for _ in range(200):
                    b.execute(pose)
                    cycle()
                    if b.is_ready("Get_Up"):
                        break
                hold(pose, SETTLE_CYCLES)
                t0, n, done = w.time_game, 0, False
                while not done and n < 400:
                    done = b.execute("Get_Up")
                    cycle()
                    n += 1
                chosen = {1: "front", 2: "back", 3: "flip"}.get(b.objects["Get_Up"].state, "?")
                t_up = w.time_game
                hold("Zero_Bent_Knees", UP_CHECK_CYCLES)
                emit(
                    test="getup",
                    side=side,
                    chosen=chosen,
                    cycles=n,
                    done=bool(done),
                    t0=t0,
                    t_up=t_up,
                    t1=w.time_game,
                )
    player.terminate()


# --------------------------------------------------------------------------------- the server side
def _median(values: list[float]) -> float | None:
    v = sorted(values)
    if not v:
        return None
    m = len(v) // 2
    return v[m] if len(v) % 2 else 0.5 * (v[m - 1] + v[m])


class _ServeTruth:
    """``robocup-gym serve`` in this process on one engine; ground truth from its world."""

    def __init__(self, engine: str, fork: bool = False) -> None:
        from robocup_gym.server import SimServer

        like_fork = {"decimals": 3, "field_lines": False} if fork else {}
        self.server = SimServer(
            0, 0, "127.0.0.1", sync=True, real_time=False, seed=0, engine=engine, **like_fork
        )
        self.truth: dict[float, tuple] = {}
        self.server.on_cycle = self._record
        self.server.start_in_thread()
        self.agent_port, self.monitor_port = self.server.agent_port, self.server.monitor_port

    def _record(self, srv) -> None:
        for a in srv.agents:
            i = srv.world_host.index(a.key) if a.has_robot else None
            if i is not None:
                w = srv.world
                key = round(w.game.game_time, 3)
                self.truth[key] = (w.torso_position(i), w.torso_up(i), w.ball_position())

    def stop(self) -> None:
        self.server.stop()


class _RealTruth:
    """A real rcssserver3d launched for the run; ground truth from its monitor stream (a
    monitor frame every cycle), read by a thread here."""

    def __init__(self) -> None:
        import threading

        from robocup_gym.backends.process import ServerProcess
        from robocup_gym.backends.rcssserver3d_monitor import MonitorTracker
        from robocup_gym.server.client import MonitorClient

        self.proc = ServerProcess(sync=True, real_time=False, monitor_step=0.02)
        self.proc.start()
        self.agent_port, self.monitor_port = self.proc.agent_port, self.proc.monitor_port
        self.truth: dict[float, tuple] = {}
        self._tracker = MonitorTracker()
        self._tracker.set_agent("left", 1)
        self._client = MonitorClient("127.0.0.1", self.monitor_port, timeout=60.0)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def _read(self) -> None:
        while not self._stop.is_set():
            try:
                frame = self._client.recv()
            except Exception:  # the server went away at the end
                return
            t = self._tracker
            t.feed(frame)
            if t.need_full and not t.full_requested:
                self._client.send("(reqfullstate)")
                t.full_requested = True
            s = t.newest()
            if s is not None and s.torso is not None:
                up = s.torso[:3, 2] / max(float(np.linalg.norm(s.torso[:3, 2])), 1e-12)
                self.truth[round(s.game_time, 3)] = (s.torso[:3, 3].copy(), up, s.ball_pos.copy())

    def stop(self) -> None:
        self._stop.set()
        self._client.close()
        self.proc.stop()


def strip_fork_gs(message: bytes) -> bytes:
    """A percept of the SPL fork (SimSpark-SPL) as upstream rcssserver3d 0.7.3 writes it: its
    ``GS`` without the fork's ``(k <side>)`` and ``(ti (…) (…))`` entries (the team codebase's
    parser does not expect them and then never learns its side). Everything else is kept."""
    start = message.find(b"(GS ")
    if start < 0:
        return message
    depth, end = 0, start
    for end in range(start, len(message)):  # the end of the GS expression
        c = message[end]
        depth += (c == 0x28) - (c == 0x29)
        if depth == 0:
            break
    gs = message[start : end + 1]
    out, i = bytearray(), 0
    while i < len(gs):
        if gs.startswith(b" (k ", i) or gs.startswith(b" (ti ", i):
            d, j = 0, i + 1
            while j < len(gs):  # skip the balanced entry
                d += (gs[j] == 0x28) - (gs[j] == 0x29)
                j += 1
                if d == 0:
                    break
            i = j
            continue
        out.append(gs[i])
        i += 1
    return message[:start] + bytes(out) + message[end + 1 :]


class _ForkRelay:
    """Sits between the team's agent and the SPL fork's agent port and turns the fork's percepts
    into upstream 0.7.3's (:func:`strip_fork_gs`); the agent's messages pass unchanged. One
    agent connection, two forwarding threads; ``port`` is the OS-chosen port the agent uses."""

    def __init__(self, server_port: int) -> None:
        import socket
        import threading

        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port = self._listener.getsockname()[1]
        self._server_port = server_port
        self._threads = [threading.Thread(target=self._run, daemon=True)]
        self._threads[0].start()

    def _run(self) -> None:
        import socket
        import threading

        from robocup_gym.protocol.framing import FrameDecoder, encode_frame

        agent, _ = self._listener.accept()
        server = socket.create_connection(("127.0.0.1", self._server_port))
        for s in (agent, server):
            s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

        def up() -> None:  # agent -> server, unchanged
            try:
                while data := agent.recv(1 << 16):
                    server.sendall(data)
            except OSError:
                pass
            server.close()

        threading.Thread(target=up, daemon=True).start()
        decoder = FrameDecoder()
        try:
            while data := server.recv(1 << 16):
                for frame in decoder.feed(data):
                    agent.sendall(encode_frame(strip_fork_gs(bytes(frame))))
        except OSError:
            pass
        agent.close()

    def stop(self) -> None:
        self._listener.close()


def run_one(args: argparse.Namespace, engine: str, robot_type: int) -> dict:
    """FC Portugal's agent of type ``robot_type`` on ``engine`` (``ode``/``mujoco``: serve in
    this process; ``real``: a real rcssserver3d)."""
    host = _RealTruth() if engine == "real" else _ServeTruth(engine, fork=args.fork)
    truth = host.truth
    agent_port, relay = host.agent_port, None
    if engine == "real" and args.fork:
        relay = _ForkRelay(host.agent_port)
        agent_port = relay.port
    cmd = [
        args.python,
        str(Path(__file__).resolve()),
        "--child",
        "--fcp",
        str(Path(args.fcp).resolve()),
        "--port",
        str(agent_port),
        "--mport",
        str(host.monitor_port),
        "--type",
        str(robot_type),
        "--trials",
        str(args.trials),
        "--tests",
        args.tests,
    ]
    started = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
    finally:
        host.stop()
        if relay is not None:
            relay.stop()
    trials = []
    for line in proc.stdout.splitlines():
        if line.startswith("{"):
            trials.append(json.loads(line))
    if not trials:
        raise RuntimeError(
            f"FC Portugal's agent reported nothing (exit {proc.returncode}):\n"
            + (proc.stdout + proc.stderr)[-3000:]
        )

    def at(t: float) -> tuple:
        return truth[min(truth, key=lambda k: abs(k - t))]

    walks, kicks, ups = [], [], {"front": [], "back": []}
    for tr in trials:
        if tr["test"] == "walk":
            p0, p1 = at(tr["t0"])[0], at(tr["t1"])[0]
            secs = max(tr["t1"] - tr["t0"], 1e-9)
            walks.append((float(np.hypot(*(p1 - p0)[:2])), secs, tr["fell"]))
        elif tr["test"] == "kick":
            b0, b1 = at(tr["t0"])[2], at(tr["t1"])[2]
            kicks.append((float(np.hypot(*(b1 - b0)[:2])), tr["done"]))
        elif tr["test"] == "getup":
            torso, up, _ = at(tr["t1"])
            stays = bool(tr["done"] and torso[2] > 0.28 and up[2] > math.cos(math.radians(30)))
            ups[tr["side"]].append((tr["cycles"], tr["done"], stays, tr["chosen"]))
    out = {
        "engine": engine,
        "robot_type": robot_type,
        "wall_s": round(time.perf_counter() - started, 1),
    }
    if walks:
        full = [d for d, s, fell in walks if not fell]
        out["walk_m_in_10s"] = [round(d, 2) for d, _, _ in walks]
        out["walk_speed_mps_median"] = round(_median([d / s for d, s, f in walks if not f]) or 0, 3)
        out["walk_falls"] = sum(f for _, _, f in walks)
        out["walk_m_in_10s_median"] = _median([round(d, 2) for d in full])
    if kicks:
        out["kick_m"] = [round(d, 2) for d, _ in kicks]
        out["kick_m_median"] = _median([d for d, _ in kicks])
    for side, rows in ups.items():
        if rows:
            done = [c for c, d, _, _ in rows if d]
            out[f"getup_{side}_cycles"] = [c for c, _, _, _ in rows]
            out[f"getup_{side}_cycles_median"] = _median(done)
            out[f"getup_{side}_stays_up"] = f"{sum(s for _, _, s, _ in rows)}/{len(rows)}"
            out[f"getup_{side}_chosen"] = sorted({c for _, _, _, c in rows})
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fcp", required=True, help="an FCPCodebase checkout")
    parser.add_argument(
        "--python", default=sys.executable, help="interpreter with numpy + pybind11 for it"
    )
    parser.add_argument("--engines", default="ode,mujoco")
    parser.add_argument("--types", default="0,1,2,3,4")
    parser.add_argument("--trials", type=int, default=3, help="trials per test and type")
    parser.add_argument("--tests", default="walk,kick,getup")
    parser.add_argument("--timeout", type=float, default=900.0, help="seconds per engine × type")
    parser.add_argument(
        "--fork",
        action="store_true",
        help="the real server is the SPL fork: compare like with like: the agent gets the fork's "
        "percepts with GS as upstream 0.7.3 writes it (without the fork's (k …)(ti …)), and "
        "serve runs as the fork (3 decimals, no field lines)",
    )
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--port", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--mport", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--type", type=int, default=0, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        _child(args)
        return
    results = []
    for engine in args.engines.split(","):
        for t in (int(x) for x in args.types.split(",")):
            r = run_one(args, engine, t)
            results.append(r)
            print({k: v for k, v in r.items() if not isinstance(v, list)}, flush=True)
    print(json.dumps({"fcp_on_serve": results}))


if __name__ == "__main__":
    main()

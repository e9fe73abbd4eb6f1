"""How reliably and how fast does a full team join a server? ``robocup-gym team``'s players
(:class:`~robocup_gym.soccer.remote.ServerTeam`) join a fresh server again and again, then play
20 cycles; on ``robocup-gym serve`` (the reference, measured in the same run) and, where
``RCSSSERVER3D`` names one, on a real rcssserver3d.

* ``serve_join_s_median``, ``real_join_s_median`` (and ``_max``): seconds from the first
  connection to every player told its side and number, all answering the same cycle;
* ``serve_failures``, ``real_failures``: joins that did not finish within 30 s, or teams that
  stopped getting percepts afterwards;
* ``real_vs_serve``: the real server's median join time over ``serve``'s.

    python benchmarks/team_joins.py [--players 11] [--runs 20]

Prints one line per server and, last, one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

from robocup_gym.soccer.match import make_team
from robocup_gym.soccer.remote import ServerTeam
from robocup_gym.types import AgentCommand


def _joins(start, stop, players: int, runs: int) -> tuple[list[float], int]:
    """Join times of the runs that worked, and how many did not."""
    times, failures = [], 0
    for _ in range(runs):
        handle, port = start()
        try:
            t0 = time.monotonic()
            with ServerTeam(make_team("standing"), port=port, players=players, timeout=30) as t:
                times.append(time.monotonic() - t0)
                for _ in range(20):
                    for p in t.players:
                        p.perceive()
                    for p in t.players:
                        p.send(AgentCommand())
        except ConnectionError as exc:
            failures += 1
            print(f"  failed: {exc}")
        finally:
            stop(handle)
    return times, failures


def _serve():
    from robocup_gym.server.bench import start_server_process

    proc, agent_port, _ = start_server_process("--sync", "--no-real-time")
    return proc, agent_port


def _stop_serve(proc) -> None:
    from robocup_gym.server.bench import stop_server_process

    stop_server_process(proc)


def _real(binary: str):
    from robocup_gym.backends.process import ServerProcess

    def start():
        server = ServerProcess(binary, sync=True, real_time=False)
        server.start()
        return server, server.agent_port

    return start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--players", type=int, default=11)
    parser.add_argument("--runs", type=int, default=20)
    args = parser.parse_args()
    out: dict[str, object] = {"players": args.players, "runs": args.runs}
    servers = [("serve", _serve, _stop_serve)]
    binary = os.environ.get("RCSSSERVER3D")
    if binary:
        servers.append(("real", _real(binary), lambda s: s.stop()))
    for name, start, stop in servers:
        times, failures = _joins(start, stop, args.players, args.runs)
        out[f"{name}_failures"] = failures
        if times:
            out[f"{name}_join_s_median"] = round(statistics.median(times), 3)
            out[f"{name}_join_s_max"] = round(max(times), 3)
        print(
            f"{name}: {args.runs - failures}/{args.runs} joins of {args.players} players, "
            f"median {out.get(f'{name}_join_s_median')} s, max {out.get(f'{name}_join_s_max')} s"
        )
    if "real_join_s_median" in out and out.get("serve_join_s_median"):
        out["real_vs_serve"] = round(out["real_join_s_median"] / out["serve_join_s_median"], 3)
    print(json.dumps(out))


if __name__ == "__main__":
    main()

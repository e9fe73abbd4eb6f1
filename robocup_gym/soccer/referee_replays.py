"""Referee situations replayed on a server over the wire, to compare ``robocup-gym serve``'s
decisions with a real rcssserver3d's: a team of standing players (its own connection per
player) and a trainer on the monitor port that moves players at given cycles, while the
monitor stream shows where the server puts them.

``python -m robocup_gym.soccer.referee_replays [--runs N]`` replays each situation N times on
``serve`` and, where ``RCSSSERVER3D`` names one, on a real server, and prints where the player
the rule moves ends (JSON last).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import select
from collections.abc import Callable

from robocup_gym.backends.rcssserver3d_monitor import MonitorTracker
from robocup_gym.protocol import trainer as trainer_cmds
from robocup_gym.protocol.framing import FrameDecoder, connect, recv_frame, send_frame
from robocup_gym.soccer.remote import ServerTeam
from robocup_gym.soccer.scripted import StandingTeam

__all__ = ["illegal_defence_replay", "replay", "touching_replay"]

_FOUL = re.compile(r"\(foul (\d+) (\d+) (\d+) (\d+)\)")


def replay(
    agent_port: int,
    monitor_port: int,
    *,
    players: int,
    track: int,
    script: list,
    read_after: float,
    fouls: list | None = None,
) -> tuple[float, float]:
    """On a server: ``players`` standing players of one team (left) and a trainer that sends
    each message of ``script`` (``(condition(game_time, cycle, shown), message)``, in order,
    checked from the team's own loop; ``shown`` maps each player's number to where the monitor
    stream last showed its torso, world (x, y)). Returns where the stream shows the torso of
    player ``track`` at game time ``read_after``, world (x, y); ``fouls`` (a list) gets the
    ``(number, type, team, unum)`` of every ``foul`` the stream reports (team 1: left)."""
    trainer = connect("127.0.0.1", monitor_port, retry_s=10.0)
    decoder = FrameDecoder()
    trackers = {unum: MonitorTracker() for unum in range(1, players + 1)}
    for unum, each in trackers.items():
        each.set_agent("left", unum)
    tracker, shown = trackers[track], {}
    script = list(script)
    seen: list = []
    try:
        with ServerTeam(
            StandingTeam(), port=agent_port, name="D", players=players, timeout=30
        ) as team:
            goalie = team.players[0]
            perceive, cycles = goalie.perceive, [0]

            def perceive_and_direct():
                p = perceive()
                cycles[0] += 1
                while select.select([trainer], [], [], 0.0)[0] or decoder.pending:
                    frame = recv_frame(trainer, decoder, 5.0)
                    for unum, each in trackers.items():
                        each.feed(frame)
                        snap = each.newest()
                        if snap is not None and snap.torso is not None:
                            shown[unum] = (float(snap.torso[0, 3]), float(snap.torso[1, 3]))
                    if fouls is not None:
                        text = (
                            frame.decode("ascii", "replace") if isinstance(frame, bytes) else frame
                        )
                        fouls.extend(tuple(map(int, m)) for m in _FOUL.findall(text))
                    if any(each.need_full for each in trackers.values()):
                        send_frame(trainer, trainer_cmds.reqfullstate())
                    snap = tracker.newest()
                    if snap is not None and snap.torso is not None:
                        seen.append((snap.game_time, snap.torso[:2, 3].copy()))
                if script and script[0][0](p.game.game_time, cycles[0], shown):
                    send_frame(trainer, script.pop(0)[1])
                return p

            goalie.perceive = perceive_and_direct
            result = team.play(seconds=read_after + 0.5)
    finally:
        trainer.close()
    if result.end != "time" or script:
        raise RuntimeError(
            f"the replay did not run to its end (the game ended with {result.end!r}, "
            f"{len(script)} trainer message(s) not sent)"
        )
    after = [xy for t, xy in seen if t >= read_after]
    if not after:
        raise RuntimeError(f"the monitor stream showed no player {track} after {read_after} s")
    return float(after[0][0]), float(after[0][1])


def _near(shown: tuple[float, float] | None, xy: tuple[float, float], tol: float = 0.05) -> bool:
    return shown is not None and abs(shown[0] - xy[0]) < tol and abs(shown[1] - xy[1]) < tol


def illegal_defence_replay(
    agent_port: int, monitor_port: int, fouls: list | None = None
) -> tuple[float, float]:
    """Five standing players of one team; a trainer puts the goalkeeper and two field players
    in their penalty area, then a third field player at (−13.5, 0.5). Where that player is
    0.1 s later."""

    first = [(1, (-14.5, 0.0)), (2, (-14.0, 1.0)), (3, (-14.0, -1.0))]
    script = [
        (lambda t, n, shown: n == 60, trainer_cmds.play_mode("PlayOn")),
        (
            lambda t, n, shown: t >= 0.5,
            "".join(trainer_cmds.agent_move(u, "Left", (x, y, 0.4), -90.0) for u, (x, y) in first),
        ),
        (
            lambda t, n, shown: t >= 1.0,
            trainer_cmds.agent_move(4, "Left", (-13.5, 0.5, 0.4), -90.0),
        ),
    ]
    return replay(
        agent_port, monitor_port, players=5, track=4, script=script, read_after=1.1, fouls=fouls
    )


def touching_replay(
    agent_port: int, monitor_port: int, fouls: list | None = None
) -> tuple[float, float]:
    """Four standing players of one team; a trainer puts the goalkeeper out of the way and
    players 2 and 3 shoulder to shoulder (0.24 m apart), and once the monitor stream shows them
    there, player 4 against player 2 from the other side (not after a fixed count of cycles: a
    trainer's message can reach the server cycles late under load, and both moves in one cycle
    make a group that nobody joined last). Where player 4 is at 0.84 s of game time."""

    pair = [(1, (-10.0, 5.0)), (2, (-5.0, 0.0)), (3, (-5.0, 0.24))]
    script = [
        (lambda t, n, shown: n == 60, trainer_cmds.play_mode("PlayOn")),
        (
            lambda t, n, shown: n == 85,
            "".join(trainer_cmds.agent_move(u, "Left", (x, y, 0.4), -90.0) for u, (x, y) in pair),
        ),
        (
            lambda t, n, shown: all(_near(shown.get(u), xy) for u, xy in pair),
            trainer_cmds.agent_move(4, "Left", (-5.0, -0.24, 0.4), -90.0),
        ),
    ]
    return replay(
        agent_port, monitor_port, players=4, track=4, script=script, read_after=0.84, fouls=fouls
    )


SITUATIONS: dict[str, Callable[[int, int], tuple[float, float]]] = {
    "illegal_defence": illegal_defence_replay,
    "touching": touching_replay,
}


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5, help="replays of each situation")
    args = parser.parse_args(argv)
    from robocup_gym.backends.process import ServerProcess
    from robocup_gym.server.bench import start_server_process, stop_server_process

    real_binary = os.environ.get("RCSSSERVER3D")
    out: dict = {}
    for name, situation in SITUATIONS.items():
        for server in ("serve", "real") if real_binary else ("serve",):
            ends = []
            for _ in range(args.runs):
                if server == "serve":
                    proc, agent_port, monitor_port = start_server_process(
                        "--sync", "--no-real-time"
                    )
                    try:
                        ends.append(situation(agent_port, monitor_port))
                    finally:
                        stop_server_process(proc)
                else:
                    real = ServerProcess(real_binary, sync=True, real_time=False)
                    real.start()
                    try:
                        ends.append(situation(real.agent_port, real.monitor_port))
                    finally:
                        real.stop()
            rounded = [[round(x, 2), round(y, 2)] for x, y in ends]
            out[f"{name}_{server}"] = rounded
            print(
                f"{name:16s} {server:6s} " + " ".join(f"({x:+.2f}, {y:+.2f})" for x, y in rounded)
            )
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

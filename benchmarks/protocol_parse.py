"""Throughput of the protocol code on the real-server percept fixtures, on one core.

Measures, over the 20 captured rcssserver3d percepts (SPL-fork format, 7 with ``See``):

* ``perception_msgs_per_s`` — full parse into :class:`robocup_gym.types.Perception`;
* ``sexpr_msgs_per_s`` — generic S-expression reading only;
* ``format_msgs_per_s`` — :func:`format_perception` (2 decimals, upstream layout);
* ``upstream_perception_msgs_per_s`` — full parse of the 2-decimal upstream example (§5.13);
* ``agent_command_msgs_per_s`` — server-side parse of a 22-joint agent command.

Each figure is the best of ``--rounds`` timed rounds. The last line printed is one JSON object.

Usage: ``python benchmarks/protocol_parse.py [--quick] [--rounds N] [--seconds S]``
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from robocup_gym.protocol.effectors import format_command, parse_agent_message
from robocup_gym.protocol.perceptors import format_perception, parse_perception
from robocup_gym.protocol.sexpr import parse
from robocup_gym.types import AgentCommand

ROOT = Path(__file__).resolve().parents[1]
FIXTURE = ROOT / "tests" / "data" / "rcssserver3d" / "perceptor_messages.txt"

# wire reference §5.13: one real rcssserver3d 0.7.3 percept (2 decimals), one line.
UPSTREAM_FIXTURE = ROOT / "tests" / "data" / "rcssserver3d" / "upstream_percept_example.txt"


def _rate(fn: Callable[[object], object], items: Sequence[object], reps: int, rounds: int) -> float:
    """Best items-per-second over ``rounds`` rounds of ``reps`` passes over ``items``."""
    best = 0.0
    for _ in range(rounds):
        start = time.perf_counter()
        for _ in range(reps):
            for item in items:
                fn(item)
        elapsed = time.perf_counter() - start
        best = max(best, reps * len(items) / elapsed)
    return best


def _reps_for(
    fn: Callable[[object], object], items: Sequence[object], seconds: float, quick: bool
) -> int:
    if quick:
        return 1
    start = time.perf_counter()
    for item in items:
        fn(item)
    once = max(time.perf_counter() - start, 1e-6)
    return max(1, int(seconds / once))


def main(argv: list[str] | None = None) -> dict[str, object]:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="tiny iteration count (for tests)")
    ap.add_argument("--rounds", type=int, default=5, help="timed rounds per figure (best wins)")
    ap.add_argument("--seconds", type=float, default=0.5, help="target duration of one round")
    args = ap.parse_args(argv)
    rounds = 1 if args.quick else args.rounds

    messages = [line for line in FIXTURE.read_text(encoding="latin-1").splitlines() if line]
    upstream = UPSTREAM_FIXTURE.read_text(encoding="latin-1").strip()
    perceptions = [parse_perception(m) for m in messages]
    command = format_command(AgentCommand(joint_velocities=[0.5] * 22), decimals=5)

    def figure(fn: Callable[[object], object], items: Sequence[object]) -> float:
        return round(_rate(fn, items, _reps_for(fn, items, args.seconds, args.quick), rounds), 1)

    result: dict[str, object] = {
        "perception_msgs_per_s": figure(parse_perception, messages),
        "sexpr_msgs_per_s": figure(parse, messages),
        "format_msgs_per_s": figure(format_perception, perceptions),
        "upstream_perception_msgs_per_s": figure(parse_perception, [upstream]),
        "agent_command_msgs_per_s": figure(parse_agent_message, [command]),
        "fixture_messages": len(messages),
        "mean_message_bytes": round(sum(map(len, messages)) / len(messages), 1),
        "quick": args.quick,
        "python": platform.python_version(),
        "machine": platform.machine(),
    }
    for key, value in result.items():
        if key.endswith("_per_s"):
            print(f"{key:34s} {value:>12,.0f}", file=sys.stderr)
    print(json.dumps(result))
    return result


if __name__ == "__main__":
    main()

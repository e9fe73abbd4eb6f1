"""``python -m robocup_gym.server``: run the server (same options as ``robocup-gym serve``)."""

from __future__ import annotations

import argparse
import logging
import sys

from robocup_gym.protocol.constants import DEFAULT_AGENT_PORT, DEFAULT_MONITOR_PORT
from robocup_gym.server.server import PortInUseError, serve


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m robocup_gym.server",
        description="The RoboCup Gym world behind the rcssserver3d 0.7.3 protocol "
        "(agents, RoboViz and trainers connect unchanged).",
    )
    p.add_argument("--agent-port", type=int, default=DEFAULT_AGENT_PORT, help="agent port (3100)")
    p.add_argument(
        "--monitor-port",
        "--server-port",
        dest="monitor_port",
        type=int,
        default=DEFAULT_MONITOR_PORT,
        help="monitor/trainer port (3200); --server-port as rcssserver3d",
    )
    p.add_argument("--host", default="0.0.0.0", help="address to listen on (all interfaces)")
    p.add_argument("--sync", action="store_true", help="sync mode: wait for (syn) from every agent")
    p.add_argument(
        "--real-time",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="20 ms cycles on the wall clock (default on; --no-real-time runs as fast as possible)",
    )
    p.add_argument("--ground-truth", action="store_true", help="mypos/myorien/ballpos in See")
    p.add_argument("--no-vision-noise", action="store_true", help="exact vision, no beam noise")
    p.add_argument("--full-vision", action="store_true", help="360 degree view cones")
    p.add_argument("--no-rules", action="store_true", help="no automatic referee")
    p.add_argument(
        "--monitor-interval", type=int, default=2, help="cycles per monitor frame (2 = 25 Hz)"
    )
    p.add_argument(
        "--sync-timeout",
        type=float,
        default=None,
        help="close agents that send no (syn) for this many seconds (default: wait forever)",
    )
    p.add_argument("--seed", type=int, default=None, help="random seed")
    p.add_argument("-v", "--verbose", action="count", default=0, help="more log output")
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    level = logging.WARNING - 10 * min(args.verbose, 2)
    logging.basicConfig(level=level, format="%(asctime)s %(levelname)s %(message)s")
    try:
        serve(
            agent_port=args.agent_port,
            monitor_port=args.monitor_port,
            host=args.host,
            sync=args.sync,
            real_time=args.real_time,
            ground_truth=args.ground_truth,
            vision_noise=not args.no_vision_noise,
            view_cone_deg=360.0 if args.full_vision else 120.0,
            rules=not args.no_rules,
            monitor_interval=args.monitor_interval,
            sync_timeout=args.sync_timeout,
            seed=args.seed,
        )
    except PortInUseError as exc:
        print(f"robocup-gym serve: {exc.strerror}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"robocup-gym serve: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

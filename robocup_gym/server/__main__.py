"""``python -m robocup_gym.server``: run the server (same options as ``robocup-gym serve``)."""

from __future__ import annotations

import argparse
import logging
import sys

from robocup_gym.protocol.constants import DEFAULT_AGENT_PORT, DEFAULT_MONITOR_PORT
from robocup_gym.robot.types import TYPE_NUMBERS
from robocup_gym.server.server import PortInUseError, serve
from robocup_gym.sim.engines.ode.lib import OdeUnavailableError


def port_number(text: str) -> int:
    """An argparse type: a TCP port 0–65535 (0 = let the OS choose a free one)."""
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number") from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(
            f"{port} is not a port number (0-65535; 0 lets the OS choose a free port)"
        )
    return port


def _positive(kind: type, what: str):
    """An argparse type: a finite ``kind`` (int or float) > 0 (``what`` names it in errors)."""

    def parse(text: str):
        try:
            v = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {what}") from None
        if not (v > 0 and v < float("inf")):
            raise argparse.ArgumentTypeError(f"{text} must be {what} > 0")
        return v

    return parse


positive_seconds = _positive(float, "a finite number of seconds")
positive_int = _positive(int, "a whole number")


def robot_type_list(text: str) -> tuple[int, ...]:
    """An argparse type: comma-separated robot types 0–4, e.g. ``0,4``."""
    try:
        types = tuple(sorted({int(t) for t in str(text).split(",") if t.strip()}))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a list of robot types") from None
    if not types or any(not 0 <= t <= 4 for t in types):
        raise argparse.ArgumentTypeError(f"{text!r}: robot types are 0 to 4, at least one")
    return types


def _load_config(parser: argparse.ArgumentParser, path: str) -> dict:
    """The options of TOML file ``path`` as argparse defaults (checked like the flags)."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        try:
            import tomli as tomllib  # type: ignore[no-redef]
        except ModuleNotFoundError:
            parser.error("--config needs Python 3.11 or the tomli package (pip install tomli)")
    try:
        with open(path, "rb") as f:
            data = tomllib.load(f)
    except OSError as exc:
        parser.error(f"--config {path}: {exc.strerror or exc}")
    except tomllib.TOMLDecodeError as exc:
        parser.error(f"--config {path}: not valid TOML ({exc})")
    actions = {a.dest: a for a in parser._actions if a.dest not in ("help", "config")}
    out = {}
    for key, value in data.items():
        dest = key.replace("-", "_")
        action = actions.get(dest)
        negated = actions.get(dest[3:]) if dest.startswith("no_") else None
        if action is None and isinstance(negated, argparse.BooleanOptionalAction):
            if not isinstance(value, bool):  # `no-rules = true` is `rules = false`
                parser.error(f"--config {path}: {key} must be true or false, got {value!r}")
            out[negated.dest] = not value
            continue
        if action is None:
            valid = ", ".join(sorted(d.replace("_", "-") for d in actions))
            parser.error(f"--config {path}: unknown option {key!r}; valid: {valid}")
        if isinstance(action, argparse.BooleanOptionalAction) or action.const is True:
            if not isinstance(value, bool):
                parser.error(f"--config {path}: {key} must be true or false, got {value!r}")
        elif action.type is not None:
            text = ",".join(map(str, value)) if isinstance(value, list) else str(value)
            try:
                value = action.type(text)
            except argparse.ArgumentTypeError as exc:
                parser.error(f"--config {path}: {key}: {exc}")
            except ValueError:
                parser.error(f"--config {path}: {key}: {value!r} is not valid")
        if action.choices is not None and value not in action.choices:
            parser.error(f"--config {path}: {key} must be one of {list(action.choices)}")
        out[dest] = value
    return out


class _OneLineErrors(argparse.ArgumentParser):
    """Usage errors as one line (``prog: error: …; see --help``), exit status 2."""

    def error(self, message: str):  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


_SWITCHES: tuple[tuple[str, bool, str], ...] = (
    (
        "--sync",
        False,
        "sync mode: wait for (syn) from every agent (default off)",
    ),
    (
        "--real-time",
        True,
        "20 ms cycles on the wall clock (default on; --no-real-time runs as fast as possible)",
    ),
    (
        "--ground-truth",
        False,
        "mypos/myorien/ballpos in See (default off; `robocup-gym agent` without a monitor "
        "port needs it)",
    ),
    (
        "--vision-noise",
        True,
        "vision noise, calibration offset and beam noise, as rcssserver3d (--no-vision-noise: "
        "exact vision)",
    ),
    (
        "--full-vision",
        False,
        "unrestricted vision: 360 degree view cones (default: 120 degrees)",
    ),
    (
        "--field-lines",
        True,
        "field lines in See, as rcssserver3d 0.7.3 (--no-field-lines: none, as the SPL fork)",
    ),
    (
        "--rules",
        True,
        "the automatic referee (--no-rules: play modes only by trainer command)",
    ),
    (
        "--type-limits",
        True,
        "the league's per-team robot-type rules (--no-type-limits: e.g. 11 robots of type 0)",
    ),
)
"""The on/off options (``--NAME`` / ``--no-NAME``): flag, default, help."""


def build_parser(prog: str = "python -m robocup_gym.server") -> argparse.ArgumentParser:
    p = _OneLineErrors(
        prog=prog,
        description="The RoboCup Gym world behind the rcssserver3d 0.7.3 protocol "
        "(agents, RoboViz and trainers connect unchanged).",
    )
    p.add_argument(
        "--agent-port",
        type=port_number,
        default=DEFAULT_AGENT_PORT,
        help="agent port (3100; 0 = a free port, printed)",
    )
    p.add_argument(
        "--monitor-port",
        "--server-port",
        dest="monitor_port",
        type=port_number,
        default=DEFAULT_MONITOR_PORT,
        help="monitor/trainer port (3200; 0 = a free port, printed); --server-port as rcssserver3d",
    )
    p.add_argument("--host", default="0.0.0.0", help="address to listen on (all interfaces)")
    for flag, default, text in _SWITCHES:
        p.add_argument(flag, action=argparse.BooleanOptionalAction, default=default, help=text)
    p.add_argument(
        "--monitor-interval",
        type=positive_int,
        default=2,
        help="cycles per monitor frame (2 = 25 Hz)",
    )
    p.add_argument(
        "--sync-timeout",
        type=positive_seconds,
        default=None,
        help="close agents that send no (syn) for this many seconds (default: wait forever)",
    )
    p.add_argument(
        "--engine",
        choices=("ode", "mujoco"),
        default="ode",
        help="physics engine: ode (SimSpark's own step, as rcssserver3d; the default) or "
        "mujoco (the fast approximation)",
    )
    p.add_argument(
        "--decimals",
        type=int,
        choices=(2, 3),
        default=2,
        help="digits after the point in percepts: 2 as rcssserver3d 0.7.3, 3 as the SPL fork",
    )
    p.add_argument(
        "--robot-types",
        type=robot_type_list,
        default=TYPE_NUMBERS,
        help="robot types agents may load, e.g. 0,4 (default: every Nao type, 0,1,2,3,4)",
    )
    p.add_argument(
        "--config",
        type=str,
        default=None,
        help="a TOML file of these options (their names without the leading dashes, e.g. "
        "sync = true, agent-port = 0, robot-types = [0, 4]); flags given here win",
    )
    p.add_argument("--seed", type=int, default=None, help="random seed")
    p.add_argument("-v", "--verbose", action="count", default=0, help="more log output")
    return p


def main(argv: list[str] | None = None, prog: str = "python -m robocup_gym.server") -> int:
    """Run the server with command-line ``argv``; returns the exit status (2: a bad option or a
    port that cannot be used, each said in one line on stderr)."""
    parser = build_parser(prog)
    first, _ = parser.parse_known_args(argv)
    if first.config is not None:
        parser.set_defaults(**_load_config(parser, first.config))
    args = parser.parse_args(argv)
    if args.agent_port == args.monitor_port and args.agent_port != 0:
        parser.error(
            f"--agent-port and --monitor-port are both {args.agent_port}; agents and monitors "
            "need two different ports"
        )
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
            vision_noise=args.vision_noise,
            view_cone_deg=360.0 if args.full_vision else 120.0,
            field_lines=args.field_lines,
            rules=args.rules,
            monitor_interval=args.monitor_interval,
            sync_timeout=args.sync_timeout,
            seed=args.seed,
            decimals=args.decimals,
            robot_types=args.robot_types,
            type_limits=args.type_limits,
            engine=args.engine,
        )
    except PortInUseError as exc:
        print(f"{prog}: error: {exc.strerror}", file=sys.stderr)
        return 2
    except OdeUnavailableError as exc:
        print(f"{prog}: error: {exc} (here: --engine mujoco)", file=sys.stderr)
        return 2
    except (OSError, ValueError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

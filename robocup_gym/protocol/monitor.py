"""The monitor stream, server → monitor on port 3200 (wire reference §7).

Every frame is three expressions: the environment/game-state list, the header ``(RSG 0 1)``
(full scene) or ``(RDS 0 1)`` (delta), and the scene graph (:mod:`.scenegraph`).

* :func:`parse_monitor_message` reads one frame into a :class:`MonitorFrame`;
* :class:`MonitorState` is a client's view: it merges the game state of every frame and keeps
  the scene graph up to date across deltas (world transforms of every node);
* :func:`format_environment`, :func:`format_game_state` and :func:`format_monitor_message` write
  frames for a server (use :class:`~robocup_gym.protocol.scenegraph.DeltaEncoder` for the scene).

Values in the environment list use C++ stream formatting (``%g``: ``30``, ``0.042``). The game
state carries the play mode as a numeric id into ``play_modes``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

from robocup_gym.protocol.constants import DEFAULT_ENVIRONMENT, PLAY_MODES
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.scenegraph import (
    DeltaNode,
    SceneGraph,
    SceneNode,
    format_delta_scene,
    format_full_scene,
    parse_delta_nodes,
    parse_scene_nodes,
)
from robocup_gym.protocol.sexpr import SExpr, dumps, parse
from robocup_gym.protocol.values import fmt_g, is_atom, strict_float, strict_int

__all__ = [
    "Foul",
    "MonitorFrame",
    "MonitorInfo",
    "MonitorState",
    "format_environment",
    "format_game_state",
    "format_monitor_frame",
    "format_monitor_message",
    "parse_monitor_message",
]


@dataclass(frozen=True)
class Foul:
    """``(foul <index> <type> <team> <unum>)``.

    Type 0 crowding … 7 self collision; team 1 = left, 2 = right.
    """

    index: int
    type: int
    team: int
    unum: int


@dataclass
class MonitorInfo:
    """The typed content of one frame's environment/game-state list; ``None`` = not in the frame."""

    constants: dict[str, float] = field(default_factory=dict)
    """Single-number environment predicates (``FieldLength`` 30, ``BallRadius`` 0.042, …)."""
    play_modes: tuple[str, ...] | None = None
    time: float | None = None
    """Game time, s."""
    half: int | None = None
    score_left: int | None = None
    score_right: int | None = None
    play_mode: int | None = None
    """Numeric play-mode id (index into ``play_modes``)."""
    team_left: str | None = None
    team_right: str | None = None
    pass_mode_score_wait_left: float | None = None
    pass_mode_score_wait_right: float | None = None
    fouls: list[Foul] = field(default_factory=list)
    other: dict[str, tuple[SExpr, ...]] = field(default_factory=dict)
    """Predicates not understood, verbatim."""


@dataclass
class MonitorFrame:
    """One monitor frame."""

    environment: list[tuple[str, tuple[SExpr, ...]]]
    """The first list verbatim: ``(name, values)`` in order."""
    info: MonitorInfo
    full: bool
    """``True`` for ``RSG`` (full scene), ``False`` for ``RDS`` (delta)."""
    version: tuple[int, int]
    """The two numbers of the header (``0 1``)."""
    scene: list[SceneNode] | list[DeltaNode]
    """:class:`SceneNode` list for a full frame, :class:`DeltaNode` list for a delta."""


_INT_KEYS = ("half", "score_left", "score_right", "play_mode")
_FLOAT_KEYS = ("time", "pass_mode_score_wait_left", "pass_mode_score_wait_right")
_STR_KEYS = ("team_left", "team_right")


def parse_monitor_message(msg: str | bytes | bytearray) -> MonitorFrame:
    """Parse one monitor frame (payload without the length prefix).

    Raises:
        ProtocolError: for malformed text, a frame that is not three expressions, an unknown
            header (e.g. RoboViz's newer ``RSMP`` format), or malformed scene nodes.
    """
    exprs = parse(msg)
    if len(exprs) != 3:
        raise ProtocolError(
            f"a monitor frame has 3 expressions (environment, header, scene), found {len(exprs)}"
        )
    env_expr, header, scene_expr = exprs
    if not isinstance(env_expr, list) or not isinstance(scene_expr, list):
        raise ProtocolError("environment and scene of a monitor frame must be lists")
    if (
        not isinstance(header, list)
        or len(header) != 3
        or header[0] not in ("RSG", "RDS")
        or not all(isinstance(x, str) for x in header[1:])
    ):
        raise ProtocolError(f"expected (RSG 0 1) or (RDS 0 1), got {dumps(header)[:40]}")
    version = (
        strict_int(header[1], predicate=header[0]),  # type: ignore[arg-type]
        strict_int(header[2], predicate=header[0]),  # type: ignore[arg-type]
    )
    environment: list[tuple[str, tuple[SExpr, ...]]] = []
    for item in env_expr:
        if not isinstance(item, list) or not item or not isinstance(item[0], str):
            raise ProtocolError(f"environment entries are (name value…) lists, got {item!r:.40}")
        environment.append((item[0], tuple(item[1:])))
    full = header[0] == "RSG"
    scene: list[SceneNode] | list[DeltaNode] = (
        parse_scene_nodes(scene_expr) if full else parse_delta_nodes(scene_expr)
    )
    return MonitorFrame(environment, _info(environment), full, version, scene)


def _info(environment: Sequence[tuple[str, tuple[SExpr, ...]]]) -> MonitorInfo:
    info = MonitorInfo()
    for name, values in environment:
        atoms = [v for v in values if isinstance(v, str)]
        if len(atoms) != len(values):
            info.other[name] = values
        elif name == "play_modes":
            info.play_modes = tuple(atoms)
        elif name in _INT_KEYS:
            setattr(info, name, strict_int(_one(name, atoms), predicate=name))
        elif name in _FLOAT_KEYS:
            setattr(info, name, strict_float(_one(name, atoms), predicate=name))
        elif name in _STR_KEYS:
            setattr(info, name, _one(name, atoms))
        elif name == "foul":
            if len(atoms) != 4:
                raise ProtocolError("(foul …) needs index, type, team, unum", predicate="foul")
            info.fouls.append(Foul(*(strict_int(a, predicate="foul") for a in atoms)))
        elif len(atoms) == 1:
            try:
                info.constants[name] = strict_float(atoms[0])
            except ProtocolError:
                info.other[name] = values
        else:
            info.other[name] = values
    return info


def _one(name: str, atoms: list[str]) -> str:
    if len(atoms) != 1:
        raise ProtocolError(f"({name} …) needs exactly one value, got {len(atoms)}", predicate=name)
    return atoms[0]


class MonitorState:
    """A monitor client's view of the game, updated frame by frame.

    Keeps the latest value of every game-state field, the environment constants and the scene
    graph (replaced by full frames, patched by deltas; deltas before the first full frame are
    ignored, as RoboViz does).
    """

    def __init__(self) -> None:
        self.info = MonitorInfo(play_modes=PLAY_MODES)
        """Merged game state (latest value of every field)."""
        self.scene = SceneGraph()
        self.has_scene = False
        """True once a full scene arrived."""
        self.frames = 0

    def update(self, msg: str | bytes | bytearray | MonitorFrame) -> MonitorFrame:
        """Apply one frame (text or already parsed); returns the parsed frame.

        Raises:
            ProtocolError: for a malformed frame or a delta that does not fit the scene.
        """
        frame = msg if isinstance(msg, MonitorFrame) else parse_monitor_message(msg)
        new = frame.info
        merged = self.info
        merged.constants.update(new.constants)
        for name in (*_INT_KEYS, *_FLOAT_KEYS, *_STR_KEYS, "play_modes"):
            value = getattr(new, name)
            if value is not None:
                setattr(merged, name, value)
        merged.fouls.extend(new.fouls)
        merged.other.update(new.other)
        if frame.full:
            self.scene = SceneGraph(list(frame.scene))  # type: ignore[arg-type]
            self.has_scene = True
        elif self.has_scene:
            self.scene.apply_delta(frame.scene)  # type: ignore[arg-type]
        self.frames += 1
        return frame

    @property
    def play_mode_name(self) -> str | None:
        """Name of the current play mode (``play_modes[play_mode]``), if known."""
        pm = self.info.play_mode
        modes = self.info.play_modes or PLAY_MODES
        if pm is None or not 0 <= pm < len(modes):
            return None
        return modes[pm]


# --------------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------------


def _value(v: float | int | str) -> str:
    if isinstance(v, str):
        if not is_atom(v):
            raise ValueError(f"{v!r} is not a single atom")
        return v
    return fmt_g(v)


def format_environment(
    constants: Iterable[tuple[str, float]] = DEFAULT_ENVIRONMENT,
    play_modes: Sequence[str] = PLAY_MODES,
) -> str:
    """The static part of a full frame's first list, without the outer parentheses:
    ``(FieldLength 30)(FieldWidth 20)…(play_modes BeforeKickOff …)``."""
    text = "".join(f"({_value(name)} {_value(v)})" for name, v in constants)
    return text + "(play_modes " + " ".join(_value(m) for m in play_modes) + ")"


def format_game_state(
    time: float,
    *,
    team_left: str | None = None,
    team_right: str | None = None,
    half: int | None = None,
    score_left: int | None = None,
    score_right: int | None = None,
    play_mode: int | str | None = None,
    extra: Iterable[tuple[str, Sequence[float | int | str]]] = (),
) -> str:
    """The dynamic predicates, without outer parentheses, in the server's order:
    ``(time t)(team_left A)(team_right B)(half h)(score_left n)(score_right m)(play_mode id)``.

    Leave out what a delta frame does not repeat. ``play_mode`` may be a name (converted to
    its id). ``extra`` appends e.g. ``("foul", (1, 0, 1, 7))``.
    """
    parts = [f"(time {fmt_g(time)})"]
    if team_left is not None:
        parts.append(f"(team_left {_value(team_left)})")
    if team_right is not None:
        parts.append(f"(team_right {_value(team_right)})")
    if half is not None:
        parts.append(f"(half {int(half)})")
    if score_left is not None:
        parts.append(f"(score_left {int(score_left)})")
    if score_right is not None:
        parts.append(f"(score_right {int(score_right)})")
    if play_mode is not None:
        pm = PLAY_MODES.index(play_mode) if isinstance(play_mode, str) else int(play_mode)
        parts.append(f"(play_mode {pm})")
    for name, values in extra:
        parts.append(f"({_value(name)}" + "".join(f" {_value(v)}" for v in values) + ")")
    return "".join(parts)


def format_monitor_message(environment: str, scene: str, *, full: bool) -> str:
    """One frame: ``(<environment>)(RSG 0 1)<scene>`` or with ``(RDS 0 1)``.

    Args:
        environment: predicates without outer parentheses (:func:`format_environment` +
            :func:`format_game_state` for a full frame, :func:`format_game_state` for a delta).
        scene: the scene list with its parentheses (:func:`.scenegraph.format_full_scene` or
            :class:`.scenegraph.DeltaEncoder`).
        full: ``True`` for ``RSG``.

    Raises:
        ValueError: for an empty environment (RoboViz crashes on an empty first list).
    """
    if not environment:
        raise ValueError("the environment list must not be empty (include at least (time t))")
    return f"({environment}){'(RSG 0 1)' if full else '(RDS 0 1)'}{scene}"


def format_monitor_frame(frame: MonitorFrame) -> str:
    """A parsed frame back as text (numbers of the environment list verbatim)."""
    env = "".join(
        "(" + " ".join([name, *(v if isinstance(v, str) else dumps(v) for v in values)]) + ")"
        for name, values in frame.environment
    )
    header = f"({'RSG' if frame.full else 'RDS'} {frame.version[0]} {frame.version[1]})"
    scene = (
        format_full_scene(frame.scene)  # type: ignore[arg-type]
        if frame.full
        else format_delta_scene(frame.scene)  # type: ignore[arg-type]
    )
    return f"({env}){header}{scene}"

"""Sockets and message decoding of the server: non-blocking connections and lenient parsing.

A :class:`Connection` owns one accepted TCP socket. Received bytes go through a
:class:`~robocup_gym.protocol.framing.FrameDecoder` into :attr:`Connection.inbox`; outgoing frames
are written without ever blocking (wire reference §1.4): when the kernel buffer is full the unsent
tail of the current frame is kept, the next send to that client only pushes that tail and drops the
new message. So frame boundaries stay intact and a slow reader loses messages, never stalls the
server.

:func:`agent_actions` and :func:`trainer_commands` decode one payload like the real server does:
structurally broken text is salvaged (complete top-level lists are kept, stray ``)`` and an
unclosed tail are dropped) instead of raising.
"""

from __future__ import annotations

import contextlib
import logging
import re
import socket

from robocup_gym.protocol import effectors, trainer
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.framing import FrameDecoder
from robocup_gym.protocol.sexpr import SExpr, dumps

log = logging.getLogger("robocup_gym.server")

RECV_CHUNK = 1 << 16
"""Bytes read per ``recv`` (as the real server: 64 KiB)."""
AGENT_MAX_FRAME = 1 << 20
"""Largest frame accepted from an agent or monitor (1 MiB; real commands are < 2 KiB). A larger
length prefix means a corrupt stream or not our protocol: the connection is closed."""
WARN_LIMIT = 5
"""Per connection, how many ignored/malformed messages are logged at WARNING before the rest go to
DEBUG (a misbehaving client must not flood the log)."""

_TOKEN = re.compile(r"\(|\)|[^ \t\n\r\v\f()]+")


def salvage(text: str, max_depth: int = 64) -> list[SExpr]:
    """Top-level expressions of broken S-expression text, as far as they are complete.

    A ``)`` without a matching ``(`` is skipped, an expression still open at the end is dropped
    while the complete expressions inside it are kept at the top level, and anything nested
    deeper than ``max_depth`` is flattened into its parent (never recursion).
    """
    stack: list[list[SExpr]] = []
    cur: list[SExpr] = []
    too_deep = 0
    for tok in _TOKEN.findall(text):
        if tok == "(":
            if len(stack) >= max_depth:
                too_deep += 1
                continue
            new: list[SExpr] = []
            cur.append(new)
            stack.append(cur)
            cur = new
        elif tok == ")":
            if too_deep:
                too_deep -= 1
            elif stack:
                cur = stack.pop()
        else:
            cur.append(tok)
    while stack:
        # an expression still open at the end is dropped (its last value may be cut short),
        # but the complete expressions inside it are kept: ``(lle3 2.0(syn)`` still syncs
        parent = stack.pop()
        parent.pop()
        parent.extend(x for x in cur if isinstance(x, list))
        cur = parent
    return cur


_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_SIMPLE = re.compile(rf"(?:\s*\((?:[a-z]{{2,3}}\d {_NUM}|syn)\))*\s*")
_SIMPLE_ITEM = re.compile(rf"\(([a-z]{{2,3}}\d) ({_NUM})\)")


def fast_joint_message(payload: bytes) -> tuple[list[tuple[str, str]], bool] | None:
    """The common per-cycle message ``(he1 0.12345)…(syn)`` without the general parser.

    Returns ``([(name, number text), …], has_syn)`` in order, or ``None`` if the message has any
    other form (then use :func:`agent_actions`). Names are not checked; numbers are plain decimal
    floats, so ``float()`` reads them exactly as C ``atof`` would.
    """
    text = payload.decode("latin-1")
    if _SIMPLE.fullmatch(text) is None:
        return None
    return _SIMPLE_ITEM.findall(text), "(syn)" in text


def agent_actions(payload: bytes) -> tuple[list[effectors.AgentAction], bool]:
    """The actions of one agent frame and whether the text was well-formed."""
    with contextlib.suppress(ProtocolError):
        return effectors.parse_agent_message(payload), True
    text = payload.decode("latin-1")
    out: list[effectors.AgentAction] = []
    for expr in salvage(text):
        if not isinstance(expr, list) or not expr or not isinstance(expr[0], str):
            continue
        try:
            out.extend(effectors.parse_agent_message(dumps_safe(expr)))
        except ProtocolError:  # pragma: no cover - a salvaged expression is balanced
            continue
    return out, False


def trainer_commands(payload: bytes) -> tuple[list[trainer.TrainerCommand], bool]:
    """The commands of one monitor-port frame (malformed ones as ``InvalidCmd``)."""
    with contextlib.suppress(ProtocolError):
        return trainer.parse_trainer_message(payload, strict=False), True
    out: list[trainer.TrainerCommand] = []
    for expr in salvage(payload.decode("latin-1")):
        if not isinstance(expr, list) or not expr or not isinstance(expr[0], str):
            continue
        try:
            out.extend(trainer.parse_trainer_message(dumps_safe(expr), strict=False))
        except ProtocolError:  # pragma: no cover
            continue
    return out, False


def dumps_safe(expr: SExpr) -> str:
    """``expr`` as text; atoms are known to be valid because they came from the tokenizer."""
    try:
        return dumps(expr)
    except ProtocolError:
        return ""


class Connection:
    """One accepted client socket (agent or monitor), non-blocking in both directions."""

    def __init__(self, sock: socket.socket, cid: int, addr: object, kind: str) -> None:
        sock.setblocking(False)
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.sock = sock
        self.cid = cid
        """Client id: 1, 2, 3, … in accept order, never reused (wire reference §1.1)."""
        self.addr = addr
        self.kind = kind
        """``"agent"`` or ``"monitor"`` (for log messages)."""
        self.decoder = FrameDecoder(AGENT_MAX_FRAME)
        self.inbox: list[bytes] = []
        """Complete payloads received and not processed yet, in arrival order."""
        self.alive = True
        """False once the peer closed, an error occurred or the stream was unusable."""
        self.closed = False
        self._tail: memoryview | None = None
        self.frames_sent = 0
        self.frames_dropped = 0
        self.warnings = 0

    def __repr__(self) -> str:
        return f"<{self.kind} #{self.cid} {self.addr}>"

    def fileno(self) -> int:
        return self.sock.fileno()

    def warn(self, msg: str, *args: object) -> None:
        """Log a client problem at WARNING the first few times, then at DEBUG."""
        self.warnings += 1
        level = logging.WARNING if self.warnings <= WARN_LIMIT else logging.DEBUG
        if self.warnings == WARN_LIMIT + 1:
            log.warning("%r: further problems with this client are logged at DEBUG level", self)
        log.log(level, "%r: " + msg, self, *args)

    def receive(self) -> None:
        """Read what the kernel has (one ``recv``) into :attr:`inbox`; marks dead on EOF/error."""
        if not self.alive:
            return
        try:
            data = self.sock.recv(RECV_CHUNK)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            log.info("%r: connection error: %s", self, exc)
            self.alive = False
            return
        if not data:
            log.info("%r: disconnected", self)
            self.alive = False
            return
        try:
            self.inbox.extend(self.decoder.feed(data))
        except ProtocolError as exc:
            log.warning("%r: closing the connection, unusable stream: %s", self, exc)
            self.alive = False

    def send(self, frame: bytes) -> bool:
        """Queue one complete frame without blocking; ``False`` if it was dropped."""
        if not self.alive:
            return False
        if self._tail is not None:
            self._flush_tail()
            self.frames_dropped += 1
            return False
        try:
            n = self.sock.send(frame)
        except (BlockingIOError, InterruptedError):
            n = 0
        except OSError as exc:
            log.info("%r: send failed: %s", self, exc)
            self.alive = False
            return False
        if n < len(frame):
            self._tail = memoryview(frame)[n:]
        self.frames_sent += 1
        return True

    def _flush_tail(self) -> None:
        tail = self._tail
        if tail is None:
            return
        try:
            n = self.sock.send(tail)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            log.info("%r: send failed: %s", self, exc)
            self.alive = False
            return
        self._tail = None if n >= len(tail) else tail[n:]

    def close(self) -> None:
        """Close the socket (idempotent)."""
        self.alive = False
        if self.closed:
            return
        self.closed = True
        with contextlib.suppress(OSError):
            self.sock.close()

"""Length-prefixed framing used on both server ports (wire reference §1.2–1.4).

Every message is a 4-byte unsigned big-endian payload length followed by the payload; no
terminator, no padding. Frames may arrive several per ``recv`` or split at any byte (also inside
the prefix), so reading needs an incremental :class:`FrameDecoder`.

Text payloads are encoded and decoded as Latin-1: one byte per character, so byte offsets and
character offsets agree and decoding never fails.
"""

from __future__ import annotations

import contextlib
import socket
import struct
import time
from collections.abc import Callable

from robocup_gym.protocol.errors import ProtocolError

__all__ = [
    "DEFAULT_MAX_FRAME_SIZE",
    "DEFAULT_TIMEOUT_S",
    "FrameDecoder",
    "connect",
    "decode_payload",
    "encode_frame",
    "encode_payload",
    "recv_frame",
    "send_frame",
]

DEFAULT_MAX_FRAME_SIZE = 16 * 1024 * 1024
"""Largest payload accepted by default, bytes (16 MiB); real percepts are ~1 KiB, monitor
frames ~10 KiB."""

DEFAULT_TIMEOUT_S = 10.0
"""Default time limit of the blocking socket helpers, s."""

_PREFIX = struct.Struct(">I")
_MAX_LENGTH = 0xFFFFFFFF
_RECV_CHUNK = 1 << 16


def encode_payload(payload: bytes | bytearray | memoryview | str) -> bytes:
    """``payload`` as bytes; a ``str`` is encoded as Latin-1.

    Raises:
        ProtocolError: for a character outside Latin-1 (it has no one-byte form on the wire).
    """
    if isinstance(payload, str):
        try:
            return payload.encode("latin-1")
        except UnicodeEncodeError as exc:
            raise ProtocolError(
                f"character {payload[exc.start]!r} cannot be sent (the wire is 8-bit text)",
                offset=exc.start,
            ) from None
    return bytes(payload)


def decode_payload(payload: bytes | bytearray | memoryview | str) -> str:
    """``payload`` as text (Latin-1, never fails); a ``str`` is returned unchanged."""
    if isinstance(payload, str):
        return payload
    return bytes(payload).decode("latin-1")


def encode_frame(
    payload: bytes | bytearray | memoryview | str, *, max_size: int | None = None
) -> bytes:
    """One frame: 4-byte big-endian length + payload.

    Args:
        payload: the message; ``str`` is encoded as Latin-1.
        max_size: optional limit on the payload length in bytes.

    Raises:
        ProtocolError: if the payload does not fit the 32-bit length or exceeds ``max_size``.
    """
    data = encode_payload(payload)
    limit = _MAX_LENGTH if max_size is None else min(max_size, _MAX_LENGTH)
    if len(data) > limit:
        raise ProtocolError(f"payload of {len(data)} bytes exceeds the frame limit of {limit}")
    return _PREFIX.pack(len(data)) + data


class FrameDecoder:
    """Incremental decoder: feed it bytes as they arrive, get complete payloads back.

    Handles several frames in one chunk and frames split across chunks at any byte, including
    inside the length prefix. Empty frames (length 0) are returned as ``b""``.

    After a :class:`ProtocolError` (oversized frame) the stream position is lost; call
    :meth:`reset` (or drop the connection) before feeding more data.
    """

    __slots__ = ("_buf", "max_frame_size")

    def __init__(self, max_frame_size: int = DEFAULT_MAX_FRAME_SIZE) -> None:
        if max_frame_size < 0:
            raise ValueError(f"max_frame_size must be >= 0, got {max_frame_size}")
        self.max_frame_size = max_frame_size
        """Largest accepted payload in bytes."""
        self._buf = bytearray()

    @property
    def pending(self) -> int:
        """Number of buffered bytes that do not yet form a complete frame."""
        return len(self._buf)

    def reset(self) -> None:
        """Drop everything buffered."""
        self._buf.clear()

    def append(self, data: bytes | bytearray | memoryview) -> None:
        """Buffer ``data`` without extracting frames (see :meth:`pop_frame`)."""
        self._buf += data

    def pop_frame(self) -> bytes | None:
        """The next complete payload from the buffer, or ``None`` if none is complete yet.

        Raises:
            ProtocolError: if the next frame announces more than :attr:`max_frame_size` bytes.
        """
        buf = self._buf
        if len(buf) < 4:
            return None
        size = _PREFIX.unpack_from(buf, 0)[0]
        if size > self.max_frame_size:
            raise ProtocolError(
                f"frame announces {size} bytes, more than the limit of {self.max_frame_size} "
                "(corrupt stream or missing length prefix?)",
                offset=0,
            )
        end = 4 + size
        if len(buf) < end:
            return None
        frame = bytes(buf[4:end])
        del buf[:end]
        return frame

    def feed(self, data: bytes | bytearray | memoryview) -> list[bytes]:
        """Buffer ``data`` and return every payload that is now complete, in order.

        Raises:
            ProtocolError: if a frame announces more than :attr:`max_frame_size` bytes; the
                frames completed before it in this call are lost with the stream position.
        """
        buf = self._buf
        buf += data
        frames: list[bytes] = []
        pos = 0
        n = len(buf)
        limit = self.max_frame_size
        unpack = _PREFIX.unpack_from
        try:
            while n - pos >= 4:
                size = unpack(buf, pos)[0]
                if size > limit:
                    raise ProtocolError(
                        f"frame announces {size} bytes, more than the limit of {limit} "
                        "(corrupt stream or missing length prefix?)",
                        offset=pos,
                    )
                end = pos + 4 + size
                if end > n:
                    break
                frames.append(bytes(buf[pos + 4 : end]))
                pos = end
        finally:
            if pos:
                del buf[:pos]
        return frames


def send_frame(
    sock: socket.socket,
    payload: bytes | bytearray | memoryview | str,
    timeout: float = DEFAULT_TIMEOUT_S,
) -> None:
    """Send one frame (prefix and payload in a single ``sendall``).

    The socket's own timeout is restored afterwards.

    Raises:
        TimeoutError: if the peer does not take the data within ``timeout`` seconds (the frame
            may then be partly sent and the stream is unusable).
        ProtocolError: for a payload that cannot be framed.
    """
    _check_timeout(timeout)
    data = encode_frame(payload)
    previous = sock.gettimeout()
    sock.settimeout(timeout)
    try:
        sock.sendall(data)
    except TimeoutError:
        raise TimeoutError(
            f"sending a {len(data)}-byte frame did not complete within {timeout} s "
            "(peer not reading?); the stream may now hold a partial frame"
        ) from None
    finally:
        sock.settimeout(previous)


def recv_frame(
    sock: socket.socket,
    decoder: FrameDecoder,
    timeout: float = DEFAULT_TIMEOUT_S,
) -> bytes:
    """Block until one complete payload is available and return it.

    Frames that arrive together are kept in ``decoder`` for the next call, so use one decoder
    per connection. Never waits longer than ``timeout`` seconds in total. The socket's own
    timeout is restored afterwards.

    Raises:
        TimeoutError: when no complete frame arrived within ``timeout``.
        ConnectionError: when the peer closed the connection.
        ProtocolError: for an oversized frame.
    """
    _check_timeout(timeout)
    frame = decoder.pop_frame()
    if frame is not None:
        return frame
    deadline = time.monotonic() + timeout
    previous = sock.gettimeout()
    try:
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise TimeoutError(
                    f"no complete frame within {timeout} s "
                    f"({decoder.pending} bytes of an incomplete frame buffered)"
                )
            sock.settimeout(remaining)
            try:
                data = sock.recv(_RECV_CHUNK)
            except TimeoutError:
                raise TimeoutError(
                    f"no complete frame within {timeout} s "
                    f"({decoder.pending} bytes of an incomplete frame buffered)"
                ) from None
            if not data:
                raise ConnectionError(
                    "connection closed by peer"
                    + (
                        f" with {decoder.pending} bytes of an incomplete frame"
                        if decoder.pending
                        else ""
                    )
                )
            decoder.append(data)
            frame = decoder.pop_frame()
            if frame is not None:
                return frame
    finally:
        with contextlib.suppress(OSError):  # socket closed meanwhile
            sock.settimeout(previous)


def _check_timeout(timeout: float) -> None:
    if timeout is None or not timeout > 0:
        raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")


def connect(
    host: str,
    port: int,
    *,
    timeout: float = 10.0,
    retry_s: float = 0.0,
    between: Callable[[], None] | None = None,
) -> socket.socket:
    """A TCP connection to ``host:port`` for framed messages: ``TCP_NODELAY`` on (the messages
    are small and must not wait for Nagle's algorithm), ``timeout`` on its operations. A
    refused connection (a server still starting) is tried again until ``retry_s`` seconds have
    passed, calling ``between()`` (default: a 50 ms sleep; a caller that watches a server
    process checks it there and raises when it died).

    Raises:
        OSError: the last attempt's error, once ``retry_s`` has passed.
    """
    deadline = time.monotonic() + retry_s
    while True:
        try:
            sock = socket.create_connection((host, int(port)), timeout=timeout)
        except OSError:
            if time.monotonic() >= deadline:
                raise
            if between is not None:
                between()
            else:
                time.sleep(0.05)
            continue
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return sock

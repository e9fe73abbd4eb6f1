"""One framed TCP connection to a server's agent or monitor port: the client side of every link
this package opens (the real-server backends, the league's agent link, the scripts' and tests'
clients).

Frames are the 4-byte length-prefixed messages of wire reference §1.2 (:mod:`.framing`).
Sending blocks; receiving polls with ``select``, so a caller can wait for a frame, or take every
frame that has arrived, with a deadline. ``TCP_NODELAY`` and (Linux) ``TCP_QUICKACK`` are on:
rcssserver3d sets neither on its sockets, and without ``QUICKACK`` the kernel delays the ACKs of
a connection that mostly receives (a monitor's) by up to ~40 ms, so that the server's own Nagle
then holds its next frames back until they come (monitor frames arrived in bursts 40 ms apart).
"""

from __future__ import annotations

import contextlib
import select
import socket
import time
from collections.abc import Callable

from robocup_gym.protocol.framing import FrameDecoder, connect, decode_payload, encode_frame

__all__ = ["Connection"]


class Connection:
    """A framed connection over ``sock``; ``what`` names it in errors (``"agent"``,
    ``"monitor"``), ``timeout`` (s) is the default of :meth:`send` and :meth:`recv`."""

    def __init__(self, sock: socket.socket, what: str = "server", timeout: float = 10.0) -> None:
        self.sock = sock
        self.what = what
        self.timeout = float(timeout)
        self.decoder = FrameDecoder()
        self.closed = False
        sock.setblocking(True)
        _set_tcp(sock, "TCP_NODELAY")
        _set_tcp(sock, "TCP_QUICKACK")

    @classmethod
    def open(
        cls,
        host: str,
        port: int,
        *,
        what: str = "server",
        timeout: float = 10.0,
        retry_s: float = 0.0,
        between: Callable[[], None] | None = None,
    ) -> Connection:
        """Connect to ``host:port``, trying a refused connection again for ``retry_s`` seconds
        (:func:`.framing.connect`, which calls ``between()`` between tries).

        Raises:
            OSError: the last attempt's error.
        """
        sock = connect(host, port, timeout=timeout, retry_s=retry_s, between=between)
        return cls(sock, what, timeout)

    def send(self, payload: str | bytes, timeout: float | None = None) -> None:
        """Send one message as one frame.

        Raises:
            ConnectionError: the connection failed or did not take it in time.
        """
        self.sock.settimeout(self.timeout if timeout is None else timeout)
        try:
            self.sock.sendall(encode_frame(payload))
        except (TimeoutError, OSError) as exc:
            raise ConnectionError(f"sending on the {self.what} connection failed: {exc}") from exc

    def recv(self, timeout: float | None = None) -> bytes:
        """The next frame's payload; waits up to ``timeout`` s (default: the connection's).

        Raises:
            TimeoutError: none complete in time.
            ConnectionError: the peer closed the connection.
        """
        timeout = self.timeout if timeout is None else timeout
        frame = self.decoder.pop_frame()
        if frame is not None:
            return frame
        deadline = time.monotonic() + timeout
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0 or not self._fill(remaining):
                raise TimeoutError(
                    f"no message on the {self.what} connection within {timeout:.1f} s"
                )
            frame = self.decoder.pop_frame()
            if frame is not None:
                return frame

    def recv_text(self, timeout: float | None = None) -> str:
        """:meth:`recv` as text."""
        return decode_payload(self.recv(timeout))

    def available(self, timeout: float = 0.0) -> list[bytes]:
        """Every complete frame that arrives within ``timeout`` s (returns at the first data
        when ``timeout`` > 0, at once when 0)."""
        frames: list[bytes] = []
        got = self._fill(timeout)
        while got:
            frame = self.decoder.pop_frame()
            while frame is not None:
                frames.append(frame)
                frame = self.decoder.pop_frame()
            got = self._fill(0.0)
        return frames

    def _fill(self, timeout: float) -> bool:
        """Read what is there (waiting up to ``timeout`` s for something); False if nothing."""
        _set_tcp(self.sock, "TCP_QUICKACK")  # Linux clears it again after some reads: re-arm
        try:
            ready, _, _ = select.select([self.sock], [], [], max(0.0, timeout))
        except (OSError, ValueError) as exc:
            raise ConnectionError(f"the {self.what} connection is closed") from exc
        if not ready:
            return False
        self.sock.settimeout(0.0)
        try:
            data = self.sock.recv(1 << 20)
        except BlockingIOError:
            return False
        except OSError as exc:
            raise ConnectionError(f"the {self.what} connection failed: {exc}") from exc
        finally:
            self.sock.settimeout(None)
        if not data:
            raise ConnectionError(f"the server closed the {self.what} connection")
        self.decoder.append(data)
        return True

    def close(self) -> None:
        """Close the connection (the peer sees the end at once); a second call does nothing."""
        if not self.closed:
            self.closed = True
            with contextlib.suppress(OSError):
                self.sock.shutdown(socket.SHUT_RDWR)
            with contextlib.suppress(OSError):
                self.sock.close()

    def __enter__(self) -> Connection:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _set_tcp(sock: socket.socket, option: str) -> None:
    """Switch a TCP option on where the OS has it (``TCP_QUICKACK`` is Linux's)."""
    value = getattr(socket, option, None)
    if value is not None:
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.IPPROTO_TCP, value, 1)

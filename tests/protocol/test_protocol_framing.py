"""Framing: 4-byte big-endian length prefix, incremental decoding, socket helpers."""

from __future__ import annotations

import socket
import struct
import threading
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from protocol_helpers import PERCEPTS

from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.framing import (
    FrameDecoder,
    decode_payload,
    encode_frame,
    recv_frame,
    send_frame,
)


def test_encode_frame_matches_spec_example() -> None:
    assert encode_frame("(syn)") == bytes.fromhex("00000005") + b"(syn)"
    assert encode_frame(b"(syn)") == b"\x00\x00\x00\x05(syn)"
    assert encode_frame("") == b"\x00\x00\x00\x00"
    big = "x" * 70000
    assert encode_frame(big)[:4] == struct.pack(">I", 70000)


def test_encode_frame_latin1_and_limits() -> None:
    assert encode_frame("é") == b"\x00\x00\x00\x01\xe9"
    assert decode_payload(b"\xe9") == "é"
    with pytest.raises(ProtocolError, match="cannot be sent"):
        encode_frame("snow ☃")
    with pytest.raises(ProtocolError, match="exceeds"):
        encode_frame(b"abcdef", max_size=5)


def _stream(payloads: list[bytes]) -> bytes:
    return b"".join(encode_frame(p) for p in payloads)


PAYLOADS = [PERCEPTS[0].encode(), b"", b"(syn)", PERCEPTS[3].encode(), b"x"]


def test_many_frames_in_one_chunk() -> None:
    dec = FrameDecoder()
    assert dec.feed(_stream(PAYLOADS)) == PAYLOADS
    assert dec.pending == 0
    frames = [f"(he1 {i})".encode() for i in range(500)]
    assert dec.feed(_stream(frames)) == frames


def test_split_at_every_byte_position() -> None:
    data = _stream(PAYLOADS)
    for cut in range(len(data) + 1):
        dec = FrameDecoder()
        got = dec.feed(data[:cut])
        got += dec.feed(data[cut:])
        assert got == PAYLOADS, cut
        assert dec.pending == 0


def test_split_at_every_pair_of_positions_small() -> None:
    payloads = [b"(a)", b"", b"(bc)"]
    data = _stream(payloads)
    for i in range(len(data) + 1):
        for j in range(i, len(data) + 1):
            dec = FrameDecoder()
            got = dec.feed(data[:i]) + dec.feed(data[i:j]) + dec.feed(data[j:])
            assert got == payloads, (i, j)


def test_byte_by_byte_and_pending() -> None:
    data = _stream(PAYLOADS)
    dec = FrameDecoder()
    got: list[bytes] = []
    for k in range(len(data)):
        got += dec.feed(data[k : k + 1])
    assert got == PAYLOADS
    dec.feed(b"\x00\x00")
    assert dec.pending == 2
    dec.reset()
    assert dec.pending == 0


def test_pop_frame_one_at_a_time() -> None:
    dec = FrameDecoder()
    dec.append(_stream([b"one", b"two"]) + b"\x00\x00\x00\x05par")
    assert dec.pop_frame() == b"one"
    assert dec.pop_frame() == b"two"
    assert dec.pop_frame() is None
    dec.append(b"ts")
    assert dec.pop_frame() == b"parts"


def test_max_frame_size_guard() -> None:
    dec = FrameDecoder(max_frame_size=10)
    assert dec.feed(encode_frame(b"0123456789")) == [b"0123456789"]
    with pytest.raises(ProtocolError, match="announces 11 bytes"):
        dec.feed(encode_frame(b"0123456789a"))
    # A percept without its length prefix: "(tim" read as a length is ~680 MB.
    with pytest.raises(ProtocolError, match="missing length prefix"):
        FrameDecoder().feed(PERCEPTS[0].encode())
    dec = FrameDecoder(max_frame_size=10)
    dec.append(encode_frame(b"x" * 11))
    with pytest.raises(ProtocolError):
        dec.pop_frame()


@settings(max_examples=60, deadline=None)
@given(
    payloads=st.lists(st.binary(max_size=40), max_size=8),
    cuts=st.lists(st.integers(min_value=0, max_value=400), max_size=6),
)
def test_random_chunking_reassembles(payloads: list[bytes], cuts: list[int]) -> None:
    data = _stream(payloads)
    points = sorted({min(c, len(data)) for c in cuts})
    dec = FrameDecoder()
    got: list[bytes] = []
    prev = 0
    for p in [*points, len(data)]:
        got += dec.feed(data[prev:p])
        prev = p
    assert got == payloads
    assert dec.pending == 0


@settings(max_examples=80, deadline=None)
@given(st.lists(st.binary(max_size=64), max_size=6))
def test_random_bytes_never_crash_decoder(chunks: list[bytes]) -> None:
    dec = FrameDecoder(max_frame_size=1000)
    for chunk in chunks:
        try:
            frames = dec.feed(chunk)
        except ProtocolError:
            dec.reset()
            continue
        assert all(len(f) <= 1000 for f in frames)
        assert dec.pending < 1004


def test_send_and_recv_frame_over_socketpair() -> None:
    a, b = socket.socketpair()
    with a, b:
        dec = FrameDecoder()
        send_frame(a, PERCEPTS[1])
        # Two frames in one write: the second must stay queued in the decoder.
        a.sendall(encode_frame("(syn)") + encode_frame(b"(he1 1)"))
        assert recv_frame(b, dec, timeout=2.0) == PERCEPTS[1].encode()
        assert recv_frame(b, dec, timeout=2.0) == b"(syn)"
        assert recv_frame(b, dec, timeout=2.0) == b"(he1 1)"
        assert b.gettimeout() is None  # restored


def test_recv_frame_reassembles_slow_sender() -> None:
    a, b = socket.socketpair()
    data = encode_frame(PERCEPTS[2])

    def slow() -> None:
        for i in range(0, len(data), 97):
            a.sendall(data[i : i + 97])
            time.sleep(0.002)

    with a, b:
        t = threading.Thread(target=slow)
        t.start()
        assert recv_frame(b, FrameDecoder(), timeout=5.0) == PERCEPTS[2].encode()
        t.join()


def test_recv_frame_times_out_instead_of_hanging() -> None:
    a, b = socket.socketpair()
    with a, b:
        a.sendall(b"\x00\x00\x00\x09(sy")  # incomplete frame
        dec = FrameDecoder()
        start = time.monotonic()
        with pytest.raises(TimeoutError, match=r"no complete frame within 0\.2 s"):
            recv_frame(b, dec, timeout=0.2)
        assert time.monotonic() - start < 2.0
        assert dec.pending == 7


def test_recv_frame_reports_closed_connection() -> None:
    a, b = socket.socketpair()
    with b:
        a.sendall(b"\x00\x00\x00\x09(sy")
        a.close()
        with pytest.raises(ConnectionError, match="closed by peer with 7 bytes"):
            recv_frame(b, FrameDecoder(), timeout=2.0)


def test_timeouts_must_be_positive() -> None:
    a, b = socket.socketpair()
    with a, b:
        with pytest.raises(ValueError):
            recv_frame(b, FrameDecoder(), timeout=0)
        with pytest.raises(ValueError):
            send_frame(a, "(syn)", timeout=-1)


def test_send_frame_times_out_when_peer_does_not_read() -> None:
    a, b = socket.socketpair()
    with a, b:
        a.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)
        with pytest.raises(TimeoutError, match="did not complete"):
            send_frame(a, b"x" * (8 << 20), timeout=0.3)

"""The link (hil/link.py) reads everything waiting on every transport, and turns every failure of the link
itself (a hung-up terminal, a closed socket, a broken pipe) into one LinkError naming the port."""
from __future__ import annotations

import os
import socket
import threading
import time
import tty
from collections.abc import Iterator

import numpy as np
import pytest

from hil.link import LinkError, open_link
from hil.states import index_ranges, mask_of_ranges


@pytest.fixture
def server() -> Iterator[socket.socket]:
    """A listening loopback TCP socket."""
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.bind(("127.0.0.1", 0))
    s.listen(1)
    s.settimeout(5)
    yield s
    s.close()


def _url(server: socket.socket) -> str:
    return f"socket://127.0.0.1:{server.getsockname()[1]}"


def _read_until(link, n: int, timeout_s: float = 5.0) -> tuple[bytes, int]:  # type: ignore[no-untyped-def]
    """What ``link`` gives until ``n`` octets (bounded), and the number of read_waiting calls that gave some."""
    got, calls = b"", 0
    deadline = time.monotonic() + timeout_s
    while len(got) < n and time.monotonic() < deadline:
        link.wait(0.05)
        chunk = link.read_waiting()
        calls += bool(chunk)
        got += chunk
    return got, calls


def test_socket_reads_everything_waiting_in_one_call(server):
    """pyserial's socket in_waiting says 0 or 1; the link must not read one octet per call."""
    link = open_link(_url(server))
    conn, _ = server.accept()
    try:
        payload = bytes(range(256)) * 200  # 51 200 octets
        conn.sendall(payload)
        time.sleep(0.2)  # all of it is in the harness's receive buffer
        got, calls = _read_until(link, len(payload))
        assert got == payload and calls <= 2 and link.octets_in == len(payload)
        assert link.read_waiting() == b""  # nothing waiting: nothing, at once
    finally:
        conn.close()
        link.close()


def test_pty_reads_everything_waiting_in_one_call():
    master, slave = os.openpty()
    tty.setraw(slave)
    link = open_link(os.ttyname(slave))
    try:
        os.write(master, b"\x55" * 3000)
        time.sleep(0.1)
        got, calls = _read_until(link, 3000)
        assert got == b"\x55" * 3000 and calls == 1
    finally:
        link.close()
        os.close(master)
        os.close(slave)


def test_closed_socket_is_a_link_error(server):
    link = open_link(_url(server))
    conn, _ = server.accept()
    conn.sendall(b"abc")
    conn.close()
    time.sleep(0.1)
    assert link.read_waiting() == b"abc"  # what arrived before the end is read first
    with pytest.raises(LinkError) as exc:
        _read_until(link, 10, timeout_s=2.0)
    assert _url(server) in str(exc.value) and "disconnected" in str(exc.value)
    link.close()
    link.close()  # closing a dead link twice never raises


def test_broken_pipe_is_a_link_error(server):
    link = open_link(_url(server))
    conn, _ = server.accept()
    conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")  # RST on close
    conn.close()
    time.sleep(0.1)
    with pytest.raises(LinkError) as exc:
        for _ in range(100):
            link.write(b"\x00" * 1000)
            time.sleep(0.01)
    assert _url(server) in str(exc.value)
    link.close()


def test_hung_up_terminal_is_a_link_error():
    """The board's side of the pseudo-terminal closes (the board died): EIO, never a bare OSError."""
    master, slave = os.openpty()
    tty.setraw(slave)
    path = os.ttyname(slave)
    link = open_link(path)
    os.close(slave)
    os.write(master, b"xyz")
    time.sleep(0.05)
    os.close(master)
    with pytest.raises(LinkError) as exc:
        for _ in range(20):
            link.read_waiting()
            link.wait(0.01)
    assert f"serial link {path} failed" in str(exc.value)
    with pytest.raises(LinkError):
        link.write(b"\x00hello\x00")
    link.close()


def test_a_link_error_mid_run_is_a_failure_not_an_exception(server):
    """Session.run keeps what it has and names the failure; a later run does nothing."""
    from hil_support import example

    from hil.schema import Schema
    from hil.session import Session

    m, t = example("spmsm", "s1")
    schema = Schema.of(m)
    link = open_link(_url(server))
    conn, _ = server.accept()
    closer = threading.Timer(0.2, conn.close)
    closer.start()
    try:
        session = Session(link, schema, timeout_s=0.1, retries=1000)
        res = session.run(schema.input.zeros(50))
    finally:
        closer.join()
        link.close()
    assert res.failure is not None and _url(server) in res.failure
    assert not res.answered.any() and res.unanswered == list(range(50)) and res.lost == []
    again = session.run(schema.input.zeros(3))
    assert again.failure == res.failure and not again.answered.any()


def test_index_ranges_round_trip():
    rng = np.random.default_rng(3)
    for n in (0, 1, 7, 200):
        mask = rng.random(n) < 0.4
        ranges = index_ranges(mask)
        assert all(a <= b for a, b in ranges) and sum(b - a + 1 for a, b in ranges) == mask.sum()
        assert np.array_equal(mask_of_ranges(ranges, n), mask)
    assert index_ranges(np.array([0, 1, 1, 0, 1], bool)) == [[1, 2], [4, 4]]
    for bad in ([[3, 2]], [[0, 9]], [[-1, 0]], [[0]], [["a", 1]]):
        with pytest.raises(ValueError):
            mask_of_ranges(bad, 5)

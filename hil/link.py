"""The serial link: pyserial ``serial_for_url`` (a device path, a pseudo-terminal or ``socket://``).

Reads never block for a count: :meth:`Link.read_waiting` returns everything
that has arrived (possibly nothing), :meth:`Link.wait` sleeps until input
arrives or a short timeout passes.  Counters of octets each way feed the
throughput figures.

Reading what is waiting: the port is opened with ``timeout=0`` and read in
chunks of :data:`READ_CHUNK_OCTETS` until a chunk comes back short; pyserial
then takes, per call, everything the device or socket holds (one ``read(2)``
or ``recv``).  ``in_waiting`` is not used: on ``socket://`` it is 0 or 1 (a
``select`` poll), so reading only that much took one octet per call; on a
terminal that has hung up its ioctl raises a bare ``OSError``.

Every failure of the link itself (EIO, hang-up, reset, a closed socket, a
broken pipe, a write that times out) raises :class:`LinkError`, naming the
port and the error; closing never raises.
"""
from __future__ import annotations

import errno
import os
import select
import socket
import time
from typing import Protocol

import serial

from codegen.errors import MpcgenError

__all__ = ["Link", "LinkError", "SerialLink", "open_link", "READ_CHUNK_OCTETS"]

#: octets asked for per read call (a chunk this full means more may be waiting)
READ_CHUNK_OCTETS = 65536
#: read calls per :meth:`SerialLink.read_waiting` at most (a bound, never reached on a sane link)
MAX_READS = 64


class LinkError(MpcgenError):
    """The link to the board failed (the port and the error in the message)."""

    def __init__(self, url: str, detail: str) -> None:
        super().__init__(f"serial link {url} failed: {detail}")
        self.url = url
        self.detail = detail


def describe(exc: BaseException) -> str:
    """One phrase for a link exception: its message, else its errno's name, else its type."""
    text = str(exc).strip()
    if text:
        return text
    if isinstance(exc, OSError) and exc.errno is not None:
        return errno.errorcode.get(exc.errno, str(exc.errno))
    return type(exc).__name__


def no_delay(fd: int) -> None:
    """TCP_NODELAY on the socket ``fd`` (pyserial's socket:// leaves Nagle on: each frame would wait for
    the ACK of the one before)."""
    sock = socket.socket(fileno=os.dup(fd))
    try:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    except OSError:
        pass  # not TCP: nothing to do
    finally:
        sock.close()


class Link(Protocol):
    """What the harness needs of a link (the fault injector and the exchange log wrap one)."""

    octets_out: int
    octets_in: int

    def write(self, data: bytes) -> None: ...

    def read_waiting(self) -> bytes: ...

    def wait(self, timeout_s: float) -> None: ...

    def close(self) -> None: ...


class SerialLink:
    """A pyserial port opened from a URL."""

    def __init__(self, url: str, baudrate: int = 921600) -> None:
        self.url = url
        self.port = serial.serial_for_url(url, baudrate=baudrate, timeout=0, write_timeout=5)
        self.octets_out = 0
        self.octets_in = 0
        self._error: LinkError | None = None  # raised by the next read (octets read before it are returned first)
        try:
            self._fd: int | None = self.port.fileno()
        except Exception:  # loop:// has no file descriptor
            self._fd = None
        if url.startswith("socket://") and self._fd is not None:
            no_delay(self._fd)

    def _failed(self, exc: BaseException) -> LinkError:
        return LinkError(self.url, describe(exc))

    def write(self, data: bytes) -> None:
        try:
            self.port.write(data)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise self._failed(exc) from None
        self.octets_out += len(data)

    def read_waiting(self) -> bytes:
        if self._error is not None:
            raise self._error
        out = bytearray()
        try:
            for _ in range(MAX_READS):
                chunk = self.port.read(READ_CHUNK_OCTETS)
                out += chunk
                if len(chunk) < READ_CHUNK_OCTETS:
                    break
        except (serial.SerialException, OSError, ValueError) as exc:
            self._error = self._failed(exc)
            if not out:
                raise self._error from None
        self.octets_in += len(out)
        return bytes(out)

    def wait(self, timeout_s: float) -> None:
        if self._fd is None:
            time.sleep(min(timeout_s, 0.001))
            return
        try:
            select.select([self._fd], [], [], timeout_s)
        except (OSError, ValueError) as exc:
            raise self._failed(exc) from None

    def close(self) -> None:
        try:
            self.port.close()
        except (serial.SerialException, OSError, ValueError):
            pass  # the link is gone already: nothing left to close


def open_link(url: str, baudrate: int = 921600) -> SerialLink:
    """Open ``url``; ``serial.SerialException`` if it cannot be opened."""
    return SerialLink(url, baudrate)

"""The serial link: pyserial ``serial_for_url`` (a device path, a pseudo-terminal or ``socket://``).

Reads never block for a count: :meth:`Link.read_waiting` returns what has
arrived (possibly nothing), :meth:`Link.wait` sleeps until input arrives or a
short timeout passes.  Counters of octets each way feed the throughput figures.
"""
from __future__ import annotations

import select
import time
from typing import Protocol

import serial

__all__ = ["Link", "SerialLink", "open_link"]


class Link(Protocol):
    """What the harness needs of a link (the fault injector wraps one)."""

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
        try:
            self._fd: int | None = self.port.fileno()
        except Exception:  # socket:// and loop:// have no file descriptor
            self._fd = None

    def write(self, data: bytes) -> None:
        self.port.write(data)
        self.octets_out += len(data)

    def read_waiting(self) -> bytes:
        n = self.port.in_waiting
        if not n:
            return b""
        data = self.port.read(n)
        self.octets_in += len(data)
        return bytes(data)

    def wait(self, timeout_s: float) -> None:
        if self._fd is not None:
            select.select([self._fd], [], [], timeout_s)
        else:
            time.sleep(min(timeout_s, 0.001))

    def close(self) -> None:
        self.port.close()


def open_link(url: str, baudrate: int = 921600) -> SerialLink:
    """Open ``url``; ``serial.SerialException`` if it cannot be opened."""
    return SerialLink(url, baudrate)

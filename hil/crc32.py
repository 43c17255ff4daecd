"""The frame CRC: CRC-32/ISO-HDLC (the zlib / IEEE 802.3 CRC-32).

Parameters (``crc.Crc32.CRC32`` of the PyPI ``crc`` package): width 32,
polynomial 0x04C11DB7, initial value and final XOR 0xFFFFFFFF, input and
output reflected; check value (CRC of b"123456789") 0xCBF43926.  The firmware
computes it with ``mpc_crc32`` (firmware/runtime/mpc_runtime.c).

The ``crc`` package is pure Python (about 2 us per octet), too slow for every
frame of a replay; the hot path uses :func:`zlib.crc32`, which computes the
same function: :func:`check` compares the two (the tests call it).
"""
from __future__ import annotations

import zlib

import crc

__all__ = ["CONFIG", "NAME", "crc32", "check"]

#: the CRC's parameters, as the crc package names them
CONFIG: crc.Configuration = crc.Crc32.CRC32.value
#: catalogue name
NAME = "CRC-32/ISO-HDLC"


def crc32(data: bytes) -> int:
    """CRC-32 of ``data`` (fast path)."""
    return zlib.crc32(data) & 0xFFFFFFFF


def check(samples: tuple[bytes, ...] = (b"123456789", b"", bytes(range(256)))) -> None:
    """Raise AssertionError unless the fast path equals the crc package's definition."""
    calc = crc.Calculator(CONFIG)
    for s in samples:
        want = calc.checksum(s)
        if crc32(s) != want:
            raise AssertionError(f"zlib.crc32 {crc32(s):#010x} != crc {want:#010x} for {s[:16]!r}")

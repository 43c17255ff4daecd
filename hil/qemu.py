"""The emulated board: the qemu-m7 firmware built with the protocol, run in QEMU, UART0 on a TCP socket.

:func:`build_qemu_board` writes the qemu-m7 project with the protocol
(``-DMPC_HIL``) into the build cache, one folder per config and schema, and
builds it with arm-none-eabi-gcc under a file lock.  :class:`QemuBoard`
starts QEMU (``codegen.stages.firmware.qemu_command``: mps2-an500, -icount,
semihosting) with ``-serial tcp:127.0.0.1:PORT,server=on,wait=on,nodelay=on``
on a free port, in its own process group; the harness connects with pyserial
``socket://127.0.0.1:PORT``.  QEMU waits for that connection before the
guest runs and is always killed at the end (``emulate.kill_group``).

Timings: the protocol image counts instructions (firmware/ports/qemu-m7/board.c:
SysTick under ``-icount shift=10``, converted on the board; its INFO says
``instructions``), so the RESULT timings are the instructions of the step, as
``mpcgen bench --emulated`` reports them: ``instructions_*`` in the summary,
never ``cycles_*``, and no clock frequency (the port's nominal 25 MHz does not
apply to instruction counts).

Speed: the emulated UART takes one octet at a time from the socket (about
15-20 kB/s host to guest), so the harness keeps the session's timeout long
(:data:`TIMEOUT_S`); the session's default window (2048 octets, about 0.12 s of
input at 17 kB/s) needs no resends there.
"""
from __future__ import annotations

import re
import socket
import subprocess
import time
from pathlib import Path
from typing import Any

from codegen.model import Model
from codegen.resources import firmware_dir
from codegen.stages.emulate import EmulationError, kill_group
from codegen.stages.firmware import (
    ICOUNT_SHIFT,
    QEMU,
    qemu_command,
    require_tools,
)

from .boards import QEMU_BOARD
from .virtual import build_protocol_image

__all__ = ["QEMU_BOARD", "TIMEOUT_S", "QemuBoard", "build_qemu_board"]

#: seconds before an unanswered frame is sent again on the emulated board (QEMU slows down a lot on a
#: loaded machine; a resend there only adds load, never a lost frame: its UART has flow control)
TIMEOUT_S = 10.0


def port_icount_shift() -> int:
    """The -icount shift the qemu-m7 port counts instructions for (its port_config.h PORT_ICOUNT_SHIFT)."""
    text = (firmware_dir() / "ports" / QEMU_BOARD / "port_config.h").read_text()
    found = re.search(r"^#define PORT_ICOUNT_SHIFT (\d+)", text, re.M)
    if found is None:
        raise EmulationError("firmware/ports/qemu-m7/port_config.h defines no PORT_ICOUNT_SHIFT")
    return int(found.group(1))


def build_qemu_board(model: Model, tables: Any) -> Path:
    """The qemu-m7 protocol image (ELF) of ``model``, built once per config and schema."""
    return build_protocol_image(model, tables, QEMU_BOARD, suffix="-qemu-m7")


def free_port() -> int:
    """A TCP port on 127.0.0.1 free at the time of the call."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class QemuBoard:
    """QEMU running a protocol image, UART0 served on ``127.0.0.1:port``; ``url`` is pyserial's URL."""

    def __init__(self, image: Path, log: Path | None = None, *, start_timeout_s: float = 10.0) -> None:
        if ICOUNT_SHIFT != port_icount_shift():
            raise EmulationError(f"the qemu-m7 protocol image counts instructions for -icount shift="
                                 f"{port_icount_shift()}, QEMU runs with shift={ICOUNT_SHIFT}")
        self.image = Path(image)
        self.log = log or self.image.with_suffix(".qemu.log")
        self.start_timeout_s = start_timeout_s
        self.proc: subprocess.Popen[bytes] | None = None
        self.port = 0
        self.url = ""

    def start(self) -> QemuBoard:
        """Start QEMU and wait until its socket listens (QEMU then waits for the harness)."""
        require_tools((QEMU,))
        for _ in range(3):  # another program may take the free port first
            self.port = free_port()
            serial = f"tcp:127.0.0.1:{self.port},server=on,wait=on,nodelay=on"
            with open(self.log, "wb") as log:
                self.proc = subprocess.Popen(qemu_command(self.image, serial), stdin=subprocess.DEVNULL,
                                             stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
            if self._listening():
                self.url = f"socket://127.0.0.1:{self.port}"
                return self
            self.stop()
        text = self.log.read_text(errors="replace")[-500:] if self.log.exists() else ""
        raise EmulationError(f"QEMU did not open its serial socket: {text}")

    def _listening(self) -> bool:
        deadline = time.monotonic() + self.start_timeout_s
        assert self.proc is not None
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                return False
            if self._port_bound():
                return True
            time.sleep(0.02)
        return False

    def _port_bound(self) -> bool:
        """Whether something listens on the port, seen in /proc/net/tcp (Linux) without connecting:
        QEMU takes only one connection, the harness's."""
        tcp = Path("/proc/net/tcp")
        if not tcp.exists():
            time.sleep(1.0)
            return True
        for line in tcp.read_text().splitlines()[1:]:
            f = line.split()
            if len(f) > 3 and f[1].endswith(f":{self.port:04X}") and f[3] == "0A":  # 0A: LISTEN
                return True
        return False

    def stop(self) -> None:
        """Kill QEMU's process group and reap it."""
        if self.proc is not None:
            kill_group(self.proc)
            self.proc = None

    def __enter__(self) -> QemuBoard:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

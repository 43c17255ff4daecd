"""The virtual board: the host port built as a serial protocol program, run on a pseudo-terminal.

:func:`build_virtual_board` writes the host project with the protocol
(``codegen.stages.firmware.write_firmware_project(..., protocol=...)``) into
the build cache, one folder per config and schema, and builds it
incrementally under a file lock (parallel test workers share the cache).
:class:`VirtualBoard` starts the program with a pseudo-terminal's master as
its stdin/stdout; the harness opens the terminal's slave path like any
serial device.
"""
from __future__ import annotations

import fcntl
import os
import subprocess
import tty
from pathlib import Path
from typing import Any

from codegen.hostbuild import cache_root
from codegen.model import Model
from codegen.stages.firmware import build_firmware, write_firmware_project

from .codecgen import protocol_build
from .schema import Schema

__all__ = ["build_protocol_image", "build_virtual_board", "VirtualBoard"]


def build_protocol_image(model: Model, tables: Any, board: str, *, suffix: str = "",
                         make_vars: dict[str, str] | None = None) -> Path:
    """The protocol image of ``model`` for firmware board ``board``, built once per config, schema
    and board under the build cache (a file lock serialises parallel builders)."""
    schema = Schema.of(model)
    root = cache_root() / "hil"
    root.mkdir(parents=True, exist_ok=True)
    name = f"{model.prefix}-{schema.config_hash}-{schema.schema_hash}{suffix}"
    with open(root / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        project = root / name
        write_firmware_project(model, tables, board, project, 1, n_bench=0, protocol=protocol_build(model, schema))
        res = build_firmware(project, board, make_vars=make_vars)
    return res.image


def build_virtual_board(model: Model, tables: Any, *, sanitize: bool = False) -> Path:
    """The protocol program of ``model`` for the host (built once per config and schema)."""
    return build_protocol_image(model, tables, "host", suffix="-san" if sanitize else "",
                                make_vars={"SANITIZE": "1"} if sanitize else None)


class VirtualBoard:
    """A running protocol program on a pseudo-terminal; ``url`` is the terminal to open."""

    def __init__(self, image: Path, log: Path | None = None) -> None:
        self.image = Path(image)
        self.log = log or self.image.with_suffix(".stderr")
        self.proc: subprocess.Popen[bytes] | None = None
        self.url = ""
        self._slave = -1

    def start(self) -> VirtualBoard:
        """Start the program; the terminal is in raw mode before it writes its first octet."""
        master, slave = os.openpty()
        tty.setraw(slave)
        with open(self.log, "wb") as err:
            self.proc = subprocess.Popen([str(self.image)], stdin=master, stdout=master, stderr=err,
                                         close_fds=True)
        os.close(master)
        self._slave = slave  # kept open until the harness has opened the path (no hang-up before)
        self.url = os.ttyname(slave)
        return self

    def release_slave(self) -> None:
        """Close this process's copy of the terminal (call once the harness has opened ``url``)."""
        if self._slave >= 0:
            os.close(self._slave)
            self._slave = -1

    def stop(self) -> None:
        """End the program (it also ends by itself when the terminal closes)."""
        self.release_slave()
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None

    def __enter__(self) -> VirtualBoard:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

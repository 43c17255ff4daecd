"""The virtual board: the host port built as a serial protocol program, run on a pseudo-terminal.

:func:`build_virtual_board` writes the host project with the protocol
(``codegen.stages.firmware.write_firmware_project(..., protocol=...)``) into
the build cache, one folder per config and schema, and builds it
incrementally under a file lock (parallel test workers share the cache).
:class:`VirtualBoard` starts the program with a pseudo-terminal's master as
its stdin/stdout; the harness opens the terminal's slave path like any
serial device.  :class:`SocketBoard` serves the same program on a loopback
TCP port instead: each connection gets a program of its own with the
connected socket as its stdin/stdout (``socket://127.0.0.1:PORT``, the
transport of QEMU and of boards behind a network bridge, without QEMU).
"""
from __future__ import annotations

import fcntl
import os
import socket
import subprocess
import threading
import tty
from pathlib import Path
from typing import Any

from codegen.hostbuild import cache_root
from codegen.model import Model
from codegen.stages.firmware import build_firmware, write_firmware_project

from .codecgen import protocol_build
from .schema import Schema

__all__ = ["build_protocol_image", "build_virtual_board", "VirtualBoard", "SocketBoard"]


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


class SocketBoard:
    """The protocol program served on ``127.0.0.1:port``: one program per TCP connection, the
    connected socket as its stdin/stdout; ``url`` is pyserial's URL.  :meth:`drop_links` closes
    every connection from the board's side (a link closed mid-run)."""

    def __init__(self, image: Path, log: Path | None = None, *, accept_poll_s: float = 0.05) -> None:
        self.image = Path(image)
        self.log = log or self.image.with_suffix(".socket.stderr")
        self.accept_poll_s = accept_poll_s
        self.url = ""
        self.procs: list[subprocess.Popen[bytes]] = []
        self._conns: list[socket.socket] = []
        self._server: socket.socket | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    def start(self) -> SocketBoard:
        """Listen on a free loopback port and accept connections in a thread until :meth:`stop`."""
        server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        server.bind(("127.0.0.1", 0))
        server.listen(4)
        server.settimeout(self.accept_poll_s)
        self._server = server
        self.url = f"socket://127.0.0.1:{server.getsockname()[1]}"
        self._thread = threading.Thread(target=self._serve, name="socket-board", daemon=True)
        self._thread.start()
        return self

    def _serve(self) -> None:
        assert self._server is not None
        while not self._stop.is_set():
            try:
                conn, _ = self._server.accept()
            except TimeoutError:
                continue
            except OSError:  # the server socket was closed: stop
                return
            conn.setblocking(True)
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            with open(self.log, "ab") as err:
                proc = subprocess.Popen([str(self.image)], stdin=conn.fileno(), stdout=conn.fileno(), stderr=err,
                                        close_fds=True)
            with self._lock:
                self.procs.append(proc)
                self._conns.append(conn)

    def drop_links(self) -> None:
        """Shut every connection down from the board's side (the harness reads the end of the stream)."""
        with self._lock:
            for conn in self._conns:
                try:
                    conn.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass

    def stop(self) -> None:
        """Stop accepting, close every connection, end every program."""
        self._stop.set()
        if self._server is not None:
            self._server.close()
        if self._thread is not None:
            self._thread.join(timeout=5)
        self.drop_links()
        with self._lock:
            for conn in self._conns:
                conn.close()
            for proc in self.procs:
                if proc.poll() is None:
                    proc.terminate()
                try:
                    proc.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
            self._conns.clear()
            self.procs.clear()

    def __enter__(self) -> SocketBoard:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

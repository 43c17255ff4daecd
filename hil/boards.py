"""Opening a board: a serial URL (device, pseudo-terminal, ``socket://``), the virtual board or the
emulated board (qemu-m7 in QEMU, hil/qemu.py)."""
from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from codegen.model import Model
from codegen.stages.firmware import EMULATED_BOARD

from .link import SerialLink, open_link
from .virtual import VirtualBoard, build_virtual_board

__all__ = ["BOARDS", "QEMU_BOARD", "VIRTUAL", "open_board"]

#: name of the virtual board (the host port built with the protocol, on a pseudo-terminal)
VIRTUAL = "virtual"
#: name of the emulated board (the qemu-m7 port built with the protocol, in QEMU, UART on a TCP socket)
QEMU_BOARD = EMULATED_BOARD
#: boards the harness starts itself
BOARDS = (VIRTUAL, QEMU_BOARD)


@contextmanager
def open_board(model: Model, tables: Any, port: str | None = None, *, image_model: Model | None = None,
               baudrate: int = 921600, board: str | None = None) -> Iterator[SerialLink]:
    """A link to the board at ``port``, or (None) to a board started for the duration of the block,
    built from ``image_model`` (default ``model``): ``board`` "virtual" (the default) or "qemu-m7"."""
    if port is not None:
        link = open_link(port, baudrate)
        try:
            yield link
        finally:
            link.close()
        return
    from codegen.topology import topology_of

    src = image_model or model
    src_tables = tables if image_model is None else topology_of(src).derive(src)
    if board == QEMU_BOARD:
        from .qemu import QemuBoard, build_qemu_board

        with QemuBoard(build_qemu_board(src, src_tables)) as qemu:
            link = open_link(qemu.url, baudrate)
            try:
                yield link
            finally:
                link.close()
        return
    if board not in (None, VIRTUAL):
        raise ValueError(f"unknown board {board!r}: the harness starts {', '.join(BOARDS)}")
    image = build_virtual_board(src, src_tables)
    with VirtualBoard(image) as vb:
        link = open_link(vb.url, baudrate)
        vb.release_slave()
        try:
            yield link
        finally:
            link.close()

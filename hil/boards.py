"""Opening a board: a serial URL (device, pseudo-terminal, ``socket://``) or the virtual board."""
from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from codegen.model import Model

from .link import SerialLink, open_link
from .virtual import VirtualBoard, build_virtual_board

__all__ = ["VIRTUAL", "open_board"]

#: name of the virtual board (the host port built with the protocol, on a pseudo-terminal)
VIRTUAL = "virtual"


@contextmanager
def open_board(model: Model, tables: Any, port: str | None = None, *, image_model: Model | None = None,
               baudrate: int = 921600) -> Iterator[SerialLink]:
    """A link to the board at ``port``, or (None) to a virtual board built from ``image_model``
    (default ``model``) started for the duration of the block."""
    if port is not None:
        link = open_link(port, baudrate)
        try:
            yield link
        finally:
            link.close()
        return
    from codegen.topology import topology_of

    src = image_model or model
    image = build_virtual_board(src, tables if image_model is None else topology_of(src).derive(src))
    with VirtualBoard(image) as board:
        link = open_link(board.url, baudrate)
        board.release_slave()
        try:
            yield link
        finally:
            link.close()

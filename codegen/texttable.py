"""Published tables written as text, parsed once at import.

The topologies' ``published`` modules hold the papers' tables as frozen data.
Writing each row as a constructor call repeats the same code shape dozens of
times; instead a table is a block of text, one row a line, and these parsers
turn it into tuples.  Conventions of a block:

* blank lines and lines starting with ``#`` are skipped (a ``#`` after the
  values starts a comment too, so a row can carry a note);
* numeric columns are separated by white space; ``inf`` is ``math.inf``;
* text columns are separated by ``|`` (:func:`split_rows`).
"""
from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any, TypeVar

__all__ = ["lines", "numbers", "number_rows", "int_cells", "split_rows", "records"]

T = TypeVar("T")


def lines(text: str) -> list[str]:
    """The data lines of ``text``: comments and blank lines removed, white space stripped."""
    out = []
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if line:
            out.append(line)
    return out


def _number(word: str) -> int | float:
    """``word`` as an int when it is written as one, else as a float (``inf`` allowed)."""
    try:
        return int(word)
    except ValueError:
        return float(word)


def numbers(line: str) -> tuple[int | float, ...]:
    """The white-space separated numbers of one line."""
    return tuple(_number(w) for w in line.split())


def number_rows(text: str) -> tuple[tuple[int | float, ...], ...]:
    """A numeric table: one tuple of numbers per data line."""
    return tuple(numbers(line) for line in lines(text))


def int_cells(text: str) -> tuple[tuple[tuple[int, ...], ...], ...]:
    """A table of integer-tuple cells: cells separated by ``|``, ints by white space.

    ``"0 2 3 | 0 3 4"`` is ``((0, 2, 3), (0, 3, 4))``."""
    return tuple(tuple(tuple(int(w) for w in cell.split()) for cell in line.split("|")) for line in lines(text))


def split_rows(text: str, columns: int) -> tuple[tuple[str, ...], ...]:
    """A text table: each data line split at ``|`` into exactly ``columns`` stripped cells."""
    rows = []
    for line in lines(text):
        cells = tuple(c.strip() for c in line.split("|"))
        if len(cells) != columns:
            raise ValueError(f"expected {columns} '|'-separated cells, got {len(cells)}: {line!r}")
        rows.append(cells)
    return tuple(rows)


def records(make: Callable[..., T], rows: Iterable[Sequence[Any]],
            convert: Sequence[Callable[[Any], Any]] | None = None) -> tuple[T, ...]:
    """``make(*row)`` for every row, each cell first passed through its ``convert`` function."""
    if convert is None:
        return tuple(make(*row) for row in rows)
    return tuple(make(*(f(c) for f, c in zip(convert, row, strict=True))) for row in rows)

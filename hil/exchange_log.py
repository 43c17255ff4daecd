"""A log of every exchange with a board (``mpcgen hil --log``): the writer.

The log is JSON lines (format :data:`FORMAT`):

* line 1, the header: ``{"format": FORMAT, config, sets, config and schema hashes, strategy, board, mode}``;
* one line per chunk of octets that crossed the link: ``{"t": s since the start, "dir": "out"|"in",
  "hex": octets}``;
* the last line, the end record, written when the run finishes: ``{"end": true, "completed": bool,
  "error": why not (or null), "run": the run's own counts, "counts": octets, lines, frames and discarded
  frames per direction, and frames per message type}``.

Every line ends with ``"sha256": D``: the SHA-256 of the log up to and including that line (the line
without this field), so each line carries the digest of everything before it, and the end record's
``sha256`` is that of the whole log.  A hand edit anywhere breaks the chain at the edited line (the
chain proves against edits, not against a forger who recomputes it: the whole log's digest, which
:meth:`LoggingLink.finish` returns, can be kept apart).

The harness ends the log with :meth:`LoggingLink.finish` (the mode's summary) or
:func:`finish_log`; used as a context manager, an exception or an exit without it writes the end record
of a run that did not complete.  :mod:`hil.log_check` reads and re-verifies a log.
"""
from __future__ import annotations

import hashlib
import json
import re
import time
from collections import Counter
from collections.abc import Mapping
from types import TracebackType
from typing import Any, TextIO

import numpy as np

from .framing import Discarded, Frame, FrameDecoder
from .link import Link
from .schema import Msg

__all__ = ["FORMAT", "FORMAT_NAME", "DIGEST_KEY", "DigestChain", "Tally", "LoggingLink", "finish_log", "run_completed",
           "type_name"]

#: first line of every log: {"format": FORMAT, ...}; bump on any change of the format
FORMAT = "mpcgen-hil-log/2"
#: every version of the format starts so
FORMAT_NAME = "mpcgen-hil-log/"
#: key of every line's digest (the last key of the line)
DIGEST_KEY = "sha256"
_SEALED = re.compile(rb', "sha256": "([0-9a-f]{64})"\}$')


class DigestChain:
    """The running SHA-256 of a log: each line carries the digest of the log up to and including itself."""

    def __init__(self) -> None:
        self._h = hashlib.sha256()

    def _peek(self, text: bytes) -> str:
        h = self._h.copy()
        h.update(text)
        return h.hexdigest()

    def seal(self, record: Mapping[str, Any]) -> str:
        """The line (newline included) of ``record`` with its digest; the line joins the chain."""
        text = json.dumps(record)
        line = f'{text[:-1]}, "{DIGEST_KEY}": "{self._peek(text.encode())}"}}\n'
        self._h.update(line.encode())
        return line

    def check(self, line: bytes) -> bool:
        """Whether ``line`` (without its newline) carries the right digest; the line joins the chain either way."""
        m = _SEALED.search(line)
        ok = m is not None and self._peek(line[:m.start()] + b"}") == m.group(1).decode()
        self._h.update(line + b"\n")
        return ok

    @property
    def digest(self) -> str:
        """SHA-256 (hex) of every line so far."""
        return self._h.hexdigest()


class Tally:
    """Lines, octets, frames and discarded frames per direction, and frames per message type."""

    def __init__(self) -> None:
        self.decoders = {"out": FrameDecoder(), "in": FrameDecoder()}
        self.by_dir: dict[str, Counter[str]] = {"out": Counter(), "in": Counter()}

    def feed(self, direction: str, data: bytes) -> list[Frame | Discarded]:
        """Count one chunk; the frames (and discarded chunks) it completes."""
        items = self.decoders[direction].feed(data)
        c = self.by_dir[direction]
        c["lines"] += 1
        c["octets"] += len(data)
        for item in items:
            if isinstance(item, Frame):
                c["frames"] += 1
                c[type_name(item.type)] += 1
            else:
                c["discarded"] += 1
        return items

    def counts(self) -> dict[str, dict[str, int]]:
        return {d: dict(sorted(c.items())) for d, c in self.by_dir.items()}


def type_name(msg_type: int) -> str:
    """The message type's name (``TYPE<n>`` for a number no message has)."""
    try:
        return Msg(msg_type).name
    except ValueError:
        return f"TYPE{msg_type}"


# ---------------------------------------------------------------- writing
#: the run's own counts copied into the end record (those of its summary that it has)
RUN_KEYS = ("mode", "states", "answered", "unanswered", "lost", "mismatches", "periods", "periods_done", "lost_at",
            "complete", "ok", "failure", "parts", "resumed_from")


def run_completed(summary: Mapping[str, Any]) -> bool:
    """Whether a mode's summary says the run did all it was to do (not whether its results are right)."""
    if "complete" in summary:  # onboard
        return bool(summary["complete"])
    if "periods_done" in summary:  # closed-loop
        return bool(summary["periods_done"] == summary["periods"] and summary.get("lost_at") is None)
    if "states" in summary:  # replay
        return bool(summary.get("answered") == summary["states"] and not summary.get("lost"))
    return False


def _plain(v: Any) -> Any:
    """A JSON value of a summary's scalar (numpy scalars as Python ones)."""
    return v.item() if isinstance(v, np.generic) else v


class LoggingLink:
    """A :class:`~hil.link.Link` that logs every octet written and read to ``out``.

    Call :meth:`finish` with the run's summary when the run ends (or use it as a context manager: an
    exception, or an exit without :meth:`finish`, writes the end record of a run that did not complete).
    """

    def __init__(self, link: Link, out: TextIO, header: dict[str, Any]) -> None:
        self.link, self.out = link, out
        self.t0 = time.perf_counter()
        self.chain = DigestChain()
        self.tally = Tally()
        self.finished = False
        self._write({"format": FORMAT, **header})

    def _write(self, record: Mapping[str, Any]) -> None:
        self.out.write(self.chain.seal(record))

    def _log(self, direction: str, data: bytes) -> None:
        if data and not self.finished:
            self.tally.feed(direction, data)
            self._write({"t": round(time.perf_counter() - self.t0, 6), "dir": direction, "hex": data.hex()})

    def finish(self, summary: Mapping[str, Any] | None = None, *, error: str | None = None) -> str:
        """Write the end record (once): the run's counts from ``summary``, completed unless ``error`` or
        the summary says otherwise; the SHA-256 of the whole log."""
        if not self.finished:
            run = {k: _plain(summary[k]) for k in RUN_KEYS if summary is not None and k in summary}
            done = error is None and summary is not None and run_completed(summary)
            if error is None and not done:
                error = ("no summary of the run" if summary is None else
                         str(summary.get("failure") or "the run did not do all it was to do"))
            self._write({"end": True, "completed": done, "error": error, "run": run, "counts": self.tally.counts()})
            self.out.flush()
            self.finished = True
        return self.chain.digest

    def __enter__(self) -> LoggingLink:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.finish(error=f"{exc_type.__name__}: {exc}" if exc_type is not None
                    else "the run ended without reporting its end")

    @property
    def octets_out(self) -> int:
        return int(getattr(self.link, "octets_out", 0))

    @property
    def octets_in(self) -> int:
        return int(getattr(self.link, "octets_in", 0))

    def write(self, data: bytes) -> None:
        self._log("out", data)
        self.link.write(data)

    def read_waiting(self) -> bytes:
        data = self.link.read_waiting()
        self._log("in", data)
        return data

    def wait(self, timeout_s: float) -> None:
        self.link.wait(timeout_s)

    def close(self) -> None:
        self.out.flush()
        self.link.close()


def finish_log(link: object, summary: Mapping[str, Any]) -> str | None:
    """End ``link``'s log with ``summary`` if it is a :class:`LoggingLink`; its digest (None: no log)."""
    return link.finish(summary) if isinstance(link, LoggingLink) else None

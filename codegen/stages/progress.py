"""Progress lines of long phases (builds, emulator runs, traces): a line when a phase starts, a heartbeat
every few seconds while it runs, a line with its time when it ends.

The lines go to the command's progress log (stderr, silenced by ``-q``: ``codegen.cli.progress_log``);
nothing here touches a result.  A phase may report how far it got (:meth:`Phase.note`), which the next
heartbeat prints.
"""
from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

__all__ = ["HEARTBEAT_S", "Phase", "phase"]

#: seconds between two heartbeat lines of a running phase
HEARTBEAT_S = 5.0

Log = Callable[[str], None]


class Phase:
    """A running phase: its name, its start, and the latest note on how far it got."""

    def __init__(self, log: Log, what: str) -> None:
        self.log, self.what = log, what
        self.t0 = time.perf_counter()
        self._note = ""
        self._lock = threading.Lock()

    def note(self, text: str) -> None:
        """How far the phase got (``"120/256 states"``), printed by the next heartbeat."""
        with self._lock:
            self._note = text

    def elapsed_s(self) -> float:
        return time.perf_counter() - self.t0

    def beat(self) -> None:
        """One heartbeat line: the phase, its time so far and its latest note."""
        with self._lock:
            note = f", {self._note}" if self._note else ""
        self.log(f"    ... {self.what}: {self.elapsed_s():.0f} s{note}")


@contextmanager
def phase(log: Log | None, what: str, every_s: float | None = None,
          probe: Callable[[], str] | None = None) -> Iterator[Phase]:
    """Run the ``with`` body as the phase ``what``: a start line, a heartbeat every ``every_s`` seconds
    (default :data:`HEARTBEAT_S`; from a daemon thread) while it runs, and its time when it ends (nothing when ``log`` is None).
    ``probe``: asked by each heartbeat how far the phase got (e.g. from the files a build wrote), for a
    phase whose body cannot report it (:meth:`Phase.note`)."""
    p = Phase(log or (lambda _line: None), what)
    if log is None:
        yield p
        return
    log(f"  {what} ...")
    stop = threading.Event()

    def heartbeat() -> None:
        while not stop.wait(HEARTBEAT_S if every_s is None else every_s):
            if probe is not None:
                try:
                    p.note(probe())
                except OSError:  # a file the probe reads is being replaced: no note this time
                    pass
            p.beat()

    thread = threading.Thread(target=heartbeat, name=f"progress: {what}", daemon=True)
    thread.start()
    try:
        yield p
    finally:
        stop.set()
        thread.join()
    log(f"  {what}: done in {p.elapsed_s():.1f} s")

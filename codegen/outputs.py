"""Writing output files so that a failure leaves nothing half-written and says so in one line.

Every file mpcgen writes for the user (generated C, reports, JSON results,
trained tables) goes through :func:`write_atomic`: the bytes go to a
temporary beside the target and are renamed over it, so a full disk, a name
too long for the file system or a Ctrl-C leaves either the old file or the
new one, never a truncated one.  :func:`output_error` turns the OS error into
the one-line error the command line prints: a name the file system refuses
is bad input (exit 2), a disk that fills up a failed job (exit 1).
"""
from __future__ import annotations

import errno
import os
from pathlib import Path

from codegen.errors import MpcgenError, UsageError

__all__ = ["write_atomic", "output_error", "OutputError"]


class OutputError(MpcgenError):
    """An output file could not be written (exit 1); nothing half-written was left."""


#: errors that say the path itself is unusable (bad input), not that the write failed
_BAD_PATH = {errno.ENAMETOOLONG: "a name in it is too long for the file system",
             errno.ENOTDIR: "a part of it is a file, not a folder",
             errno.EISDIR: "it is a folder",
             errno.EACCES: "permission denied",
             errno.EROFS: "the file system is read-only"}


def _short(path: Path) -> str:
    """The path for a message, shortened in the middle when it is very long."""
    text = str(path)
    return text if len(text) <= 120 else f"{text[:60]}...{text[-50:]}"


def output_error(exc: OSError, path: Path) -> MpcgenError:
    """The one-line error for ``exc`` raised while writing ``path``."""
    reason = _BAD_PATH.get(exc.errno or 0)
    if reason is not None:
        return UsageError(f"cannot write {_short(path)}: {reason}")
    if exc.errno == errno.ENOSPC:
        return OutputError(f"cannot write {_short(path)}: no space left on the device (nothing half-written "
                           "was left; files written before it are complete)")
    return OutputError(f"cannot write {_short(path)}: {exc.strerror or exc}")


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary in the same folder (folders created); one-line
    :class:`OutputError` / :class:`~codegen.errors.UsageError` on failure, the temporary removed."""
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            tmp.write_bytes(data)
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)
    except OSError as exc:
        raise output_error(exc, path) from None

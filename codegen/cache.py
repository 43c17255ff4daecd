"""The build cache as a small database: one checked root, atomic entries, each validated before use.

Everything mpcgen caches (compiled host libraries, training counts, rendered
simulator headers, firmware builds) lives under :func:`cache_root`
(``MPCGEN_CACHE``, else ``~/.cache/mpcgen``).  The rules:

- the root is checked once per process: a path that is a file, or a folder
  that cannot be created or written, is refused in one line (exit 2) before
  anything runs;
- an entry is written to a private temporary and renamed into place
  (:func:`write_json`, :func:`seal`), so a reader never sees half an entry and
  two processes sharing one cache never corrupt each other;
- an entry records the SHA-256 of its content when it is written and is
  checked against it when it is read (:func:`read_json`, :func:`sealed_ok`);
  a damaged entry is reported in one warning line and rebuilt;
- temporaries left by an interrupted run (``*.tmp<pid>``, whose process is
  gone) are removed when the root is first used.
"""
from __future__ import annotations

import functools
import hashlib
import json
import os
import re
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

from codegen.errors import UsageError

__all__ = ["LAYOUT", "CacheError", "cache_root", "write_json", "read_json", "seal", "sealed_ok", "discard", "warn",
           "SEAL_NAME"]

#: the file in a sealed entry folder recording the SHA-256 of its payload
SEAL_NAME = "entry.json"
#: part of every entry's key: entries of another layout (an older mpcgen's, unsealed) are never read
LAYOUT = "sealed-1"
#: a temporary of process <pid>: ``<name>.tmp<pid>`` (a folder or a file)
_TMP_RE = re.compile(r"\.tmp(\d+)$")


class CacheError(UsageError):
    """The cache location cannot be used (one line, exit 2)."""


def warn(text: str) -> None:
    """One warning line on stderr."""
    print(f"mpcgen: warning: {text}", file=sys.stderr)


def cache_root() -> Path:
    """The checked cache folder (MPCGEN_CACHE, else ~/.cache/mpcgen); :class:`CacheError` if it cannot be
    used.  Stale temporaries of finished processes are removed on first use."""
    root = os.environ.get("MPCGEN_CACHE") or str(Path.home() / ".cache" / "mpcgen")
    return _checked(root)


@functools.cache
def _checked(root: str) -> Path:
    path = Path(root)
    source = "MPCGEN_CACHE" if os.environ.get("MPCGEN_CACHE") else "the build cache"
    if path.exists() and not path.is_dir():
        raise CacheError(f"{source} = {root!r}: is a file, not a folder; set MPCGEN_CACHE to a writable folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".probe", dir=path)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise CacheError(f"{source} = {root!r}: cannot write there ({exc.strerror or exc}); "
                         "set MPCGEN_CACHE to a writable folder") from None
    _remove_stale(path)
    return path


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _remove_stale(root: Path) -> None:
    """Remove the temporaries of processes that no longer run (an interrupted build or write)."""
    try:
        entries = list(root.rglob("*.tmp*"))
    except OSError:  # another process removed a folder during the scan: its own clean-up, nothing to do
        return
    for entry in entries:
        m = _TMP_RE.search(entry.name)
        if m is None or _alive(int(m.group(1))):
            continue
        try:
            if entry.is_dir():
                shutil.rmtree(entry, ignore_errors=True)
            else:
                entry.unlink(missing_ok=True)
        except OSError:  # gone or changed under us (concurrent runs share the cache)
            continue


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def write_json(path: Path, value: Any) -> None:
    """Write ``value`` as a JSON entry with its content's SHA-256, atomically (temporary + rename)."""
    payload = json.dumps(value, sort_keys=True)
    blob = json.dumps({"sha256": _digest(payload.encode()), "payload": payload}).encode()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.tmp{os.getpid()}")
    tmp.write_bytes(blob)
    os.replace(tmp, path)


def read_json(path: Path) -> Any | None:
    """The value of a JSON entry; None when there is none, or when it is damaged (not JSON, no digest,
    the digest does not match: one warning line, the entry removed so that it is rebuilt)."""
    try:
        blob = path.read_bytes()
    except FileNotFoundError:
        return None
    try:
        outer = json.loads(blob)
        payload = outer["payload"]
        if _digest(payload.encode()) != outer["sha256"]:
            raise ValueError("content does not match its recorded SHA-256")
        return json.loads(payload)
    except (ValueError, KeyError, TypeError, UnicodeDecodeError) as exc:
        warn(f"cache entry {path} is damaged ({exc}); rebuilding it")
        path.unlink(missing_ok=True)
        return None


def seal(folder: Path, payload: Path) -> None:
    """Record ``payload``'s (a file inside ``folder``) SHA-256 in ``folder``'s seal, before the folder is
    renamed into place."""
    (folder / SEAL_NAME).write_text(json.dumps({"file": payload.name, "sha256": _digest(payload.read_bytes())}))


def sealed_ok(folder: Path, payload: Path) -> str | None:
    """None when ``payload`` matches ``folder``'s seal, else why not (no seal, another file, a changed
    or truncated payload)."""
    try:
        seal_data = json.loads((folder / SEAL_NAME).read_text())
        name, want = seal_data["file"], seal_data["sha256"]
    except FileNotFoundError:
        return "no seal"
    except (ValueError, KeyError, TypeError) as exc:
        return f"unreadable seal ({exc})"
    if name != payload.name:
        return f"the seal names {name}, not {payload.name}"
    try:
        got = _digest(payload.read_bytes())
    except OSError as exc:
        return f"unreadable ({exc.strerror or exc})"
    return None if got == want else "its content does not match the SHA-256 recorded when it was built"


def discard(folder: Path) -> None:
    """Remove a damaged entry folder (renamed away first, so a concurrent reader never sees it half gone)."""
    gone = folder.with_name(f"{folder.name}.tmp{os.getpid()}")
    try:
        os.replace(folder, gone)
    except OSError:
        return  # another process moved it already
    shutil.rmtree(gone, ignore_errors=True)

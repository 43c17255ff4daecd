"""Compiled templates kept across processes: a jinja2 bytecode cache under the build cache's rules.

Compiling the templates is most of a command's fixed cost (about 0.3 s of a
0.9 s ``verify --states 1000``); the compiled code of a template depends only
on its source, jinja2 and the Python version, so it is kept in
``<cache root>/templates/<key>/`` where ``<key>`` names the layout, the
Python and the jinja2 version.  An entry is keyed by jinja2 from the
template's name, stores the SHA-1 of the source it was compiled from (jinja2
recompiles when the source changed) and, here, the SHA-256 of the stored
bytes: an entry that does not match it (a damaged disk, an edited file) is
reported in one warning line, removed and recompiled.  Entries are written to
a private temporary and renamed into place (:mod:`codegen.cache`), so two
processes never see half an entry.  A cache that cannot be used (no writable
folder, a full disk) only costs the compile: rendering never fails because
of it.
"""
from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

import jinja2

from codegen.cache import LAYOUT, CacheError, cache_root, warn

__all__ = ["SealedBytecodeCache"]

#: the digest line that starts every entry: 64 hex digits and a newline
_DIGEST_LEN = 65


class SealedBytecodeCache(jinja2.BytecodeCache):
    """jinja2's :class:`~jinja2.BytecodeCache` over sealed files of the build cache."""

    def __init__(self) -> None:
        self._folder: Path | None = None
        self._disabled = False

    def _root(self) -> Path | None:
        if self._folder is None and not self._disabled:
            try:
                tag = f"{LAYOUT}-py{sys.version_info[0]}{sys.version_info[1]}-jinja{jinja2.__version__}"
                self._folder = cache_root() / "templates" / tag
                self._folder.mkdir(parents=True, exist_ok=True)
            except (CacheError, OSError):
                self._disabled = True  # rendering works without it; the commands that need the cache say why
                self._folder = None
        return self._folder

    def _path(self, bucket: jinja2.bccache.Bucket) -> Path | None:
        root = self._root()
        return None if root is None else root / f"{bucket.key}.bc"

    def load_bytecode(self, bucket: jinja2.bccache.Bucket) -> None:
        """Fill ``bucket`` from its entry when the entry is whole (its SHA-256 matches); jinja2 itself
        discards code compiled from another source."""
        path = self._path(bucket)
        if path is None:
            return
        try:
            blob = path.read_bytes()
        except OSError:
            return
        digest, data = blob[:_DIGEST_LEN - 1], blob[_DIGEST_LEN:]
        if len(blob) < _DIGEST_LEN or digest.decode("ascii", "replace") != hashlib.sha256(data).hexdigest():
            warn(f"cache entry {path} is damaged (its content does not match its recorded SHA-256); "
                 "recompiling the template")
            path.unlink(missing_ok=True)
            return
        bucket.bytecode_from_string(data)

    def dump_bytecode(self, bucket: jinja2.bccache.Bucket) -> None:
        """Write ``bucket``'s code with its SHA-256, atomically; a write that fails is skipped."""
        path = self._path(bucket)
        if path is None:
            return
        data = bucket.bytecode_to_string()
        tmp = path.with_name(f"{path.name}.tmp{os.getpid()}")
        try:
            tmp.write_bytes(hashlib.sha256(data).hexdigest().encode("ascii") + b"\n" + data)
            os.replace(tmp, path)
        except OSError:
            tmp.unlink(missing_ok=True)

    def clear(self) -> None:
        """Remove every entry of this Python and jinja2 version."""
        root = self._root()
        if root is not None:
            for entry in root.glob("*.bc"):
                entry.unlink(missing_ok=True)

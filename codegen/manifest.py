"""The generated C of a model for one target, its hash, and the manifest ``generate`` writes beside it.

Every piece of evidence (``<prefix>_report.md``, ``<prefix>_quantisation.md``,
``mpcgen report``, ``verify --json``, the HIL harness) names the C it is
about by one hash, defined here once:

    **C hash** = SHA-256 (hex) of the lines ``"<sha256 of the file>  <name>\\n"`` of the generated
    ``.c`` and ``.h`` files of one target, in name order (byte order of the UTF-8 names)

-- the output of ``sha256sum`` over those files, sorted by name, hashed again, so a folder
can be checked with coreutils::

    cd DIR && sha256sum $(ls *.c *.h | LC_ALL=C sort) | sha256sum

:func:`c_hash` gives it for a model and a target without writing anything; ``mpcgen generate``
writes ``<prefix>_manifest.json`` (:func:`manifest_text`) with the SHA-256 of every file it wrote
and the C hash.  Deterministic: the same config gives the same bytes.
"""
from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from typing import Any

from codegen import __version__
from codegen.model import Model
from codegen.render import render_speed_pi
from codegen.topology import topology_of

__all__ = ["C_SUFFIXES", "C_HASH_DEFINITION", "sha256_hex", "manifest", "c_hash_of", "sources", "c_hash",
           "manifest_name", "manifest_record", "manifest_text"]

#: the suffixes of the files the C hash covers
C_SUFFIXES = (".c", ".h")
#: the definition of the C hash, as the manifest states it
C_HASH_DEFINITION = ("sha256 of the lines '<sha256>  <name>\\n' of the generated .c and .h files in name order "
                     "(sha256sum of those files sorted by name, hashed again)")


def sha256_hex(data: str | bytes) -> str:
    """SHA-256 (hex) of ``data`` (text as its UTF-8 bytes: the bytes ``generate`` writes)."""
    return hashlib.sha256(data.encode() if isinstance(data, str) else data).hexdigest()


def manifest(files: Mapping[str, str | bytes]) -> dict[str, str]:
    """File name -> SHA-256 (hex) of every file of ``files`` (name -> text or bytes), in name order."""
    return {name: sha256_hex(files[name]) for name in sorted(files)}


def _is_c(name: str) -> bool:
    return name.endswith(C_SUFFIXES)


def c_hash_of(files: Mapping[str, str | bytes]) -> str:
    """The C hash (module doc) of the ``.c``/``.h`` files among ``files`` (name -> text or bytes);
    ValueError if there is none."""
    hashes = {name: h for name, h in manifest(files).items() if _is_c(name)}
    if not hashes:
        raise ValueError(f"no .c or .h file among {sorted(files)}: nothing to hash")
    lines = "".join(f"{hashes[name]}  {name}\n" for name in sorted(hashes, key=lambda n: n.encode()))
    return sha256_hex(lines)


def sources(model: Model, target: str | None = None, tables: Any = None) -> dict[str, str]:
    """File name -> text of the C ``generate`` writes for ``model`` and ``target`` (default
    ``model.target``): the step (the topology's ``render``) and the speed PI; ``tables``: ``model``'s
    derived tables when the caller has them (derived here otherwise)."""
    t = model.target if target is None else target
    topo = topology_of(model)
    tables = topo.derive(model) if tables is None else tables
    files = topo.render(model, tables, t)
    files.update(render_speed_pi(model, t, getattr(tables, "scaling", None)))
    return files


def c_hash(model: Model, target: str | None = None) -> str:
    """The C hash of what ``mpcgen generate`` writes for ``model`` (its strategy, number format and
    tables) and ``target`` (default ``model.target``): the hash ``<prefix>_manifest.json`` names."""
    return c_hash_of(sources(model, target))


def manifest_name(model: Model) -> str:
    """File name of the manifest: ``<prefix>_manifest.json``."""
    return f"{model.prefix}_manifest.json"


def manifest_record(model: Model, files: Mapping[str, str | bytes]) -> dict[str, Any]:
    """The manifest of the generated ``files`` of ``model`` for ``model.target``: every file's SHA-256,
    the C hash, the config hash, target, placement, strategy, number format and mpcgen version."""
    c = model.controller
    return {
        "config": model.name, "config_hash": model.config_hash(), "mpcgen": __version__,
        "target": model.target, "placement": model.placement, "topology": model.inverter.topology,
        "strategy": c.strategy, "number_format": c.number_format,
        "c_hash": c_hash_of(files), "c_hash_definition": C_HASH_DEFINITION,
        "files": manifest(files),
    }


def manifest_text(model: Model, files: Mapping[str, str | bytes]) -> str:
    """:func:`manifest_record` as JSON text: indented, keys sorted, one final newline."""
    return json.dumps(manifest_record(model, files), indent=2, sort_keys=True) + "\n"

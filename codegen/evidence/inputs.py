"""The evidence page's inputs: each file read once with its sha256, the hashes it names, and the check
that every input belongs to the config.

A JSON input names hashes under keys ending in ``_hash`` at any depth (``config_hash``, a C hash such
as ``c_hash``, a board's ``schema_hash`` ...); the ``config_hash`` keys say which config the run was
made from.  The quantisation markdown names its config hash in its header line (``(hash XXXX)``).
"""
from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from codegen.errors import UsageError

__all__ = ["Source", "Identity", "Inputs", "read_json", "read_file", "read_pngs", "quant_markdown",
           "named_hashes", "config_hashes", "foreign_hashes", "check_belongs", "CONFIG_HASH_KEY"]

#: the key under which every command's JSON names the config hash of its run
CONFIG_HASH_KEY = "config_hash"
#: a hash in markdown text: an optional word before ``hash`` ("C hash", "config hash") and hex digits
_MD_HASH = re.compile(r"(?:\b([A-Za-z][A-Za-z0-9_]*)[ _])?\bhash\b[\s:=`(]*([0-9a-f]{12,64})\b")


@dataclass(frozen=True)
class Source:
    """One input file: the option that named it, its path as given, its sha256 and its content."""

    option: str
    path: str
    sha256: str
    data: bytes
    #: parsed JSON (a dict), or None for markdown and images
    json: Mapping[str, Any] | None = None

    @property
    def name(self) -> str:
        """The file's name (no folders)."""
        return Path(self.path).name

    @property
    def text(self) -> str:
        """The content as UTF-8 text (bad bytes replaced)."""
        return self.data.decode("utf-8", errors="replace")


@dataclass(frozen=True)
class Identity:
    """What a config hash stands for: a label ("config", "config with trained tables", ...) and the
    number format of that model."""

    label: str
    number_format: str


@dataclass(frozen=True)
class Inputs:
    """Every input of the page (each optional)."""

    verify: tuple[Source, ...] = ()
    simulate: Source | None = None
    plots: tuple[Source, ...] = ()
    #: the folder --plots named (as given), for the section's provenance line
    plots_dir: str | None = None
    report: Source | None = None
    #: the PNGs the quantisation markdown shows, by the name it gives them
    report_images: Mapping[str, Source] = field(default_factory=dict)
    bench: Source | None = None
    hil: tuple[Source, ...] = ()
    manifest: tuple[Source, ...] = ()

    def all(self) -> list[Source]:
        """Every input that can name a hash, in page order."""
        one = [s for s in (self.report, self.bench, self.simulate) if s is not None]
        return [*self.manifest, *self.verify, *self.hil, *one]


def _read(option: str, path: str | Path) -> bytes:
    try:
        return Path(path).read_bytes()
    except FileNotFoundError:
        raise UsageError(f"{option} = {path}: no such file") from None
    except IsADirectoryError:
        raise UsageError(f"{option} = {path}: is a folder; give a file") from None
    except OSError as exc:
        raise UsageError(f"{option} = {path}: cannot read: {exc.strerror}") from None


def _source(option: str, path: str | Path, data: bytes, parsed: Mapping[str, Any] | None = None) -> Source:
    return Source(option, str(path), hashlib.sha256(data).hexdigest(), data, parsed)


def read_json(option: str, path: str | Path) -> Source:
    """A JSON input (an object at the top), or a one-line :class:`UsageError`."""
    data = _read(option, path)
    try:
        parsed = json.loads(data)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise UsageError(f"{option} = {path}: not JSON ({exc})") from None
    if not isinstance(parsed, dict):
        raise UsageError(f"{option} = {path}: not a JSON object (the JSON an mpcgen command writes)")
    return _source(option, path, data, parsed)


def read_file(option: str, path: str | Path) -> Source:
    """A markdown or image input (bytes as they are)."""
    return _source(option, path, _read(option, path))


def quant_markdown(option: str, path: str | Path) -> Path:
    """The quantisation markdown: ``path`` itself, or the one ``*_quantisation.md`` in the folder ``path``."""
    p = Path(path)
    if not p.is_dir():
        return p
    found = sorted(p.glob("*_quantisation.md"))
    if len(found) != 1:
        what = "no" if not found else f"{len(found)}"
        raise UsageError(f"{option} = {path}: {what} *_quantisation.md files in the folder; "
                         "name the report's markdown file")
    return found[0]


def read_pngs(option: str, folder: str | Path) -> tuple[Source, ...]:
    """Every ``*.png`` in ``folder`` (not recursive), by name; at least one."""
    d = Path(folder)
    if not d.is_dir():
        raise UsageError(f"{option} = {folder}: no such folder")
    files = sorted(d.glob("*.png"))
    if not files:
        raise UsageError(f"{option} = {folder}: no PNG files in the folder")
    return tuple(_source(option, f, _read(option, f)) for f in files)


def named_hashes(source: Source) -> list[tuple[str, str]]:
    """(key, value) of every hash ``source`` names: JSON keys ending in ``_hash`` (dotted path), or the
    markdown's ``... hash XXXX`` (key ``config_hash`` for a bare or "config" hash, else ``WORD_hash``)."""
    if source.json is not None:
        return sorted(_json_hashes(source.json, ""))
    found = []
    for word, value in _MD_HASH.findall(source.text):
        key = CONFIG_HASH_KEY if word.lower() in ("", "config") else f"{word}_hash"
        if (key, value) not in found:
            found.append((key, value))
    return found


def _json_hashes(data: object, prefix: str) -> Iterable[tuple[str, str]]:
    if isinstance(data, Mapping):
        for key, value in data.items():
            name = f"{prefix}{key}"
            if isinstance(value, str) and (key == "hash" or str(key).endswith("_hash")):
                yield name, value
            else:
                yield from _json_hashes(value, f"{name}.")
    elif isinstance(data, list):
        for k, item in enumerate(data):
            yield from _json_hashes(item, f"{prefix}{k}.")


def config_hashes(source: Source) -> list[str]:
    """The config hashes ``source`` names (keys ``config_hash`` at any depth), each once."""
    out: list[str] = []
    for key, value in named_hashes(source):
        if key.rsplit(".", 1)[-1] == CONFIG_HASH_KEY and value not in out:
            out.append(value)
    return out


def foreign_hashes(sources: Sequence[Source], identities: Mapping[str, Identity]) -> list[tuple[Source, str]]:
    """(input, hash) for every config hash an input names that is none of ``identities``."""
    return [(s, h) for s in sources for h in config_hashes(s) if h not in identities]


def check_belongs(sources: Sequence[Source], identities: Mapping[str, Identity], config: str) -> None:
    """Refuse (one-line :class:`UsageError`) the first input naming a config hash not of ``identities``."""
    for source, value in foreign_hashes(sources, identities)[:1]:
        known = ", ".join(f"{h} ({i.label})" for h, i in identities.items())
        raise UsageError(f"{source.option} = {source.path}: config hash {value} is not the config's "
                         f"({config}: {known}); run it from the same config and overrides, or pass --allow-mixed")

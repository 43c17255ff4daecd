"""Compiled templates kept across processes: same output, a damaged entry recompiled with one warning,
an unusable cache costing only the compile."""
from __future__ import annotations

import hashlib

import jinja2
import pytest

from codegen.resources import templates_dir
from codegen.templatecache import SealedBytecodeCache

TEMPLATE = "twolevel/mpc.c.j2"


def _env() -> jinja2.Environment:
    """A fresh environment (no in-process template cache) over the product's templates."""
    return jinja2.Environment(loader=jinja2.FileSystemLoader(str(templates_dir())), undefined=jinja2.StrictUndefined,
                              keep_trailing_newline=True, bytecode_cache=SealedBytecodeCache())


def _entries(root) -> list:
    return sorted((root / "templates").rglob("*.bc"))


def _code_of(env: jinja2.Environment, name: str) -> object:
    return env.get_template(name).root_render_func.__code__


def test_second_environment_loads_what_the_first_compiled(tmp_path, monkeypatch):
    monkeypatch.setenv("MPCGEN_CACHE", str(tmp_path))
    first = _code_of(_env(), TEMPLATE)
    entries = _entries(tmp_path)
    assert entries, "no entry written"
    stamps = {p: p.stat().st_mtime_ns for p in entries}
    second = _code_of(_env(), TEMPLATE)
    assert second.co_code == first.co_code and second.co_consts == first.co_consts
    assert {p: p.stat().st_mtime_ns for p in _entries(tmp_path)} == stamps  # read, not rewritten
    assert not list((tmp_path / "templates").rglob("*.tmp*"))


def test_damaged_entry_is_reported_removed_and_recompiled(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("MPCGEN_CACHE", str(tmp_path))
    want = _code_of(_env(), TEMPLATE)
    for entry in _entries(tmp_path):
        blob = bytearray(entry.read_bytes())
        blob[-3] ^= 0xFF  # one flipped byte in the compiled code: marshal could load it as other code
        entry.write_bytes(bytes(blob))
    capsys.readouterr()
    got = _code_of(_env(), TEMPLATE)
    err = capsys.readouterr().err
    assert "is damaged" in err and "recompiling the template" in err
    assert got.co_code == want.co_code
    for entry in _entries(tmp_path):  # rewritten whole
        blob = entry.read_bytes()
        assert blob[:64].decode() == hashlib.sha256(blob[65:]).hexdigest()


@pytest.mark.parametrize("damage", [b"", b"abc", b"0" * 64 + b"\n"])
def test_truncated_entries_are_recompiled(tmp_path, monkeypatch, capsys, damage):
    monkeypatch.setenv("MPCGEN_CACHE", str(tmp_path))
    want = _code_of(_env(), TEMPLATE)
    for entry in _entries(tmp_path):
        entry.write_bytes(damage)
    assert _code_of(_env(), TEMPLATE).co_code == want.co_code
    assert "is damaged" in capsys.readouterr().err


def test_unusable_cache_only_costs_the_compile(tmp_path, monkeypatch):
    afile = tmp_path / "afile"
    afile.write_text("x")
    monkeypatch.setenv("MPCGEN_CACHE", str(afile))
    text = _env().get_template("common/macros.j2").render()
    assert isinstance(text, str) and afile.read_text() == "x"

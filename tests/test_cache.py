"""The build cache: an unusable location is refused in one line, a damaged entry is rebuilt with one warning.

The damaged-library case runs in fresh processes: a truncated shared library
that were loaded would kill the process (SIGBUS), so the check must happen
before it is loaded.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from codegen import cache
from codegen.cli import main

from conftest import ROOT, SPMSM


def _one_line_exit_2(capsys: pytest.CaptureFixture[str], argv: list[str], *fragments: str) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    for f in fragments:
        assert f in err, err


def test_cache_naming_a_file_is_refused(tmp_path, monkeypatch, capsys):
    f = tmp_path / "afile"
    f.write_text("x")
    monkeypatch.setenv("MPCGEN_CACHE", str(f))
    _one_line_exit_2(capsys, ["verify", str(SPMSM), "--states", "100", "--strategies", "conventional", "-q"],
                     "MPCGEN_CACHE", "is a file, not a folder")


def test_unwritable_cache_is_refused(monkeypatch, capsys):
    monkeypatch.setenv("MPCGEN_CACHE", "/proc/self/mpcgen-cache")  # procfs: no folder can be made there
    _one_line_exit_2(capsys, ["verify", str(SPMSM), "--states", "100", "--strategies", "conventional", "-q"],
                     "MPCGEN_CACHE", "cannot write there")


def test_json_entry_round_trip_and_damage(tmp_path, capsys):
    entry = tmp_path / "e.json"
    cache.write_json(entry, {"s2": [[1, 2], [3, 4]]})
    assert cache.read_json(entry) == {"s2": [[1, 2], [3, 4]]}
    assert not list(tmp_path.glob("*.tmp*"))  # written through a temporary, renamed into place
    blob = entry.read_bytes()
    entry.write_bytes(blob[: len(blob) // 2])  # truncated
    assert cache.read_json(entry) is None and not entry.exists()
    assert "damaged" in capsys.readouterr().err
    cache.write_json(entry, [1])
    data = json.loads(entry.read_text())
    entry.write_text(json.dumps({**data, "payload": "[2]"}))  # edited: the digest no longer matches
    assert cache.read_json(entry) is None
    assert "does not match" in capsys.readouterr().err


def test_stale_temporaries_are_removed(tmp_path, monkeypatch):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True, check=True).stdout.strip()
    (tmp_path / f"lib_x.tmp{dead}").mkdir()
    (tmp_path / f"training_y.json.tmp{dead}").write_text("half")
    live = tmp_path / f"lib_z.tmp{os.getpid()}"
    live.mkdir()
    monkeypatch.setenv("MPCGEN_CACHE", str(tmp_path))
    assert cache.cache_root() == tmp_path
    assert sorted(p.name for p in tmp_path.iterdir()) == [live.name]


_BUILD = """
import sys
from codegen.config import load_config
from codegen.topology import topology_of
m = load_config(sys.argv[1], {"controller.strategy": "conventional"})
t = topology_of(m)
lib = t.host_library(m, t.derive(m))
print(lib.build_dir)
"""


def _build(env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", _BUILD, str(SPMSM)], capture_output=True, text=True, env=env,
                          cwd=ROOT, timeout=600)


def test_truncated_library_is_rebuilt_not_loaded(tmp_path):
    env = {**os.environ, "MPCGEN_CACHE": str(tmp_path), "PYTHONPATH": str(ROOT)}
    first = _build(env)
    assert first.returncode == 0, first.stderr
    bdir = Path(first.stdout.strip().splitlines()[-1])
    so = next(bdir.glob("*.so"))
    assert (bdir / cache.SEAL_NAME).is_file()
    so.write_bytes(so.read_bytes()[:4096])  # an interrupted copy, a full disk
    second = _build(env)
    assert second.returncode == 0, second.stderr  # SIGBUS (-7) if the truncated library had been loaded
    assert "damaged" in second.stderr and "rebuilding" in second.stderr
    assert len(second.stderr.strip().splitlines()) == 1, second.stderr
    third = _build(env)  # the cache works again: no warning
    assert third.returncode == 0 and third.stderr.strip() == "", third.stderr

"""Output writes that fail cleanly: a full disk or a name the file system refuses gives one line and the
right exit code, and leaves no half-written file (every file written is complete, no temporaries)."""
from __future__ import annotations

import subprocess

import pytest

from codegen.cli import main

from conftest import EXAMPLES

SERVO = EXAMPLES / "servo400w.toml"


def _one_line(capsys: pytest.CaptureFixture[str], *fragments: str) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    for f in fragments:
        assert f in err, err
    return err


@pytest.fixture
def small_fs(tmp_path):
    """A 48 kB file system (tmpfs), unmounted afterwards."""
    mnt = tmp_path / "small"
    mnt.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=48k", "tmpfs", str(mnt)], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.fail(f"cannot mount a small tmpfs for the full-disk test (needs root): {r.stderr.strip()}")
    yield mnt
    subprocess.run(["umount", str(mnt)], check=True)


def test_full_disk_one_line_exit_1_nothing_half_written(small_fs, tmp_path, capsys):
    roomy = tmp_path / "roomy"
    assert main(["generate", str(SERVO), "--target", "all", "-o", str(roomy), "-q"]) == 0
    capsys.readouterr()
    out = small_fs / "out"
    assert main(["generate", str(SERVO), "--target", "all", "-o", str(out), "-q"]) == 1
    _one_line(capsys, "no space left on the device", "nothing half-written")
    files = [p for p in out.rglob("*") if p.is_file()]
    assert not [p for p in files if ".tmp" in p.name], files
    for p in files:  # every file that is there is the whole file
        assert p.read_bytes() == (roomy / p.relative_to(out)).read_bytes(), p


def test_long_folder_name_one_line_exit_2(tmp_path, capsys):
    out = tmp_path / ("x" * 300)
    assert main(["generate", str(SERVO), "-o", str(out), "-q"]) == 2
    _one_line(capsys, "too long for the file system")


def test_long_json_path_one_line_exit_2(tmp_path, capsys):
    path = tmp_path / "/".join(["d" * 250] * 20) / "r.json"  # 5 kB: longer than PATH_MAX
    assert main(["tables", str(SERVO), "--utilisation", "published", "--json", str(path), "-q"]) == 2
    _one_line(capsys, "too long")

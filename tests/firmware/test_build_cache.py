"""Built firmware images cached by content hash (``firmware.build_firmware``, codegen.cache entries).

A second build of a project whose every input is identical (sources, headers, Makefile and its
flags, make variables, compiler version) reuses the first build's folder and says so; one changed
byte of a source, another compiler or other make variables build again; a damaged entry is
reported and rebuilt; a project that already has a build folder is left to make.
"""
from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from codegen.stages import emulate
from codegen.stages import firmware as firmware

from fw_support import example, needs_qemu

BOARD = "qemu-m7"


@pytest.fixture()
def cache_dir(tmp_path, monkeypatch) -> Path:
    root = tmp_path / "cache"
    monkeypatch.setenv("MPCGEN_CACHE", str(root))
    return root


def _project(path: Path) -> Path:
    m, t = example("spmsm", "s3")
    firmware.write_firmware_project(m, t, BOARD, path, 10, n_bench=0)
    return path


@needs_qemu
def test_identical_inputs_reuse_the_image_and_one_byte_rebuilds(tmp_path, cache_dir):
    lines: list[str] = []
    first = firmware.build_firmware(_project(tmp_path / "a"), BOARD, log=lines.append)
    assert first.reused is None and "-o build/gen/mpc_selftest_data.o" in first.log and not lines
    entries = sorted((cache_dir / firmware.IMAGE_CACHE).iterdir())
    assert len(entries) == 1 and entries[0].name.startswith(f"{BOARD}-")

    # the same project written again elsewhere: the image (and the whole build folder) is reused
    b = _project(tmp_path / "b")
    second = firmware.build_firmware(b, BOARD, log=lines.append)
    assert second.reused == entries[0]
    assert len(lines) == 1 and "reused the qemu-m7 image built from identical inputs" in lines[0]
    assert second.log.startswith("mpcgen: reused the qemu-m7 image")
    assert second.image == b / "build/fw.elf" and second.image.read_bytes() == first.image.read_bytes()
    assert (second.text, second.stack_depth) == (first.text, first.stack_depth) and second.text > 0
    assert (b / "build/gen/spmsm_mpc.o").is_file() and any((b / "build").glob("**/*.su"))
    # the restored folder is up to date: make has nothing to compile or link
    dry = subprocess.run(["make", "-n", "-C", str(b)], capture_output=True, text=True, check=True).stdout
    assert "arm-none-eabi-gcc" not in dry
    run = emulate.run_qemu(second.image, timeout_s=120)
    assert run.returncode == 0 and "RESULT PASS" in run.uart, run.uart[-1000:]

    # one byte of one source changed: built again, and stored as its own entry
    c = _project(tmp_path / "c")
    src = c / "firmware/runtime/console.c"
    text = src.read_bytes()
    at = text.index(b"console.c")  # in the file's header comment
    src.write_bytes(text[:at] + b"C" + text[at + 1:])
    third = firmware.build_firmware(c, BOARD, log=lines.append)
    assert third.reused is None and len(lines) == 1
    assert "-o build/firmware/runtime/console.o" in third.log
    assert len(list((cache_dir / firmware.IMAGE_CACHE).iterdir())) == 2


@needs_qemu
def test_a_project_with_a_build_folder_is_left_to_make(tmp_path, cache_dir):
    a = _project(tmp_path / "a")
    firmware.build_firmware(a, BOARD)
    again = firmware.build_firmware(a, BOARD)  # incremental: make, nothing to do
    assert again.reused is None and "-o build/" not in again.log
    b = _project(tmp_path / "b")
    (b / "build").mkdir()
    fresh = firmware.build_firmware(b, BOARD)
    assert fresh.reused is None and "-o build/gen/mpc_selftest_data.o" in fresh.log
    assert firmware.build_firmware(_project(tmp_path / "c"), BOARD, reuse=False).reused is None


@needs_qemu
def test_a_damaged_entry_is_reported_and_rebuilt(tmp_path, cache_dir, capsys):
    firmware.build_firmware(_project(tmp_path / "a"), BOARD)
    (entry,) = (cache_dir / firmware.IMAGE_CACHE).iterdir()
    archive = entry / "build.tar.gz"
    archive.write_bytes(archive.read_bytes()[:-100])
    rebuilt = firmware.build_firmware(_project(tmp_path / "b"), BOARD)
    err = capsys.readouterr().err
    assert rebuilt.reused is None and "damaged" in err and str(entry) in err and rebuilt.image.is_file()
    again = firmware.build_firmware(_project(tmp_path / "c"), BOARD)
    assert again.reused == entry and again.image.read_bytes() == rebuilt.image.read_bytes()


def test_inputs_hash_covers_sources_flags_make_variables_and_compiler(tmp_path, monkeypatch):
    """Every input of the build changes the hash; the build folder does not."""
    p = _project(tmp_path / "p")
    monkeypatch.setattr(firmware, "compiler_identity", lambda cc: f"{cc} 12.2.1")
    base = firmware.build_inputs_hash(p, BOARD)
    assert base == firmware.build_inputs_hash(_project(tmp_path / "q"), BOARD)  # same content elsewhere
    (p / "build").mkdir()
    (p / "build/junk.o").write_bytes(b"x")
    assert firmware.build_inputs_hash(p, BOARD) == base
    assert firmware.build_inputs_hash(p, BOARD, {"SANITIZE": "1"}) != base
    assert firmware.build_inputs_hash(p, "qemu-m3") != base
    monkeypatch.setattr(firmware, "compiler_identity", lambda cc: f"{cc} 13.1.0")
    assert firmware.build_inputs_hash(p, BOARD) != base
    monkeypatch.setattr(firmware, "compiler_identity", lambda cc: f"{cc} 12.2.1")
    mk = p / "Makefile"
    mk.write_text(mk.read_text().replace("-O2", "-Os", 1))
    assert firmware.build_inputs_hash(p, BOARD) != base
    mk.write_text(mk.read_text().replace("-Os", "-O2", 1))
    assert firmware.build_inputs_hash(p, BOARD) == base
    header = p / "firmware/runtime/console.h"
    header.write_bytes(header.read_bytes() + b"\n")
    assert firmware.build_inputs_hash(p, BOARD) != base


@needs_qemu
def test_emulated_run_says_when_it_reuses_the_image(tmp_path, cache_dir):
    """The path of ``bench --emulated`` (emulate.run_and_check): the second identical image is not
    built again, its progress log says so, and the image still passes in QEMU."""
    m, t = example("spmsm", "s3")
    for i in (0, 1):
        lines: list[str] = []
        counts = emulate.run_and_check(m, t, tmp_path / f"w{i}", n_selftest=20, n_bench=0, log=lines.append)
        assert counts.mismatches == 0 and counts.digests_match and counts.states == 20
        reused = [line for line in lines if "reused the qemu-m7 image built from identical inputs" in line]
        assert len(reused) == i, lines

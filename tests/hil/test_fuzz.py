"""Fuzzing the firmware's frame decoder: libFuzzer + AddressSanitizer + UBSan, 10^6 inputs.

tests/hil/fuzz/fuzz_frame.c feeds arbitrary octets to the receive path of
firmware/runtime/hil_proto.c (unchanged: gathering up to 0x00, COBS decode,
length and CRC checks, message dispatch, STEP/BATCH through the generated
controller of the two-level example) with a stub port, and checks that every
frame the firmware sends is itself a valid frame.  The seed corpus
(tests/hil/fuzz/corpus/: HELLO, STEP, BATCH, PING, RESET, a bad CRC, an
unknown type, an oversize frame) is copied to a temporary folder, so the run
never writes to the repository.  clang with libFuzzer is required
(scripts/bootstrap.sh installs clang and libclang-rt-14-dev): missing, the
test fails, never skips.
"""
from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest
from hil_support import example

from codegen.stages.firmware import write_firmware_project
from hil.codecgen import protocol_build

from conftest import require_tool

pytestmark = pytest.mark.slow

FUZZ = Path(__file__).resolve().parent / "fuzz"
RUNS = 1_000_000
#: a hang guard only (the runs take about 2 min here): the test measures no speed, it demands every run
HANG_S = 1800
CFLAGS = ("-std=c99", "-g", "-O2", "-DMPC_HIL", "-Wall", "-Wextra", "-Wconversion", "-Wdouble-promotion", "-Werror",
          "-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all")


@pytest.fixture(scope="module")
def fuzzer(tmp_path_factory) -> Path:
    clang = require_tool("clang", "clang")
    project = tmp_path_factory.mktemp("fuzz")
    model, tables = example("spmsm", "s1")
    write_firmware_project(model, tables, "host", project, 1, n_bench=0, protocol=protocol_build(model))
    srcs = sorted(p for p in [*project.glob("gen/*.c"), *project.glob("firmware/runtime/*.c")]
                  if p.name != "main.c")
    exe = project / "fuzz_frame"
    r = subprocess.run([clang, *CFLAGS, *(f"-I{project / d}" for d in ("gen", "firmware/runtime",
                                                                        "firmware/ports/host")),
                        *map(str, srcs), str(FUZZ / "fuzz_frame.c"), "-lm", "-o", str(exe)],
                       capture_output=True, text=True)
    if r.returncode != 0 and "libclang_rt.fuzzer" in r.stderr:
        pytest.fail("clang has no libFuzzer runtime: install the Debian package libclang-rt-14-dev "
                    "(scripts/bootstrap.sh does)\n" + r.stderr)
    assert r.returncode == 0, r.stderr
    return exe


def test_seed_corpus_is_small_and_present():
    seeds = sorted((FUZZ / "corpus").iterdir())
    assert len(seeds) >= 5 and all(0 < p.stat().st_size <= 256 for p in seeds)


def test_frame_decoder_survives_a_million_inputs(fuzzer, tmp_path):
    corpus = tmp_path / "corpus"
    shutil.copytree(FUZZ / "corpus", corpus)
    r = subprocess.run([str(fuzzer), f"-runs={RUNS}", "-seed=1", "-max_len=256",
                        "-print_final_stats=1", f"-artifact_prefix={tmp_path}/", str(corpus)],
                       capture_output=True, text=True, timeout=HANG_S, cwd=tmp_path)
    log = r.stdout + r.stderr
    assert r.returncode == 0, log[-4000:]
    assert "ERROR:" not in log and "runtime error" not in log, log[-4000:]
    done = re.search(r"Done (\d+) runs", log)
    assert done is not None and int(done.group(1)) >= RUNS, log[-2000:]
    assert not list(tmp_path.glob("crash-*")) and not list(tmp_path.glob("leak-*"))

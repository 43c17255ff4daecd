"""Fuzzing the firmware's frame decoder: libFuzzer + AddressSanitizer + UBSan.

tests/hil/fuzz/fuzz_frame.c feeds arbitrary octets to the receive path of
firmware/runtime/hil_proto.c (unchanged: gathering up to 0x00, COBS decode,
length and CRC checks, message dispatch, STEP/BATCH through the generated
controller of the two-level example, SETPOINTS through the on-board loop,
runs cut to 64 periods) with a stub port, and checks that every frame the
firmware sends is itself a valid frame.  The seed corpus
(tests/hil/fuzz/corpus/, written by tests/hil/fuzz_seeds.py from the
protocol) holds every message and every error path; a build with clang's
source coverage shows that running the seeds once executes every
``send_error`` of hil_proto.c and every refusal of ``onboard_check``, and
the target's own counters (the error codes and SETPOINTS details it sent)
that every code is reached.  Then a 5-second fuzz run and (slow) 10^6
inputs.  The corpus is copied to a temporary folder, so the runs never
write to the repository.  clang with libFuzzer is required
(scripts/bootstrap.sh installs clang and libclang-rt-14-dev): missing, the
test fails, never skips.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from fuzz_seeds import CORPUS, seeds
from hil_support import example

from codegen.stages.firmware import write_firmware_project
from hil.codecgen import protocol_build
from hil.schema import Err, Msg

from conftest import require_tool

FUZZ = Path(__file__).resolve().parent / "fuzz"
RUNS = 1_000_000
#: a hang guard only (the runs take about 2 min here): the test measures no speed, it demands every run
HANG_S = 1800
#: seconds of the short fuzz run of every test run
SHORT_S = 5
CFLAGS = ("-std=c99", "-g", "-O2", "-DMPC_HIL", "-Wall", "-Wextra", "-Wconversion", "-Wdouble-promotion", "-Werror",
          "-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all")
COVERAGE = ("-fprofile-instr-generate", "-fcoverage-mapping")


@pytest.fixture(scope="module")
def project(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("fuzz")
    model, tables = example("spmsm", "s1")
    write_firmware_project(model, tables, "host", out, 1, n_bench=0, protocol=protocol_build(model))
    return out


def _build(project: Path, name: str, extra: tuple[str, ...] = ()) -> Path:
    """The fuzz target: hil_proto.c compiled with its on-board run renamed to fuzz_onboard_run (the
    target's bounded one), every other source as it is."""
    clang = require_tool("clang", "clang")
    srcs = sorted(p for p in [*project.glob("gen/*.c"), *project.glob("firmware/runtime/*.c")]
                  if p.name not in ("main.c", "hil_proto.c"))
    inc = [f"-I{project / d}" for d in ("gen", "firmware/runtime", "firmware/ports/host")]
    obj = project / f"{name}_hil_proto.o"
    exe = project / name
    for cmd in ([clang, *CFLAGS, *extra, *inc, "-Donboard_run=fuzz_onboard_run", "-c",
                 str(project / "firmware/runtime/hil_proto.c"), "-o", str(obj)],
                [clang, *CFLAGS, *extra, *inc, *map(str, srcs), str(obj), str(FUZZ / "fuzz_frame.c"), "-lm", "-o",
                 str(exe)]):
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0 and "libclang_rt.fuzzer" in r.stderr:
            pytest.fail("clang has no libFuzzer runtime: install the Debian package libclang-rt-14-dev "
                        "(scripts/bootstrap.sh does)\n" + r.stderr)
        assert r.returncode == 0, r.stderr
    return exe


@pytest.fixture(scope="module")
def fuzzer(project) -> Path:
    return _build(project, "fuzz_frame")


def _llvm_tool(name: str) -> str:
    """``name`` of clang's own LLVM (its profile format), else the one on PATH."""
    clang = Path(os.path.realpath(require_tool("clang", "clang")))
    tool = clang.parent / name
    return str(tool) if tool.exists() else require_tool(name, "llvm")


def _counts(log: str) -> dict[str, int]:
    """The target's "fuzz_frame sent:" line as {"msg:4": n, "err:1": n, "sp:2": n, "batch:zero": n, ...}."""
    lines = [ln for ln in log.splitlines() if ln.startswith("fuzz_frame sent:")]
    assert lines, log[-3000:]
    return {k: int(v) for k, v in re.findall(r"(\w+:\w+)=(\d+)", lines[-1])}


def _assert_every_error_reached(counts: dict[str, int]) -> None:
    missing = [e.name for e in Err if counts.get(f"err:{e.value}", 0) == 0]
    missing += [f"SETPOINTS detail {d}" for d in range(1, 6) if counts.get(f"sp:{d}", 0) == 0]
    missing += [f"BATCH count {w}" for w in ("zero", "big") if counts.get(f"batch:{w}", 0) == 0]
    missing += [m.name for m in (Msg.INFO, Msg.RESULT, Msg.PONG, Msg.TELEMETRY, Msg.RUN_END)
                if counts.get(f"msg:{m.value}", 0) == 0]
    assert not missing, f"never sent: {missing} ({counts})"


def test_seed_corpus_is_small_and_present():
    seeds_ = sorted((FUZZ / "corpus").iterdir())
    assert len(seeds_) >= 20 and all(0 < p.stat().st_size <= 256 for p in seeds_)


def test_seed_corpus_follows_the_protocol():
    want = seeds()
    have = {p.name: p.read_bytes() for p in CORPUS.iterdir()}
    assert have == want, "the corpus is stale: PYTHONPATH=. .venv/bin/python tests/hil/fuzz_seeds.py rewrites it"


def test_seed_corpus_reaches_every_error_path(project, tmp_path):
    """Each seed once, in a build with source coverage: every error the target sent (its counters) and
    every error line of hil_proto.c and onboard_check executed (llvm-cov)."""
    exe = _build(project, "fuzz_cov", COVERAGE)
    raw = tmp_path / "seeds.profraw"
    r = subprocess.run([str(exe), *sorted(map(str, CORPUS.iterdir()))], capture_output=True, text=True, timeout=120,
                       cwd=tmp_path, env={**os.environ, "LLVM_PROFILE_FILE": str(raw)})
    log = r.stdout + r.stderr
    assert r.returncode == 0 and "ERROR:" not in log and "runtime error" not in log, log[-4000:]
    _assert_every_error_reached(_counts(log))
    data = tmp_path / "seeds.profdata"
    subprocess.run([_llvm_tool("llvm-profdata"), "merge", "-sparse", str(raw), "-o", str(data)], check=True)

    def lines(src: Path) -> list[tuple[str, str]]:
        out = subprocess.run([_llvm_tool("llvm-cov"), "show", str(exe), f"-instr-profile={data}", str(src)],
                             capture_output=True, text=True, check=True).stdout
        rows = [re.match(r"\s*\d+\|\s*([^|]*)\|(.*)$", ln) for ln in out.splitlines()]
        return [(m.group(1).strip(), m.group(2)) for m in rows if m is not None]

    proto = lines(project / "firmware/runtime/hil_proto.c")
    errors = [(count, code) for count, code in proto if "send_error(HIL_ERR_" in code]
    # every ERROR the firmware sends: SHORT, CRC, COBS, TYPE, OVERSIZE x2 (more than the buffer, decodes to more
    # than a frame), LENGTH x4 (STEP, BATCH without head, BATCH count and length differ, SETPOINTS), BATCH,
    # SETPOINTS
    source = (project / "firmware/runtime/hil_proto.c").read_text()
    assert len(errors) == source.count("send_error(HIL_ERR_") >= 12, errors
    assert all(count not in ("", "0") for count, _ in errors), [e for e in errors if e[0] in ("", "0")]
    window = [c for c, code in proto if "idx - run_first >= run_count" in code]
    assert window and window[0] not in ("", "0")
    onboard = lines(project / "firmware/runtime/onboard.c")
    start = next(i for i, (_, code) in enumerate(onboard) if code.startswith("uint16_t onboard_check("))
    stop = next(i for i, (_, code) in enumerate(onboard) if i > start and code.startswith("}"))
    refusals = [(count, code) for count, code in onboard[start:stop] if re.search(r"return [1-9]u;", code)]
    # details 1 periods, 2 decimation, 3 step count, 4 first step and step order, 5 frame window
    assert len(refusals) == 6 and all(count not in ("", "0") for count, _ in refusals), refusals


def test_short_fuzz_run(fuzzer, tmp_path):
    corpus = tmp_path / "corpus"
    shutil.copytree(CORPUS, corpus)
    r = subprocess.run([str(fuzzer), f"-max_total_time={SHORT_S}", "-seed=1", "-max_len=256",
                        "-print_final_stats=1", f"-artifact_prefix={tmp_path}/", str(corpus)],
                       capture_output=True, text=True, timeout=SHORT_S + 120, cwd=tmp_path)
    log = r.stdout + r.stderr
    assert r.returncode == 0, log[-4000:]
    assert "ERROR:" not in log and "runtime error" not in log, log[-4000:]
    assert re.search(r"Done \d+ runs", log), log[-2000:]
    assert not list(tmp_path.glob("crash-*")) and not list(tmp_path.glob("leak-*"))
    _assert_every_error_reached(_counts(log))


@pytest.mark.slow
def test_frame_decoder_survives_a_million_inputs(fuzzer, tmp_path):
    corpus = tmp_path / "corpus"
    shutil.copytree(CORPUS, corpus)
    r = subprocess.run([str(fuzzer), f"-runs={RUNS}", "-seed=1", "-max_len=256",
                        "-print_final_stats=1", f"-artifact_prefix={tmp_path}/", str(corpus)],
                       capture_output=True, text=True, timeout=HANG_S, cwd=tmp_path)
    log = r.stdout + r.stderr
    assert r.returncode == 0, log[-4000:]
    assert "ERROR:" not in log and "runtime error" not in log, log[-4000:]
    done = re.search(r"Done (\d+) runs", log)
    assert done is not None and int(done.group(1)) >= RUNS, log[-2000:]
    assert not list(tmp_path.glob("crash-*")) and not list(tmp_path.glob("leak-*"))
    _assert_every_error_reached(_counts(log))

"""`mpcgen verify` estimates its memory before anything runs and refuses, in one line, a run that would not
fit (issue 28: ``--states 200000000`` under a 6 GB address-space limit ended in a MemoryError traceback)."""
from __future__ import annotations

import os
import resource
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import codegen.simulator.memory as memory
from codegen.cli import main
from codegen.config import load_config
from codegen.stages.verify import RUNTIME_BYTES, check_verify_memory, verify_memory

from conftest import ROOT, SPMSM, TTYPE

GIB = 1024**3


def _env(jobs: int = 2) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT), "MPCGEN_JOBS": str(jobs)}


def _limit_as(n_bytes: int):  # type: ignore[no-untyped-def]
    def pre() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (n_bytes, n_bytes))
    return pre


@pytest.mark.parametrize("cfg", [SPMSM, TTYPE], ids=["spmsm", "tlevel"])
def test_too_many_states_under_an_address_space_limit_is_one_line(cfg: Path) -> None:
    r = subprocess.run([sys.executable, "-m", "codegen.cli", "verify", str(cfg), "--states", "200000000", "-q"],
                       preexec_fn=_limit_as(6 * GIB), capture_output=True, text=True, timeout=300, env=_env(),
                       cwd=ROOT)
    lines = [line for line in r.stderr.strip().splitlines() if not line.startswith("mpcgen: warning:")]
    assert r.returncode == 2 and len(lines) == 1, r.stderr
    assert "Traceback" not in r.stderr and "MemoryError" not in r.stderr
    assert "--states = 200000000" in lines[0] and "the address-space limit (RLIMIT_AS)" in lines[0], lines[0]
    assert "at most about" in lines[0] and r.stdout == "", r.stdout  # refused before anything ran


def test_refused_against_the_available_memory(monkeypatch: pytest.MonkeyPatch,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(memory, "memory_room", lambda: [("the available memory (MemAvailable)", 2 * GIB, False)])
    assert main(["verify", str(SPMSM), "--states", "50000000", "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "more than the available memory (MemAvailable) leaves (2.15 GB)" in err[0], err


def test_the_estimate_follows_records_strategies_and_chunking(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MPCGEN_JOBS", "2")
    model = load_config(TTYPE)
    small, big = verify_memory(model, 10_000), verify_memory(model, 8_000_000)
    assert small.jobs == 1 and small.chunk == 250_000 and big.jobs == 2
    assert big.in_bytes == 36 and big.per_state == 2 * 36 + 24 + big.out_bytes  # outputs held for the pool
    # the strategies run one after the other: the check takes the largest, 27-MPDTC's longer output record
    est = check_verify_memory(model, ["mpdtc27", "mpdtc63"], 1000)
    assert est[0].out_bytes > est[1].out_bytes
    monkeypatch.setattr(memory, "memory_room", lambda: [("the address-space limit (RLIMIT_AS)", GIB, True)])
    check_verify_memory(model, ["mpdtc63"], 1000)  # fits
    with pytest.raises(Exception, match="at most about"):
        check_verify_memory(model, ["mpdtc63"], 8_000_000)


PROBE = textwrap.dedent("""
    import sys
    from codegen.config import load_config
    from codegen.stages.verify import verify_memory, verify_strategy
    from codegen.topology import topology_of

    def vm(key):
        for line in open("/proc/self/status"):
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024

    m = load_config(sys.argv[1], {"controller.strategy": sys.argv[2], "controller.number_format": sys.argv[3]})
    topo = topology_of(m)
    topo.host_library(m, topo.derive(m))
    before = vm("VmSize")
    est = verify_memory(m, int(sys.argv[4]), closed_loop=False)
    r = verify_strategy(m, int(sys.argv[4]), log=lambda s: None, closed_loop=False)
    assert r.mismatches == 0
    print(vm("VmPeak") - before, est.main_bytes)
""")


@pytest.mark.parametrize("cfg,strategy,fmt,n,jobs", [
    (SPMSM, "conventional", "float32", 4_000_000, 2),
    (TTYPE, "mpdtc27", "fixed", 2_000_000, 1),
], ids=["spmsm-pool", "tlevel-fixed-serial"])
def test_the_estimate_bounds_the_measured_peak(cfg: Path, strategy: str, fmt: str, n: int, jobs: int) -> None:
    r = subprocess.run([sys.executable, "-c", PROBE, str(cfg), strategy, fmt, str(n)], capture_output=True, text=True,
                       timeout=600, env=_env(jobs), cwd=ROOT)
    assert r.returncode == 0, r.stderr[-2000:]
    peak, est = (int(v) for v in r.stdout.split())
    assert peak <= est - RUNTIME_BYTES // 2, (peak, est)  # an upper bound, with the runtime margin to spare
    assert est < 3 * peak + RUNTIME_BYTES, (peak, est)  # and not a wild one

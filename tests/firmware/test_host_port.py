"""The host port under AddressSanitizer + UndefinedBehaviorSanitizer runs the self-test clean,
for every two-level and three-level strategy."""
from __future__ import annotations

import subprocess

import pytest

from codegen import emulate
from codegen import fwproject as firmware
from codegen.fwdata import expected_outputs, selftest_states, topology_of, values_crc

from fw_support import spmsm, tlevel

CASES = [("spmsm", s) for s in ("conventional", "s1", "s2", "s3")] + [("tlevel", s) for s in ("mpdtc27", "mpdtc63")]


@pytest.mark.parametrize("config,strategy", CASES, ids=[f"{c}-{s}" for c, s in CASES])
def test_host_port_sanitizers(tmp_path, config, strategy):
    m, t = (spmsm if config == "spmsm" else tlevel)(strategy)
    n = 10_000 if config == "spmsm" else 3_000
    firmware.write_firmware_project(m, t, "host", tmp_path, n, n_bench=200)
    res = firmware.build_firmware(tmp_path, "host", make_vars={"SANITIZE": "1"})
    assert "-fsanitize=address,undefined" in res.log
    run = subprocess.run([str(res.image)], capture_output=True, text=True, timeout=300)
    assert "runtime error" not in run.stderr and "AddressSanitizer" not in run.stderr, run.stderr
    rep = emulate.parse_console(run.stdout)
    assert run.returncode == 0 and rep.result == "PASS", run.stdout[-2000:]
    s = rep.sets["selftest"]
    assert s.n == n and s.mismatches == 0 and rep.sets["bench"].mismatches == 0
    outputs = expected_outputs(t, selftest_states(m, t, n))
    assert s.crc_out == values_crc(outputs, topology_of(m).output_fields)

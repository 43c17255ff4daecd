"""The host port under AddressSanitizer + UndefinedBehaviorSanitizer runs the self-test clean,
for every two-level and T-type strategy."""
from __future__ import annotations

import subprocess

import pytest

from codegen.stages import emulate
from codegen.stages import firmware as firmware
from codegen.stages.fwdata import expected_outputs, layouts, selftest_states
from codegen.topology import topology_of

from fw_support import CASE_IDS, CASES, example


@pytest.mark.parametrize("config,strategy", CASES, ids=CASE_IDS)
def test_host_port_sanitizers(tmp_path, config, strategy):
    m, t = example(config, strategy)
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
    outputs = expected_outputs(topology_of(m), t, selftest_states(m, t, n))
    assert s.crc_out == layouts(m)[1].crc(outputs)

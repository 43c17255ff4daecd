"""The host port under AddressSanitizer + UndefinedBehaviorSanitizer runs the self-test clean."""
from __future__ import annotations

import subprocess

from codegen import emulate
from codegen import fwproject as firmware
from codegen.fwdata import selftest_states, values_crc
from codegen.twolevel.interface import OUTPUT_FIELDS
from codegen.twolevel.reference import step_batch

from fw_support import spmsm


def test_host_port_sanitizers(tmp_path):
    m, t = spmsm("s2")
    firmware.write_firmware_project(m, t, "host", tmp_path, 10_000, n_bench=500)
    res = firmware.build_firmware(tmp_path, "host", make_vars={"SANITIZE": "1"})
    assert "-fsanitize=address,undefined" in res.log
    run = subprocess.run([str(res.image)], capture_output=True, text=True, timeout=300)
    assert "runtime error" not in run.stderr and "AddressSanitizer" not in run.stderr, run.stderr
    rep = emulate.parse_console(run.stdout)
    assert run.returncode == 0 and rep.result == "PASS", run.stdout[-2000:]
    s = rep.sets["selftest"]
    assert s.n == 10_000 and s.mismatches == 0 and rep.sets["bench"].mismatches == 0
    assert s.crc_out == values_crc(step_batch(t, selftest_states(m, t, 10_000)), OUTPUT_FIELDS)

"""The STM32H743 project builds warning-free with the step in ITCM and tables in DTCM."""
from __future__ import annotations

import re
import subprocess

from codegen.stages import firmware as firmware

from fw_support import example, needs_arm


@needs_arm
def test_stm32h743_build_layout(tmp_path):
    m, t = example("spmsm", "s3")
    firmware.write_firmware_project(m, t, "stm32h743", tmp_path, 10_000)
    res = firmware.build_firmware(tmp_path, "stm32h743")
    assert "warning" not in res.log.lower(), res.log
    assert res.text > 0 and res.bss > 0 and res.stack_depth > 0, res.log
    assert res.stack_path[0].startswith("Reset_Handler")
    assert any(f.startswith("spmsm_step(") for f in res.stack_path), res.stack_path  # through the timed call

    mapfile = (tmp_path / "build" / "fw.map").read_text()
    # the step: output section .itcm_text in the ITCM (0x00000000 + 64 KB)
    step = re.search(r"^\s+(0x[0-9a-f]+)\s+spmsm_step\s*$", mapfile, re.M)
    assert step and int(step.group(1), 16) < 0x10000, "spmsm_step not in ITCM"
    itcm = re.search(r"^\.itcm_text\s+(0x[0-9a-f]+)\s+(0x[0-9a-f]+)\s+load address\s+(0x[0-9a-f]+)", mapfile, re.M)
    assert itcm and int(itcm.group(1), 16) < 0x10000 and int(itcm.group(3), 16) >= 0x08000000
    # the tables: input section .dtcm_rodata of the controller in DTCM (0x20000000 + 128 KB)
    tables = re.search(r"^\s*\.dtcm_rodata\s+(0x[0-9a-f]+)\s+0x[0-9a-f]+\s+\S*spmsm_mpc\.o", mapfile, re.M)
    assert tables and 0x20000000 <= int(tables.group(1), 16) < 0x20020000, "tables not in DTCM"
    nm = subprocess.run(["arm-none-eabi-nm", str(res.image)], capture_output=True, text=True, check=True).stdout
    addr = {line.split()[2]: int(line.split()[0], 16) for line in nm.splitlines() if len(line.split()) == 3}
    for table in ("spmsm_rows", "spmsm_row_n", "spmsm_uxy", "spmsm_zero_sw", "spmsm_vec_to_sw"):
        assert 0x20000000 <= addr[table] < 0x20020000, table
    assert addr["cm7_vectors"] == 0x08000000
    assert "memcpy" not in addr or addr["memcpy"] < 0x10000  # the step calls no library copy out of ITCM

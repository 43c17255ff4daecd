"""Real-board ports build with the serial protocol (-DMPC_HIL): STM32H743 with arm-none-eabi-gcc
(the project's Makefile, -Werror), TMS320F28377 compiled on the host under the C28x type model
(as tests/firmware/test_c28x.py: cl2000 is not installable here)."""
from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from hil_support import example

from codegen.hostbuild import STRICT_CFLAGS
from codegen.stages.firmware import build_firmware, write_firmware_project
from hil.codecgen import protocol_build

from conftest import require_tool

ROOT = Path(__file__).resolve().parents[2]
MODEL_H = ROOT / "tests" / "firmware" / "c28x_type_model.h"
MODEL_FLAGS = ("-DMPC_C28X_TYPE_MODEL", "--param=min-pagesize=0", "-include", str(MODEL_H))


@pytest.mark.slow
def test_stm32h743_protocol_project_builds(tmp_path):
    require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    model, tables = example("spmsm", "s2")
    write_firmware_project(model, tables, "stm32h743", tmp_path, 1, n_bench=0, protocol=protocol_build(model))
    assert "-DMPC_HIL" in (tmp_path / "Makefile").read_text()
    res = build_firmware(tmp_path, "stm32h743")
    nm = subprocess.run(["arm-none-eabi-nm", str(res.image)], capture_output=True, text=True, check=True).stdout
    assert " T port_read" in nm and " T hil_serve" in nm and "mpc_selftest_run" not in nm


def test_f28377_protocol_sources_compile_under_the_c28x_type_model(tmp_path):
    model, tables = example("spmsm", "s3")
    write_firmware_project(model, tables, "tms320f28377", tmp_path, 1, n_bench=0, protocol=protocol_build(model))
    incs = [f"-I{tmp_path / d}" for d in ("gen", "firmware/runtime", "firmware/ports/tms320f28377")]
    srcs = sorted([*tmp_path.glob("gen/*.c"), *tmp_path.glob("firmware/runtime/*.c"),
                   *tmp_path.glob("firmware/ports/tms320f28377/*.c")])
    assert any(p.name == "hil_proto.c" for p in srcs) and any(p.name == "hil_codec.c" for p in srcs)
    for src in srcs:
        r = subprocess.run(["gcc", *STRICT_CFLAGS, *MODEL_FLAGS, "-DMPC_HIL", *incs, "-c", str(src),
                            "-o", "/dev/null"], capture_output=True, text=True)
        assert r.returncode == 0, f"{src.name}:\n{r.stderr}"
    board = (tmp_path / "firmware/ports/tms320f28377/board.c").read_text()
    assert "uint16_t port_read(uint16_t *octets, uint16_t max)" in board

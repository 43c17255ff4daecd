"""`mpcgen generate`: deterministic, warning-free under the strict flags on gcc and arm-none-eabi-gcc."""
from __future__ import annotations

import re
import subprocess

import pytest

from codegen.cli import main

from conftest import IPMSM, SPMSM, TWO_LEVEL, require_tool

WARN = ["-std=c99", "-Wall", "-Wextra", "-Wconversion", "-Wdouble-promotion", "-Werror"]
ARM = ["-mcpu=cortex-m7", "-mthumb", "-mfpu=fpv5-d16", "-mfloat-abi=hard", "-O2", "-ffp-contract=off", "-fno-math-errno"]


def _generate(cfg, target, out, *extra):
    assert main(["generate", str(cfg), "--target", target, "-o", str(out), "-q", *extra]) == 0
    return sorted(out.iterdir())


@pytest.mark.parametrize("cfg", [SPMSM, IPMSM], ids=["spmsm", "ipmsm"])
@pytest.mark.parametrize("strategy", TWO_LEVEL)
def test_compiles_strict_for_every_target(tmp_path, cfg, strategy):
    arm = require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    for target in ("stm32h743", "tms320f28377", "host"):
        out = tmp_path / target
        files = _generate(cfg, target, out, "--strategy", strategy, "--tables", "published")
        src = [f for f in files if f.name.endswith("_mpc.c")][0]
        r = subprocess.run(["gcc", *WARN, "-O2", "-ffp-contract=off", "-c", str(src), "-o", str(tmp_path / "x.o")],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        if target == "stm32h743":
            r = subprocess.run([arm, *ARM, *WARN, "-c", str(src), "-o", str(tmp_path / "m7.o")], capture_output=True, text=True)
            assert r.returncode == 0, r.stderr
            syms = subprocess.run(["arm-none-eabi-objdump", "-h", str(tmp_path / "m7.o")], capture_output=True, text=True).stdout
            assert ".itcm_text" in syms and ".dtcm_rodata" in syms


def test_generate_twice_is_byte_identical(tmp_path):
    a = _generate(SPMSM, "stm32h743", tmp_path / "a", "--strategy", "s3")
    b = _generate(SPMSM, "stm32h743", tmp_path / "b", "--strategy", "s3")
    assert [p.name for p in a] == [p.name for p in b]
    for pa, pb in zip(a, b):
        assert pa.read_bytes() == pb.read_bytes(), pa.name


def test_c28x_profile_uses_no_8bit_types_and_no_double(tmp_path):
    for strategy in TWO_LEVEL:
        for f in _generate(SPMSM, "tms320f28377", tmp_path / strategy, "--strategy", strategy, "--tables", "published"):
            if f.suffix in (".c", ".h"):
                text = re.sub(r"/\*.*?\*/", "", f.read_text(), flags=re.S)  # code only
                for bad in ("int8_t", "uint8_t", "double", "char "):
                    assert bad not in text, f"{f.name} uses {bad}"


def test_every_symbol_is_prefixed(tmp_path):
    files = _generate(IPMSM, "host", tmp_path / "h", "--strategy", "s2", "--tables", "published")
    obj = tmp_path / "x.o"
    src = [f for f in files if f.name.endswith("_mpc.c")][0]
    subprocess.run(["gcc", "-std=c99", "-O2", "-c", str(src), "-o", str(obj)], check=True)
    nm = subprocess.run(["nm", str(obj)], capture_output=True, text=True, check=True).stdout
    names = [line.split()[-1] for line in nm.splitlines() if line.split()[-2] in "TtDdRrBb"]
    assert names and all(n.startswith("ipmsm_") for n in names if not n.startswith(".")), names


def test_comments_cite_equations_and_spec(tmp_path):
    files = _generate(SPMSM, "host", tmp_path / "h", "--strategy", "s3", "--tables", "published")
    text = [f for f in files if f.name.endswith("_mpc.c")][0].read_text()
    for needle in ("mptc-two-level.md", "numerics.md", "eq. (12)", "Cost", "Clarke", "Park"):
        assert needle in text

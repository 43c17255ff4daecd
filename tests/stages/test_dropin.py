"""Drop-in safety of the generated C (targets.md "Dropping the C into a vendor project"):
no fused multiply-add whatever the build flags (the .c switches contraction off itself),
a loud #error where it cannot, and optional section placement."""
from __future__ import annotations

import re
import subprocess

import pytest

from codegen.cli import main

from conftest import IPMSM, SPMSM, TTYPE, require_tool

#: CubeIDE-like Cortex-M7 flags: gnu11, no -ffp-contract=off (GCC then contracts by default)
M7_VENDOR = ("-std=gnu11", "-O2", "-mcpu=cortex-m7", "-mthumb", "-mfpu=fpv5-d16", "-mfloat-abi=hard",
             "-Wall", "-Wextra", "-Werror")
#: host flags that would contract: x86-64 FMA available, gnu11, no -ffp-contract=off
HOST_VENDOR = ("-std=gnu11", "-O2", "-mfma", "-Wall", "-Wextra", "-Werror")
ARM_FMA = re.compile(r"\bvfn?m[as]\b")
X86_FMA = re.compile(r"\bvfn?m(add|sub)")
CASES = [(SPMSM, "s3"), (IPMSM, "s1"), (TTYPE, "mpdtc63")]
#: the two-level s3's tables as published (a T-type config has no controller.tables)
PUBLISHED = {SPMSM: ("--tables", "published"), IPMSM: ("--tables", "published"), TTYPE: ()}


def _generate(cfg, target, out, *extra):
    assert main(["generate", str(cfg), "--target", target, "-o", str(out), "-q", *extra]) == 0
    return out


def _fmas(cc: str, objdump: str, flags, src, obj, rx) -> int:
    r = subprocess.run([cc, *flags, f"-I{src.parent}", "-c", str(src), "-o", str(obj)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return len(rx.findall(subprocess.run([objdump, "-d", str(obj)], capture_output=True, text=True, check=True).stdout))


def _without_pragma(src, tmp_path):
    """A copy of ``src`` without the contraction pragma (shows the flags alone do contract)."""
    text, n = re.subn(r'^#pragma GCC optimize\("fp-contract=off".*$', "", src.read_text(), flags=re.M)
    assert n == 1
    bare = src.parent / ("bare_" + src.name)
    bare.write_text(text)
    return bare


@pytest.mark.parametrize("cfg,strategy", CASES, ids=["spmsm-s3", "ipmsm-s1", "ttype-63"])
def test_no_fma_on_cortex_m7_without_fp_contract_flag(tmp_path, cfg, strategy):
    arm = require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    d = _generate(cfg, "stm32h743", tmp_path / "g", "--strategy", strategy, *PUBLISHED[cfg])
    for src in [*d.glob("*_mpc.c"), *d.glob("*_speed_pi.c")]:
        assert _fmas(arm, "arm-none-eabi-objdump", M7_VENDOR, src, tmp_path / "x.o", ARM_FMA) == 0, src.name
    mpc = next(d.glob("*_mpc.c"))
    assert _fmas(arm, "arm-none-eabi-objdump", M7_VENDOR, _without_pragma(mpc, tmp_path), tmp_path / "b.o", ARM_FMA) > 0


@pytest.mark.parametrize("cfg,strategy", CASES, ids=["spmsm-s3", "ipmsm-s1", "ttype-63"])
def test_no_fma_on_host_with_fma_flags(tmp_path, cfg, strategy):
    d = _generate(cfg, "host", tmp_path / "g", "--strategy", strategy, *PUBLISHED[cfg])
    for src in [*d.glob("*_mpc.c"), *d.glob("*_speed_pi.c")]:
        assert _fmas("gcc", "objdump", HOST_VENDOR, src, tmp_path / "x.o", X86_FMA) == 0, src.name
    mpc = next(d.glob("*_mpc.c"))
    assert _fmas("gcc", "objdump", HOST_VENDOR, _without_pragma(mpc, tmp_path), tmp_path / "b.o", X86_FMA) > 0


def _preprocess(src, *defs):
    return subprocess.run(["gcc", "-E", "-P", *defs, f"-I{src.parent}", str(src), "-o", "/dev/null"],
                          capture_output=True, text=True)


def test_builds_that_cannot_be_forced_fail_loudly(tmp_path):
    d = _generate(SPMSM, "tms320f28377", tmp_path / "g", "--strategy", "s1")
    for src in [next(d.glob("*_mpc.c")), next(d.glob("*_speed_pi.c"))]:
        # TI cl2000: nothing in the source switches contraction off -> #error unless the user states it
        ti = ("-D__TI_COMPILER_VERSION__=22006000", "-D__TI_STRICT_FP_MODE__=1")
        r = _preprocess(src, *ti)
        assert r.returncode != 0 and "MPCGEN_FP_CONTRACT_OFF" in r.stderr and "--fp_mode=strict" in r.stderr
        assert _preprocess(src, *ti, "-DMPCGEN_FP_CONTRACT_OFF=1").returncode == 0
        r = _preprocess(src, "-D__TI_COMPILER_VERSION__=22006000", "-D__TI_STRICT_FP_MODE__=0",
                        "-DMPCGEN_FP_CONTRACT_OFF=1")
        assert r.returncode != 0 and "--fp_mode=strict" in r.stderr
        # an unknown compiler (neither GCC, clang nor TI) -> #error saying how to build it
        r = _preprocess(src, "-U__GNUC__")
        assert r.returncode != 0 and "unknown compiler" in r.stderr and "MPCGEN_FP_CONTRACT_OFF" in r.stderr
        assert _preprocess(src, "-U__GNUC__", "-DMPCGEN_FP_CONTRACT_OFF=1").returncode == 0
        # -ffast-math breaks the NaN guard and the operation order
        r = subprocess.run(["gcc", "-ffast-math", "-c", str(src), f"-I{src.parent}", "-o", "/dev/null"],
                           capture_output=True, text=True)
        assert r.returncode != 0 and "fast-math" in r.stderr


def test_placement_default_has_no_sections(tmp_path):
    arm = require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    cfg = tmp_path / "default.toml"
    cfg.write_text(SPMSM.read_text() + '\n[target]\nplacement = "default"\n'
                   if "[target]" not in SPMSM.read_text() else
                   SPMSM.read_text().replace("[target]", '[target]\nplacement = "default"'))
    for target in ("stm32h743", "tms320f28377"):
        d = _generate(cfg, target, tmp_path / target, "--strategy", "s1")
        text = next(d.glob("*_mpc.c")).read_text()
        assert "section(" not in text and "CODE_SECTION" not in text
    src = next((tmp_path / "stm32h743").glob("*_mpc.c"))
    subprocess.run([arm, *M7_VENDOR, "-c", str(src), f"-I{src.parent}", "-o", str(tmp_path / "d.o")], check=True)
    sections = subprocess.run(["arm-none-eabi-objdump", "-h", str(tmp_path / "d.o")], capture_output=True,
                              text=True, check=True).stdout
    assert ".itcm_text" not in sections and ".dtcm_rodata" not in sections

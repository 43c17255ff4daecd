"""`mpcgen generate` writes the modulator and an example interrupt routine for each embedded target
(docs/modulator.md), and they compile warning-free: gcc and arm-none-eabi-gcc under the strict flags
for the STM32H743 (with the port's stm32h743_regs.h), gcc under the C28x type model for the
TMS320F28377 (with the port's c28x_regs.h; cl2000 is not installed here).  Every symbol they define
is prefixed; the host target gets neither file; the files are in the manifest's C hash."""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from codegen.cli import main
from codegen.manifest import c_hash_of

from conftest import (
    M7_FLAGS,
    ROOT,
    SPMSM,
    STRICT_WARN,
    TTYPE,
    assert_c28x_clean,
    assert_symbols_prefixed,
    compile_strict,
    require_tool,
)

MODEL_H = ROOT / "tests" / "firmware" / "c28x_type_model.h"
C28X_FLAGS = ("-DMPC_C28X_TYPE_MODEL", "--param=min-pagesize=0", "-include", str(MODEL_H))
PORT = {"stm32h743": (ROOT / "firmware/ports/stm32h743", ROOT / "firmware/ports/cortex-m7"),
        "tms320f28377": (ROOT / "firmware/ports/tms320f28377",)}
CASES = [  # (config, prefix, extra generate arguments)
    (SPMSM, "spmsm", ("--strategy", "s1", "--tables", "published")),  # delay compensation off
    (SPMSM, "spmsm", ("--strategy", "s3", "--tables", "published", "--set", "controller.delay_compensation=true")),
    (SPMSM, "spmsm", ("--strategy", "s1", "--tables", "published", "--number-format", "fixed")),
    (TTYPE, "tlevel", ("--strategy", "mpdtc63")),
    (TTYPE, "tlevel", ("--strategy", "mpdtc27", "--number-format", "fixed")),
]
IDS = ["spmsm-s1", "spmsm-s3-delay", "spmsm-s1-fixed", "tlevel-63", "tlevel-27-fixed"]


def _generate(cfg: Path, target: str, out: Path, extra: tuple[str, ...]) -> list[Path]:
    assert main(["generate", str(cfg), "--target", target, "-o", str(out), "-q", *extra]) == 0
    return sorted(out.iterdir())


def _compile(src: Path, out: Path, target: str, compiler: tuple[str, ...]) -> None:
    incs = [f"-I{out}", *[f"-I{d}" for d in PORT[target]]]
    flags = (*M7_FLAGS,) if compiler[0].startswith("arm") else C28X_FLAGS if target == "tms320f28377" else ()
    r = subprocess.run([*compiler, *STRICT_WARN, *flags, *incs, "-c", str(src), "-o", str(out / "x.o")],
                       capture_output=True, text=True)
    assert r.returncode == 0, f"{src.name} ({' '.join(compiler)}, {target}):\n{r.stderr}"


@pytest.mark.parametrize("target", ["stm32h743", "tms320f28377"])
@pytest.mark.parametrize(("cfg", "prefix", "extra"), CASES, ids=IDS)
def test_modulator_and_example_compile_for_the_target(tmp_path, cfg, prefix, extra, target):
    out = tmp_path / target
    names = {p.name for p in _generate(cfg, target, out, extra)}
    files = [f"{prefix}_modulator.c", f"{prefix}_modulator.h", f"{prefix}_isr_example.c"]
    assert set(files) <= names
    compilers = [("gcc",)] + ([(require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi"),)]
                              if target == "stm32h743" else [])
    for src in (out / files[0], out / files[2]):
        for cc in compilers:
            _compile(src, out, target, cc)
    compile_strict(out / files[0], tmp_path / "mod.o")  # the modulator alone needs no port header
    assert_symbols_prefixed(out / files[0], tmp_path / "m.o", prefix)
    if target == "tms320f28377":
        for f in files:
            assert_c28x_clean(f, (out / f).read_text())
    manifest = json.loads((out / f"{prefix}_manifest.json").read_text())
    assert set(files) <= set(manifest["files"])
    assert manifest["c_hash"] == c_hash_of({n: (out / n).read_bytes() for n in names if n.endswith((".c", ".h"))})


def test_example_symbols_are_prefixed(tmp_path):
    """The example's own functions and counters too (the board's functions it calls are declared only)."""
    out = tmp_path / "m7"
    _generate(TTYPE, "stm32h743", out, ("--strategy", "mpdtc63"))
    obj = tmp_path / "isr.o"
    r = subprocess.run(["gcc", "-std=c99", "-O2", f"-I{out}", *[f"-I{d}" for d in PORT["stm32h743"]], "-c",
                        str(out / "tlevel_isr_example.c"), "-o", str(obj)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    nm = subprocess.run(["nm", str(obj)], capture_output=True, text=True, check=True).stdout
    defined = [ln.split()[-1] for ln in nm.splitlines() if len(ln.split()) >= 2 and ln.split()[-2] in "TtDdBbCc"]
    assert defined and all(n.startswith("tlevel_") for n in defined), defined


def test_host_target_has_no_modulator(tmp_path):
    names = {p.name for p in _generate(SPMSM, "host", tmp_path / "h", ("--strategy", "s1", "--tables", "published"))}
    assert not any("modulator" in n or "isr_example" in n for n in names)


def test_too_short_a_period_for_the_modulator_is_one_config_line(tmp_path, capsys):
    """The T-type modulator needs 12 minimum pulses per period: a shorter controller.dt_s is refused in
    one line naming the file, the field, the value and the bound."""
    rc = main(["generate", str(TTYPE), "--target", "stm32h743", "-o", str(tmp_path / "x"), "-q",
               "--set", "controller.dt_s=1e-5"])
    err = capsys.readouterr().err.strip()
    assert rc != 0 and len(err.splitlines()) == 1, err
    assert "controller.dt_s = 1e-05" in err and "dt_s >= 2.4e-05" in err and str(TTYPE) in err


def test_stm32_example_uses_only_the_port_header_registers():
    """The STM32 example's timer, GPIO and ADC registers are those stm32h743_regs.h defines (RM0433)."""
    regs = (PORT["stm32h743"][0] / "stm32h743_regs.h").read_text()
    for name in ("TIM1_BASE", "TIM8_BASE", "ADC1_BASE", "TIM_BDTR(base)", "TIM_CCR3(base)", "ADC_JDR4(base)",
                 "GPIO_AFRH(base)", "RCC_APB2ENR"):
        assert f"#define {name}" in regs, name

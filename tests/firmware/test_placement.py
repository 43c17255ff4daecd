"""The STM32H743 placement of docs/targets.md links at every optimisation level the IDEs use.

The linker lines the user is told to add to STM32CubeIDE's stock
``STM32H743xx_FLASH.ld`` are read from docs/targets.md (the block after
"Stock CubeIDE"), inserted where the doc says into a model of that stock
script (its MEMORY regions and section order), and the generated step of each
strategy and number format is linked with a minimal reset handler at CubeIDE's
Debug (``-O0 -g3``) and Release (``-Os``) levels and at ``-O2``.  The map check
then reads the image:

- the step, every function it reaches and every library routine they call lie
  in the ITCM region (no branch from the ITCM section leaves it, no long-branch
  veneer into flash, no indirect call);
- the sections fit their regions (the link fails otherwise, with the linker's
  "region overflowed" line in the assertion).

The stack the step needs at each level (``-fstack-usage``, the step's own
frame) is printed with the sizes, for docs/targets.md.
"""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from codegen.manifest import sources

from conftest import CASES, example, require_tool

ROOT = Path(__file__).resolve().parents[2]
M7 = ("-mcpu=cortex-m7", "-mthumb", "-mfpu=fpv5-d16", "-mfloat-abi=hard")
#: CubeIDE's compile flags (every configuration) plus what docs/targets.md requires of any project
CUBE = ("-std=gnu11", "-ffunction-sections", "-fdata-sections", "-Wall", "-fstack-usage", "-fno-math-errno")
LEVELS = {"debug-O0": ("-O0", "-g3"), "release-Os": ("-Os",), "O2": ("-O2",)}
ITCM = (0x00000000, 64 * 1024)
#: a model of STM32CubeIDE's STM32H743xx_FLASH.ld: its MEMORY block and section order; the doc's
#: block goes where the doc says (MPCGEN marks the place)
STOCK_LD = """\
ENTRY(Reset_Handler)
_estack = ORIGIN(RAM_D1) + LENGTH(RAM_D1);
_Min_Heap_Size = 0x200;
_Min_Stack_Size = 0x400;
MEMORY
{
  ITCMRAM (xrw) : ORIGIN = 0x00000000, LENGTH = 64K
  DTCMRAM (xrw) : ORIGIN = 0x20000000, LENGTH = 128K
  RAM_D1  (xrw) : ORIGIN = 0x24000000, LENGTH = 512K
  RAM_D2  (xrw) : ORIGIN = 0x30000000, LENGTH = 288K
  RAM_D3  (xrw) : ORIGIN = 0x38000000, LENGTH = 64K
  FLASH   (rx)  : ORIGIN = 0x08000000, LENGTH = 2048K
}
SECTIONS
{
  .isr_vector : { . = ALIGN(4); KEEP(*(.isr_vector)) . = ALIGN(4); } >FLASH
MPCGEN
  .text : { . = ALIGN(4); *(.text) *(.text*) *(.glue_7) *(.glue_7t) *(.eh_frame)
            KEEP (*(.init)) KEEP (*(.fini)) . = ALIGN(4); _etext = .; } >FLASH
  .rodata : { . = ALIGN(4); *(.rodata) *(.rodata*) . = ALIGN(4); } >FLASH
  .ARM.extab : { *(.ARM.extab* .gnu.linkonce.armextab.*) } >FLASH
  .ARM : { __exidx_start = .; *(.ARM.exidx*) __exidx_end = .; } >FLASH
  .preinit_array : { KEEP (*(.preinit_array*)) } >FLASH
  .init_array : { KEEP (*(SORT(.init_array.*))) KEEP (*(.init_array*)) } >FLASH
  .fini_array : { KEEP (*(SORT(.fini_array.*))) KEEP (*(.fini_array*)) } >FLASH
  _sidata = LOADADDR(.data);
  .data : { . = ALIGN(4); _sdata = .; *(.data) *(.data*) . = ALIGN(4); _edata = .; } >RAM_D1 AT> FLASH
  .bss : { _sbss = .; *(.bss) *(.bss*) *(COMMON) . = ALIGN(4); _ebss = .; } >RAM_D1
  ._user_heap_stack : { . = ALIGN(8); PROVIDE ( end = . ); PROVIDE ( _end = . );
                        . = . + _Min_Heap_Size; . = . + _Min_Stack_Size; . = ALIGN(8); } >RAM_D1
  /DISCARD/ : { libc.a ( * ) libm.a ( * ) libgcc.a ( * ) }
  .ARM.attributes 0 : { *(.ARM.attributes) }
}
"""
MAIN_C = """\
#include "{p}_mpc.h"
extern unsigned int _estack;
static {p}_input_t in;
static {p}_output_t out;
void Reset_Handler(void);
__attribute__((section(".isr_vector"), used))
static const void *const vectors[2] = {{&_estack, (const void *)Reset_Handler}};
void Reset_Handler(void)
{{
    for (;;) {{
        {p}_step(&in, &out);
    }}
}}
"""
#: a direct branch in objdump's listing: mnemonic (b, bl, b<cc>, cbz, cbnz, with .w/.n) and target
BRANCH = re.compile(r"^\s*([0-9a-f]+):\s+(?:[0-9a-f]{4}\s?)+\s+(b|bl|b[a-z]{2}|cbn?z)(?:\.[wn])?\s+"
                    r"(?:r\d+,\s*)?([0-9a-f]+)\b", re.M)
#: an indirect call (blx rN); bx lr (a return) is not one
INDIRECT = re.compile(r"^\s*[0-9a-f]+:.*\s(blx\s+r\d+|bx\s+r(?!14)\d+)", re.M)


def docs_block() -> str:
    """The linker lines docs/targets.md gives for the stock CubeIDE script (the first code block after
    "Stock CubeIDE")."""
    text = (ROOT / "docs" / "targets.md").read_text()
    at = text.index("Stock CubeIDE")
    m = re.compile(r"^```\n(.*?)^```", re.M | re.S).search(text, at)
    assert m is not None, "docs/targets.md: no code block after 'Stock CubeIDE'"
    return m.group(1)


def _link(work: Path, strategy: str, number_format: str, level: tuple[str, ...]) -> tuple[Path, str]:
    """The generated step (stm32h743) and a reset handler, built and linked with the doc's lines."""
    arm = require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi libnewlib-arm-none-eabi")
    config = dict((s, c) for c, s in CASES)[strategy]
    m, t = example(config, strategy, number_format)
    for name, text in sources(m, "stm32h743", t).items():
        (work / name).write_text(text)
    p = m.prefix
    (work / "main.c").write_text(MAIN_C.format(p=p))
    (work / "stock.ld").write_text(STOCK_LD.replace("MPCGEN", docs_block().replace("<prefix>", p)))
    flags = [arm, *M7, *CUBE, *level]
    for src in (f"{p}_mpc.c", "main.c"):
        r = subprocess.run([*flags, f"-I{work}", "-c", src, "-o", src[:-2] + ".o"], cwd=work,
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
    r = subprocess.run([*flags, "--specs=nano.specs", "-nostartfiles", "-Wl,--gc-sections", "-T", "stock.ld",
                        "-Wl,-Map=image.map", "main.o", f"{p}_mpc.o", "-lm", "-o", "image.elf"],
                       cwd=work, capture_output=True, text=True)
    assert r.returncode == 0, f"{strategy} {number_format} {' '.join(level)}: the doc's lines do not link:\n{r.stderr}"
    return work / "image.elf", p


def _sections(elf: Path) -> dict[str, tuple[int, int]]:
    """Output section -> (address, size)."""
    out = subprocess.run(["arm-none-eabi-size", "-A", str(elf)], capture_output=True, text=True, check=True).stdout
    return {f[0]: (int(f[2]), int(f[1])) for f in (line.split() for line in out.splitlines())
            if len(f) == 3 and f[0].startswith(".") and f[1].isdigit()}


def _symbols(elf: Path) -> dict[str, int]:
    out = subprocess.run(["arm-none-eabi-nm", str(elf)], capture_output=True, text=True, check=True).stdout
    return {f[2]: int(f[0], 16) for f in (line.split() for line in out.splitlines()) if len(f) == 3}


def map_check(elf: Path, prefix: str) -> list[str]:
    """What leaves the ITCM: branches out of it, veneers, indirect calls, a step outside it."""
    sec = _sections(elf)
    start, size = sec[".itcm_text"]
    lo, hi = ITCM
    problems = []
    if not (lo <= start and start + size <= lo + hi):
        problems.append(f".itcm_text at {start:#x}+{size} is not within ITCMRAM")
    syms = _symbols(elf)
    step = syms.get(f"{prefix}_step")
    if step is None or not (start <= step < start + size):
        problems.append(f"{prefix}_step at {step!r} is not in .itcm_text")
    # a veneer in ITCM is a long branch out of it (the reset handler's veneer into ITCM is in flash)
    problems += [f"long-branch veneer {n} at {a:#x}" for n, a in syms.items()
                 if "veneer" in n and start <= a < start + size]
    listing = subprocess.run(["arm-none-eabi-objdump", "-d", "-j", ".itcm_text", str(elf)],
                             capture_output=True, text=True, check=True).stdout
    for at, op, target in BRANCH.findall(listing):
        if not (start <= int(target, 16) < start + size):
            problems.append(f"{op} at {at} to {target}: outside .itcm_text")
    problems += [f"indirect call {m}" for m in INDIRECT.findall(listing)]
    return problems


def _stack(work: Path, prefix: str) -> int:
    """The step's own frame in bytes (-fstack-usage)."""
    su = (work / f"{prefix}_mpc.su").read_text()
    m = re.search(rf":{prefix}_step\t(\d+)", su)
    assert m is not None, su
    return int(m.group(1))


QUICK = {("s1", "float32", "debug-O0"), ("mpdtc63", "float32", "debug-O0"), ("mpdtc63", "fixed", "debug-O0"),
         ("mpdtc63", "fixed", "release-Os"), ("s1", "fixed", "release-Os"), ("mpdtc27", "float32", "O2")}


def _cases() -> list[object]:
    out = []
    for _, s in CASES:
        for fmt in ("float32", "fixed"):
            for lv in LEVELS:
                marks = () if (s, fmt, lv) in QUICK else (pytest.mark.slow,)
                out.append(pytest.param(s, fmt, lv, id=f"{s}-{fmt}-{lv}", marks=marks))
    return out


@pytest.mark.parametrize(("strategy", "number_format", "level"), _cases())
def test_docs_placement_links_and_stays_in_itcm(tmp_path, strategy, number_format, level):
    elf, prefix = _link(tmp_path, strategy, number_format, LEVELS[level])
    problems = map_check(elf, prefix)
    sec = _sections(elf)
    print(f"{strategy} {number_format} {level}: .itcm_text {sec['.itcm_text'][1]} B, "
          f".dtcm_rodata {sec['.dtcm_rodata'][1]} B, step frame {_stack(tmp_path, prefix)} B")
    assert not problems, "\n".join(problems[:20])


def test_map_check_sees_a_call_into_flash(tmp_path):
    """Control: the stock script without the doc's file line leaves the helpers in flash, and the map
    check reports the step's calls to them."""
    block = docs_block()
    kept = "\n".join(line for line in block.splitlines() if "_mpc.o(.text" not in line)
    assert kept != block, "the doc's block has no line placing the step's object file"
    elf, prefix = _link(tmp_path, "s1", "fixed", LEVELS["release-Os"])
    (tmp_path / "stock.ld").write_text(STOCK_LD.replace("MPCGEN", kept.replace("<prefix>", prefix)))
    r = subprocess.run([require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi"), *M7, "--specs=nano.specs",
                        "-nostartfiles", "-Wl,--gc-sections", "-T", "stock.ld", "main.o", f"{prefix}_mpc.o",
                        "-lm", "-o", "control.elf"], cwd=tmp_path, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert any("outside .itcm_text" in p or "veneer" in p for p in map_check(tmp_path / "control.elf", prefix))

"""Shared fixtures: example configs, tables per strategy, host builds, strict C checks.

Test modules import these names with ``from conftest import ...``: pytest puts
this folder on ``sys.path`` (rootdir conftest, default "prepend" import mode),
so the tests in sub-folders (tests/stages, tests/topologies/<name>) see it too.
The folders under tests/topologies are packages (``__init__.py``), so their test
modules may share basenames with each other.
"""
from __future__ import annotations

import functools
import re
import shutil
import subprocess
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import pytest

from codegen.config import load_config
from codegen.model import Model

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
SPMSM = EXAMPLES / "seed001_spmsm.toml"
IPMSM = EXAMPLES / "seed001_ipmsm.toml"
#: the T-type example (its file name and C prefix "tlevel" are what user commands name)
TTYPE = EXAMPLES / "seed000_tlevel.toml"
TWO_LEVEL = ("conventional", "s1", "s2", "s3")
TTYPE_STRATEGIES = ("mpdtc27", "mpdtc63")

#: the strict warning set every generated C file must pass (host and target compilers)
STRICT_WARN = ("-std=c99", "-O2", "-Wall", "-Wextra", "-Wconversion", "-Wdouble-promotion", "-Werror",
               "-ffp-contract=off")
#: Cortex-M7 (STM32H743) code generation flags
M7_FLAGS = ("-mcpu=cortex-m7", "-mthumb", "-mfpu=fpv5-d16", "-mfloat-abi=hard", "-fno-math-errno")
#: C spellings the C28x profile must not use (no 8-bit types, no double)
C28X_FORBIDDEN = ("int8_t", "uint8_t", "double", "char ")


#: (example, strategy) of every strategy of both topologies (firmware and HIL tests)
CASES = [("spmsm", s) for s in TWO_LEVEL] + [("tlevel", s) for s in TTYPE_STRATEGIES]
CASE_IDS = [f"{c}-{s}" for c, s in CASES]


@functools.cache
def example(config: str, strategy: str, number_format: str | None = None) -> tuple[Model, Any]:
    """An example ("spmsm" or "tlevel") with ``strategy`` and its derived tables (two-level: the
    published switch tables, so that no training run is needed); ``number_format``: override
    ``controller.number_format``."""
    from codegen.topology import topology_of

    overrides: dict[str, object] = {"controller.strategy": strategy}
    if number_format is not None:
        overrides["controller.number_format"] = number_format
    if config == "spmsm":
        overrides["controller.tables"] = "published"
    m = load_config(SPMSM if config == "spmsm" else TTYPE, overrides)
    return m, topology_of(m).derive(m)


def model_for(path: Path, **overrides: object) -> Model:
    """Load an example with ``controller.<key>`` overrides."""
    return load_config(path, {f"controller.{k}": v for k, v in overrides.items()})


def require_tool(name: str, package: str) -> str:
    """Path of a required tool; fail (not skip) when it is missing: CI installs it."""
    path = shutil.which(name)
    if path is None:
        pytest.fail(f"{name} not found: install the Debian package {package} (scripts/bootstrap.sh does)")
    return path


def compile_strict(src: Path, obj: Path, compiler: Iterable[str] = ("gcc",)) -> None:
    """Compile ``src`` to ``obj`` under the strict warning set; fail with the compiler's messages."""
    r = subprocess.run([*compiler, *STRICT_WARN, "-c", str(src), "-o", str(obj)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def compile_m7(src: Path, obj: Path) -> None:
    """Compile ``src`` strictly for the Cortex-M7 and check the ITCM/DTCM placement sections."""
    arm = require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    compile_strict(src, obj, (arm, *M7_FLAGS))
    sections = subprocess.run(["arm-none-eabi-objdump", "-h", str(obj)], capture_output=True, text=True).stdout
    assert ".itcm_text" in sections and ".dtcm_rodata" in sections


def check_target_c(out: Path, work: Path, target: str, *, int16_model: bool = False) -> None:
    """The step generated into ``out`` for ``target``, compiled as that target asks: gcc under the
    strict warnings (every target), arm-none-eabi-gcc (stm32h743), the C28x text rules for the .c and
    .h (tms320f28377) and, with ``int16_model``, clang's MSP430 target, whose int is 16 bits like the
    C28x's."""
    src = next(out.glob("*_mpc.c"))
    compile_strict(src, work / f"{target}.o")
    if target == "stm32h743":
        compile_m7(src, work / "m7.o")
    if target == "tms320f28377":
        for f in (src, next(out.glob("*_mpc.h"))):
            assert_c28x_clean(f.name, f.read_text())
        if int16_model:
            r = subprocess.run([require_tool("clang", "clang"), "--target=msp430", "-ffreestanding", "-fsyntax-only",
                                *STRICT_WARN, f"-I{out}", str(src)], capture_output=True, text=True)
            assert r.returncode == 0, r.stderr


def assert_c28x_clean(name: str, text: str) -> None:
    """The C code of ``text`` (comments removed) uses no spelling the C28x profile forbids."""
    code = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    for bad in C28X_FORBIDDEN:
        assert bad not in code, f"{name} uses {bad}"


def assert_symbols_prefixed(src: Path, obj: Path, prefix: str) -> None:
    """Every symbol ``src`` defines (text, data, rodata, bss) starts with ``prefix_``."""
    subprocess.run(["gcc", "-std=c99", "-O2", "-c", str(src), "-o", str(obj)], check=True)
    nm = subprocess.run(["nm", str(obj)], capture_output=True, text=True, check=True).stdout
    names = [p[-1] for p in (line.split() for line in nm.splitlines())
             if len(p) >= 2 and p[-2] in "TtDdRrBb" and not p[-1].startswith(".")]
    assert names, f"{src.name} defines no symbol"
    bad = [n for n in names if not n.startswith(prefix + "_")]
    assert not bad, bad


# ---------------------------------------------------------------- serial HIL (tests/hil)
def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--hil-port", default=None, metavar="URL",
                     help="serial URL of a real board for the HIL tests (default: the virtual board); the board "
                          "must be flashed from the config each test names")
    parser.addoption("--hil-board", default=None, metavar="NAME", choices=("virtual", "qemu-m7"),
                     help="board the harness starts for the HIL tests: virtual (default) or qemu-m7")


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "board: needs a board speaking the serial HIL protocol "
                                       "(the virtual board unless --hil-port URL)")


@pytest.fixture
def board(request: pytest.FixtureRequest):
    """``board(model, tables)``: a context manager giving a link to a board running ``model``'s
    controller: the virtual board (built and started by the harness), the emulated one with
    ``--hil-board qemu-m7``, or a real board with ``--hil-port URL``."""
    from hil.boards import open_board

    port = request.config.getoption("--hil-port")
    name = request.config.getoption("--hil-board")

    def opener(model: Model, tables: object, **kw: object):
        if port is None and name is not None:
            kw.setdefault("board", name)
        return open_board(model, tables, port, **kw)  # type: ignore[arg-type]

    opener.port = port  # type: ignore[attr-defined]
    return opener

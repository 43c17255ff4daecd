"""The TMS320F28377 project: its C compiles on the host under the C28x type model.

cl2000 is not installable here, so every C file of the project (generated
controller, test data, runtime, port) is compiled with gcc, the strict
-Werror flags, -DMPC_C28X_TYPE_MODEL and the forced include
c28x_type_model.h (size checks; double/int8_t/uint8_t poisoned); and the
sources are searched for 8-bit types, double and byte-pointer casts.
"""
from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from codegen.hostbuild import STRICT_CFLAGS
from codegen.stages import firmware as firmware

from fw_support import example

MODEL_H = Path(__file__).resolve().parent / "c28x_type_model.h"
# --param=min-pagesize=0: the registers live at small addresses (CpuTimer1 at
# 0x0C08), which GCC's host null-page heuristic would otherwise flag.
MODEL_FLAGS = ("-DMPC_C28X_TYPE_MODEL", "--param=min-pagesize=0", "-include", str(MODEL_H))
FORBIDDEN = {
    "int8_t": re.compile(r"\bu?int8_t\b"),
    "double": re.compile(r"\bdouble\b"),
    "byte-pointer cast": re.compile(r"\(\s*(const\s+)?(volatile\s+)?(unsigned\s+|signed\s+)?char\s*\*\s*\)"),
    "uint8_t pointer": re.compile(r"\bu?int8_t\s*\*"),
}


def _code(text: str) -> str:
    """C source without comments and string literals."""
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    text = re.sub(r"//[^\n]*", " ", text)
    return re.sub(r'"(\\.|[^"\\])*"', '""', text)


@pytest.fixture(scope="module")
def project(tmp_path_factory) -> Path:
    m, t = example("spmsm", "s3")
    out = tmp_path_factory.mktemp("c28x")
    firmware.write_firmware_project(m, t, "tms320f28377", out, 10_000)
    return out


def _sources(project: Path) -> list[Path]:
    return sorted([*project.glob("gen/*.c"), *project.glob("firmware/runtime/*.c"),
                   *project.glob("firmware/ports/tms320f28377/*.c")])


def test_c28x_project_compiles_under_type_model(project):
    incs = [f"-I{project / d}" for d in ("gen", "firmware/runtime", "firmware/ports/tms320f28377")]
    srcs = _sources(project)
    assert any(p.name == "board.c" for p in srcs) and any(p.name.endswith("_mpc.c") for p in srcs)
    for src in srcs:
        r = subprocess.run(["gcc", *STRICT_CFLAGS, *MODEL_FLAGS, *incs, "-c", str(src), "-o", "/dev/null"],
                           capture_output=True, text=True)
        assert r.returncode == 0, f"{src.name}:\n{r.stderr}"
    # compact expected outputs: the full records would not fit the F28377S flash
    data = (project / "gen/mpc_selftest_data.c").read_text()
    assert "selftest_expected_crc[10000]" in data and "TI.ramfunc" in (project / "gen/spmsm_mpc.c").read_text()


def test_c28x_type_model_rejects_forbidden_types(tmp_path):
    for bad in ("double x;", "uint8_t b;", "int8_t c;"):
        src = tmp_path / "bad.c"
        src.write_text(f"{bad}\n")
        r = subprocess.run(["gcc", *STRICT_CFLAGS, *MODEL_FLAGS, "-c", str(src), "-o", "/dev/null"],
                           capture_output=True, text=True)
        assert r.returncode != 0 and "poisoned" in r.stderr, bad


def test_c28x_sources_have_no_8bit_types_double_or_byte_pointers(project):
    files = [*_sources(project), *project.glob("gen/*.h"), *project.glob("firmware/runtime/*.h"),
             *project.glob("firmware/ports/tms320f28377/*.h")]
    for path in files:
        code = _code(path.read_text())
        for what, rx in FORBIDDEN.items():
            assert not rx.search(code), f"{path.name}: {what}: {rx.search(code).group(0)!r}"


def test_c28x_build_script_without_cl2000(project):
    if shutil.which("cl2000") is not None:  # a machine with TI's tools builds for real
        assert firmware.build_firmware(project, "tms320f28377").image.exists()
        return
    with pytest.raises(firmware.ToolchainError) as err:
        firmware.build_firmware(project, "tms320f28377")
    assert "cl2000" in str(err.value) and "\n" not in str(err.value)
    r = subprocess.run(["make", "-C", str(project)], capture_output=True, text=True)
    assert r.returncode != 0 and "cl2000 not found" in r.stderr
    for name in ("f28377s.cmd", "build.sh", "codestart.c", "c28x_regs.h", "board.c"):
        assert (project / "firmware/ports/tms320f28377" / name).is_file()

"""Every value-changing compiler flag is neutralised or refused by the generated float32 step
(targets.md "Compiler flags").

The float32 step of every strategy is compiled under IDE-like flag sets
(CubeIDE Debug and Release, -O2, -O3, and the value-changing ones) by gcc and
clang for the host and by arm-none-eabi-gcc and clang for the Cortex-M7, and
then either runs the firmware self-test (10 000 guard and random states plus
the 2 000-state bench trajectory, each output compared bit for bit with the
Python reference's, on the host or on the emulated Cortex-M7 in QEMU) with no
mismatch, or stops at an #error naming the flag.  A silent difference fails.

Only the step's object is compiled with the flag set; the rest of the
firmware (runtime, board port, embedded data) keeps the project's own flags
and the program is linked without them (the link-time part of
-funsafe-math-optimizations is test_crtfastmath_link_changes_results).  The
controls compile the same step without its pragmas under the same flags and
see mismatches: the self-test does catch what the flags change.
"""
from __future__ import annotations

import functools
import os
import re
import subprocess
from pathlib import Path

import pytest

from codegen.cli import main
from codegen.stages import emulate, firmware

from conftest import CASES, SPMSM, example, require_tool

#: IDE-like flag sets (on top of -std=gnu11 and the project's warnings): CubeIDE Debug and Release,
#: -O2, -O3, then the flags that change float results unless the file neutralises them
FLAG_SETS: dict[str, tuple[str, ...]] = {
    "debug-O0-g3": ("-O0", "-g3"),
    "release-Os": ("-Os",),
    "O2": ("-O2",),
    "O3": ("-O3",),
    "unsafe-math": ("-O2", "-funsafe-math-optimizations"),
    "assoc-math": ("-O2", "-fassociative-math", "-fno-signed-zeros", "-fno-trapping-math"),
    "reciprocal-math": ("-O2", "-freciprocal-math"),
    "fp-contract-fast": ("-O2", "-ffp-contract=fast"),
    "fast-math": ("-O2", "-ffast-math"),
}
#: flag sets the file refuses per compiler family: the flag the #error names
REFUSED = {"gcc": {"unsafe-math": "-funsafe-math-optimizations", "fast-math": "-ffast-math"},
           "clang": {"fast-math": "-ffast-math"}}
WARN = ("-std=gnu11", "-Wall", "-Wextra", "-Wconversion", "-Wdouble-promotion", "-Werror")
M7 = ("-mcpu=cortex-m7", "-mthumb", "-mfpu=fpv5-d16", "-mfloat-abi=hard")
#: the guard's pragmas (templates/numfmt/float32.j2 strict_fp), removed for the controls
PRAGMAS = re.compile(r"^#pragma (GCC optimize|STDC FP_CONTRACT|clang fp).*$", re.M)
#: fused multiply-add instructions in objdump's listing: Arm VFMA/VFMS/VFNMA/VFNMS, x86 VFMADD...
FMA = re.compile(r"\bvfn?m[as]\.f\d+\b|\bvfn?m(?:add|sub)\w*")
STRATEGIES = [s for _, s in CASES]
#: the flag sets that change float32 results unless the file neutralises or refuses them
VALUE_CHANGING = ("unsafe-math", "assoc-math", "reciprocal-math", "fp-contract-fast", "fast-math")
#: the strategies whose value-changing cells run in the default (not slow) selection
QUICK = ("s1", "mpdtc63")
CONFIG = dict((s, c) for c, s in CASES)


@functools.cache
def _host_has_fma() -> bool:
    try:
        return re.search(r"^flags\s*:.*\bfma\b", Path("/proc/cpuinfo").read_text(), re.M) is not None
    except OSError:
        return False


@functools.cache
def _arm_sysroot() -> str:
    """newlib's folder of arm-none-eabi-gcc (the one with include/ and lib/), for clang's Arm builds."""
    arm = require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi libnewlib-arm-none-eabi")
    libc = Path(subprocess.run([arm, *M7, "-print-file-name=libc.a"], capture_output=True, text=True,
                               check=True).stdout.strip())
    for d in libc.parents:
        if (d / "include" / "string.h").is_file():
            return str(d)
    pytest.fail(f"newlib headers not found above {libc}: install libnewlib-arm-none-eabi")


def _compiler(name: str) -> tuple[str, str, list[str]]:
    """(board, family, command and target flags) of a compiler of the matrix.  The host builds
    use -mfma where the CPU has FMA, so that a contracted product would show."""
    fma = ["-mfma"] if _host_has_fma() else []
    if name == "gcc":
        return "host", "gcc", ["gcc", *fma]
    if name == "clang":
        return "host", "clang", [require_tool("clang", "clang"), *fma]
    if name == "arm-none-eabi-gcc":
        return "qemu-m7", "gcc", [require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi"), *M7]
    return "qemu-m7", "clang", [require_tool("clang", "clang"), "--target=thumbv7em-none-eabihf", *M7,
                                f"--sysroot={_arm_sysroot()}"]


COMPILERS = ["gcc", "clang", "arm-none-eabi-gcc", "clang-m7"]


@pytest.fixture(scope="module")
def projects(tmp_path_factory):
    """A built firmware project per (board, strategy), written once; each case recompiles only
    the step's object."""
    cache: dict[tuple[str, str], tuple[Path, str]] = {}

    def get(board: str, strategy: str) -> tuple[Path, str]:
        if (board, strategy) not in cache:
            m, t = example(CONFIG[strategy], strategy)
            out = tmp_path_factory.mktemp(f"flags_{board}_{strategy}")
            firmware.write_firmware_project(m, t, board, out, 10_000)
            firmware.build_firmware(out, board)
            cache[board, strategy] = out, m.prefix
        return cache[board, strategy]

    return get


def _run(project: Path, board: str, cmd: list[str], src: Path, prefix: str) -> tuple[dict[str, tuple[int, int]], int]:
    """Compile ``src`` as the step's object with ``cmd``, relink, run the self-test: ({set: (n,
    mismatches)}, VFMA/VFMADD count of the object)."""
    obj = project / "build" / "gen" / f"{prefix}_mpc.o"
    subprocess.run([*cmd, f"-I{project / 'gen'}", "-c", str(src), "-o", str(obj)], check=True,
                   capture_output=True, text=True)
    build = firmware.build_firmware(project, board)  # relinks with the new object
    assert f"-o build/gen/{prefix}_mpc.o" not in build.log, "make rebuilt the step's object"
    objdump = "objdump" if board == "host" else "arm-none-eabi-objdump"
    fmas = len(FMA.findall(subprocess.run([objdump, "-d", str(obj)], capture_output=True, text=True,
                                          check=True).stdout))
    if board == "host":
        text = subprocess.run([str(build.image)], capture_output=True, text=True, timeout=300).stdout
    else:
        run = emulate.run_qemu(build.image, timeout_s=300)
        assert not run.timed_out, run.uart[-500:]
        text = run.uart
    sets = {s: (int(n), int(bad)) for s, n, bad in re.findall(r"^SUMMARY set=(\w+) n=(\d+) mismatches=(\d+)",
                                                              text, re.M)}
    assert set(sets) == {"selftest", "bench"}, text[-2000:]
    return sets, fmas


def _outcome(compiler: str, strategy: str, projects, flag_set: str, *, strip: bool = False):
    """"error: <message>" or ({set: (n, mismatches)}, FMA count) of one cell of the matrix."""
    board, _, cc = _compiler(compiler)
    project, prefix = projects(board, strategy)
    src = project / "gen" / f"{prefix}_mpc.c"
    if strip:
        bare = project / "gen" / f"bare_{prefix}_mpc.c"
        text, n = PRAGMAS.subn("", src.read_text())
        assert n >= 1
        bare.write_text(text)
        src = bare
    cmd = [*cc, *WARN, *FLAG_SETS[flag_set]]
    try:
        return _run(project, board, cmd, src, prefix)
    except subprocess.CalledProcessError as e:
        return f"error: {e.stderr}"


def _check_cell(compiler: str, strategy: str, projects, flag_set: str) -> None:
    family = _compiler(compiler)[1]
    got = _outcome(compiler, strategy, projects, flag_set)
    refused = REFUSED[family].get(flag_set)
    if refused is not None:
        assert isinstance(got, str) and "#error" in got and refused in got, (compiler, strategy, flag_set, got)
        return
    assert not isinstance(got, str), (compiler, strategy, flag_set, got)
    sets, fmas = got
    assert sets == {"selftest": (10_000, 0), "bench": (2_000, 0)}, (compiler, strategy, flag_set, sets)
    assert fmas == 0, (compiler, strategy, flag_set, fmas)


@pytest.mark.parametrize("strategy", QUICK)
@pytest.mark.parametrize("compiler", COMPILERS)
def test_value_changing_flags_neutralised_or_refused(projects, compiler, strategy):
    """The value-changing flag sets, on one strategy per topology."""
    for flag_set in VALUE_CHANGING:
        _check_cell(compiler, strategy, projects, flag_set)


@pytest.mark.slow
@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize("compiler", COMPILERS)
def test_flag_matrix(projects, compiler, strategy):
    """The whole matrix: every flag set, every strategy, every compiler."""
    for flag_set in FLAG_SETS:
        if strategy in QUICK and flag_set in VALUE_CHANGING:
            continue  # test_value_changing_flags_neutralised_or_refused
        _check_cell(compiler, strategy, projects, flag_set)


#: (compiler, strategy, flag set) whose pragma-free step differs from the reference (the controls)
CONTROLS = [("gcc", "s1", "assoc-math"), ("gcc", "mpdtc63", "reciprocal-math"),
            ("arm-none-eabi-gcc", "mpdtc27", "assoc-math"), ("clang", "s1", "assoc-math"),
            ("clang-m7", "mpdtc63", "fp-contract-fast"), ("clang-m7", "s3", "unsafe-math")]


@pytest.mark.parametrize("compiler,strategy,flag_set", CONTROLS, ids=["-".join(c) for c in CONTROLS])
def test_without_the_pragmas_the_flags_change_results(projects, compiler, strategy, flag_set):
    got = _outcome(compiler, strategy, projects, flag_set, strip=True)
    assert not isinstance(got, str), got
    sets, fmas = got
    assert sets["selftest"][1] + sets["bench"][1] > 0, (compiler, strategy, flag_set, sets)
    if flag_set == "fp-contract-fast":
        assert fmas > 0


def test_crtfastmath_link_changes_results(projects, tmp_path):
    """Why GCC's -funsafe-math-optimizations is refused, not neutralised: given to the link (as
    CMake and most Makefiles do), it adds crtfastmath.o, which turns on flush-to-zero for the
    whole program before main; a step compiled strictly then differs on the self-test's subnormal
    states.  Linked without it, the same objects pass."""
    project, prefix = projects("host", "mpdtc27")
    obj = project / "build" / "gen" / f"{prefix}_mpc.o"  # the step compiled strictly (a case may have left another)
    subprocess.run(["gcc", *WARN, "-O2", f"-I{project / 'gen'}", "-c", str(project / "gen" / f"{prefix}_mpc.c"),
                    "-o", str(obj)], check=True)
    objs = sorted(str(p) for p in (project / "build").rglob("*.o"))
    counts = {}
    for name, flags in (("plain", ()), ("crtfastmath", ("-funsafe-math-optimizations",))):
        exe = tmp_path / name
        r = subprocess.run(["gcc", *flags, *objs, "-lm", "-o", str(exe)], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        text = subprocess.run([str(exe)], capture_output=True, text=True, timeout=300).stdout
        counts[name] = sum(int(b) for b in re.findall(r"^SUMMARY set=\w+ n=\d+ mismatches=(\d+)", text, re.M))
    assert counts["plain"] == 0, counts
    assert counts["crtfastmath"] > 0, f"no flush-to-zero effect (does this gcc link crtfastmath.o?): {counts}"


def _preprocess(cc: list[str], src: Path, *flags: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*cc, *flags, "-E", "-P", f"-I{src.parent}", str(src), "-o", os.devnull],
                          capture_output=True, text=True)


def test_refusals_name_the_flag(projects):
    """The #error checks on their own (preprocessor only), in both float32 files of a project: each
    names its flag; the four flags of -funsafe-math-optimizations given one by one are refused too;
    clang older than 12 (Apple clang 13) is refused, since its pragmas are missing."""
    project, prefix = projects("host", "s1")
    gen = project / "speed_pi"
    assert main(["generate", str(SPMSM), "--strategy", "s1", "--tables", "published", "-o", str(gen), "-q"]) == 0
    clang = [require_tool("clang", "clang")]
    for src in (project / "gen" / f"{prefix}_mpc.c", gen / f"{prefix}_speed_pi.c"):
        for cc in (["gcc"], clang):
            assert _preprocess(cc, src, "-O2").returncode == 0
            for flags, named in ((("-ffast-math",), "-ffast-math"), (("-Ofast",), "-Ofast"),
                                 (("-ffinite-math-only",), "-ffinite-math-only")):
                r = _preprocess(cc, src, *flags)
                assert r.returncode != 0 and "#error" in r.stderr and named in r.stderr, (cc, flags, r.stderr)
        for flags in (("-funsafe-math-optimizations",),
                      ("-fassociative-math", "-freciprocal-math", "-fno-signed-zeros", "-fno-trapping-math")):
            r = _preprocess(["gcc"], src, *flags)
            assert r.returncode != 0 and "-funsafe-math-optimizations" in r.stderr, (flags, r.stderr)
        for flags in (("-freciprocal-math",), ("-fassociative-math", "-fno-signed-zeros", "-fno-trapping-math")):
            assert _preprocess(["gcc"], src, *flags).returncode == 0, flags  # neutralised by the pragma
        old = ("-U__clang_major__", "-D__clang_major__=11")
        r = _preprocess(clang, src, *old)
        assert r.returncode != 0 and "clang 12 or later" in r.stderr
        apple = ("-D__apple_build_version__=13000000", "-U__clang_major__")
        assert _preprocess(clang, src, *apple, "-D__clang_major__=12").returncode != 0
        assert _preprocess(clang, src, *apple, "-D__clang_major__=13").returncode == 0

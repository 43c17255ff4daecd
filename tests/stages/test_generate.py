"""`mpcgen generate`: deterministic, warning-free under the strict flags on gcc and arm-none-eabi-gcc."""
from __future__ import annotations

import pytest

from codegen.cli import main

from conftest import (
    IPMSM,
    SPMSM,
    TWO_LEVEL,
    assert_c28x_clean,
    assert_symbols_prefixed,
    check_target_c,
    compile_strict,
)


def _generate(cfg, target, out, *extra):
    assert main(["generate", str(cfg), "--target", target, "-o", str(out), "-q", *extra]) == 0
    return sorted(out.iterdir())


@pytest.mark.parametrize("cfg", [SPMSM, IPMSM], ids=["spmsm", "ipmsm"])
@pytest.mark.parametrize("strategy", TWO_LEVEL)
def test_compiles_strict_for_every_target(tmp_path, cfg, strategy):
    for target in ("stm32h743", "tms320f28377", "host"):
        out = tmp_path / target
        files = _generate(cfg, target, out, "--strategy", strategy, "--tables", "published")
        check_target_c(out, tmp_path, target)
        pi = [f for f in files if f.name.endswith("_speed_pi.c")][0]
        compile_strict(pi, tmp_path / "pi.o")


def test_generate_twice_is_byte_identical(tmp_path):
    """s3 with the tables trained on the example's scenario (the file `mpcgen tables --derive` writes)."""
    trained = tmp_path / "spmsm_tables.json"
    assert main(["tables", str(SPMSM), "--derive", "-o", str(trained), "-q"]) == 0
    a = _generate(SPMSM, "stm32h743", tmp_path / "a", "--strategy", "s3", "--set", f"controller.tables_file={trained}")
    b = _generate(SPMSM, "stm32h743", tmp_path / "b", "--strategy", "s3", "--set", f"controller.tables_file={trained}")
    assert [p.name for p in a] == [p.name for p in b]
    for pa, pb in zip(a, b):
        assert pa.read_bytes() == pb.read_bytes(), pa.name


def test_c28x_profile_uses_no_8bit_types_and_no_double(tmp_path):
    for strategy in TWO_LEVEL:
        for f in _generate(SPMSM, "tms320f28377", tmp_path / strategy, "--strategy", strategy, "--tables", "published"):
            if f.suffix in (".c", ".h"):
                assert_c28x_clean(f.name, f.read_text())


def test_every_symbol_is_prefixed(tmp_path):
    files = _generate(IPMSM, "host", tmp_path / "h", "--strategy", "s2", "--tables", "published")
    src = [f for f in files if f.name.endswith("_mpc.c")][0]
    assert_symbols_prefixed(src, tmp_path / "x.o", "ipmsm")


def test_comments_cite_equations_and_spec(tmp_path):
    files = _generate(SPMSM, "host", tmp_path / "h", "--strategy", "s3", "--tables", "published")
    text = [f for f in files if f.name.endswith("_mpc.c")][0].read_text()
    for needle in ("mptc-two-level.md", "numerics.md", "eq. (12)", "Cost", "Clarke", "Park"):
        assert needle in text

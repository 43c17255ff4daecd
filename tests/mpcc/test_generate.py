"""The generated long-horizon C: deterministic, warning-free under the strict flags with gcc and
arm-none-eabi-gcc (Cortex-M7), C28x text rules, every symbol prefixed, each block citing its equation
(T-type: with the neutral-point penalty of eq. (14), at every horizon)."""
from __future__ import annotations

from pathlib import Path

import pytest

from codegen.topology import topology_of

from .helpers import mpcc_model
from conftest import assert_symbols_prefixed, check_target_c


@pytest.mark.parametrize("config", ["spmsm", "tlevel"])
@pytest.mark.parametrize("target", ["host", "stm32h743", "tms320f28377"])
def test_target_c_is_strict_and_deterministic(config: str, target: str, tmp_path: Path):
    from codegen.render import write_files

    m = mpcc_model(config).replace(target=target)
    topo = topology_of(m)
    files = topo.render(m, topo.derive(m), target)
    assert files == topo.render(m, topo.derive(m), target)
    write_files(files, tmp_path / "out")
    check_target_c(tmp_path / "out", tmp_path, target)
    src = tmp_path / "out" / f"{m.prefix}_mpc.c"
    assert_symbols_prefixed(src, tmp_path / "sym.o", m.prefix)
    text = src.read_text()
    for eq in ("eq. (1)", "eq. (2)", "eq. (4)", "eq. (5)", "eq. (10)", "eq. (11)"):
        assert eq in text
    # the neutral-point penalty (eq. (14)) is the T-type's alone
    assert ("eq. (14)" in text) == (config == "tlevel") and ("LAMBDA_VO" in text) == (config == "tlevel")


@pytest.mark.parametrize("horizon", [1, 2, 5, 6])
def test_every_horizon_compiles(horizon: int, tmp_path: Path):
    from codegen.render import write_files

    for config in ("spmsm", "tlevel"):
        m = mpcc_model(config, horizon=horizon).replace(target="stm32h743")
        topo = topology_of(m)
        write_files(topo.render(m, topo.derive(m), "stm32h743"), tmp_path / config)
        check_target_c(tmp_path / config, tmp_path, "stm32h743")

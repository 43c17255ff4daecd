"""A config the fixed-point format cannot hold: the one-line error names the field that sets the offending
range and the value that fits (issue 28: ``inverter.i_trip_a = 1e5`` blamed ``motor.rated_torque_nm``)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.kernels.rangecause import range_cause, sensitivities
from codegen.kernels.stepformat import motor_ranges

from conftest import EXAMPLES, IPMSM, SPMSM, TTYPE

EXAMPLE_FILES = [IPMSM, SPMSM, TTYPE, EXAMPLES / "servo400w.toml"]


def _generate(tmp_path: Path, capsys: pytest.CaptureFixture[str], cfg: Path, *sets: str) -> tuple[int, str]:
    args = ["generate", str(cfg), "--number-format", "fixed", "-o", str(tmp_path / "o"), "-q"]
    for s in sets:
        args += ["--set", s]
    rc = main(args)
    lines = [line for line in capsys.readouterr().err.strip().splitlines() if not line.startswith("mpcgen: warning:")]
    assert rc == 0 or len(lines) == 1, lines
    return rc, "\n".join(lines)


@pytest.mark.parametrize("cfg", EXAMPLE_FILES, ids=lambda p: p.stem)
def test_trip_current_is_named_with_a_value_that_fits(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                      cfg: Path) -> None:
    rc, err = _generate(tmp_path, capsys, cfg, "inverter.i_trip_a=1e5")
    assert rc == 2 and "Traceback" not in err
    # the ConfigError names the field that set the range, with its value, and what to do with it
    assert re.search(r": inverter\.i_trip_a = 100000\.0: ", err), err
    assert "motor.rated_torque_nm = " not in err and "widen" not in err, err
    m = re.search(r"lower inverter\.i_trip_a \(now 1e\+05\) to at most ([0-9.e+]+) ", err)
    assert m, err
    # the advised value holds the step; a little more does not
    fits = float(m.group(1))
    assert _generate(tmp_path / "a", capsys, cfg, f"inverter.i_trip_a={fits}")[0] == 0
    assert _generate(tmp_path / "b", capsys, cfg, f"inverter.i_trip_a={fits * 1.05}")[0] == 2


def test_cost_range_grows_with_the_trip_current_not_the_rated_torque() -> None:
    """The two-level cost bound g = e_T^2 + e_psi^2, e_T = (Te_max + T*_guard)/T_N: with a huge trip
    current g grows as i_trip^4 (Te_max ~ L i^2) and shrinks as T_N^-2."""
    from codegen.topologies.twolevel.derive import cost_bounds

    model = load_config(IPMSM, {"controller.number_format": "fixed", "inverter.i_trip_a": 1e5})

    def ranges_of(m):  # type: ignore[no-untyped-def]
        return motor_ranges(m)[1] + cost_bounds(m)

    cause = range_cause(model, "g (cost)", ranges_of)
    assert cause is not None and cause.field == "inverter.i_trip_a" and cause.exponent == pytest.approx(4, abs=0.05)
    found = {c.field: c.exponent for c in sensitivities(model, "g (cost)", ranges_of)}
    assert found["motor.rated_torque_nm"] == pytest.approx(-2, abs=0.05)


def test_constant_too_small_names_its_own_field(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = _generate(tmp_path, capsys, SPMSM, "controller.eps_t_nm=1e-9", "controller.strategy=s1",
                        "controller.tables=published")
    assert rc == 2 and ": controller.eps_t_nm = 1e-09: " in err and "raise it" in err, err


def test_constant_starved_by_a_wide_range_names_the_range(tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    """T-type: the 1e5 A trip current widens the cost bound until PSI_F_SQ keeps too few counts; the
    error names the trip current (the cost bound set the resolution), not motor.psi_f_wb."""
    rc, err = _generate(tmp_path, capsys, TTYPE, "inverter.i_trip_a=1e5")
    assert rc == 2 and ": inverter.i_trip_a = 100000.0: constant PSI_F_SQ" in err, err
    assert "the widest range, g (cost, eq. (7))" in err and "lower inverter.i_trip_a" in err, err


def test_global_q_names_fixed_q_and_the_nearest_that_holds(tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = _generate(tmp_path, capsys, SPMSM, "controller.fixed_q=24", "controller.tables=published")
    assert rc == 2 and ": controller.fixed_q = 24: " in err, err
    assert "no global Q holds the step" in err or re.search(r"controller\.fixed_q to \d+ \(the nearest", err), err


@pytest.mark.parametrize("sets", [("controller.dt_s=1e-3",), ("motor.ld_h=1e-5", "motor.lq_h=1e-5")],
                         ids=["dt_1ms", "ld_lq_10uH"])
@pytest.mark.parametrize("cfg", [SPMSM, TTYPE], ids=lambda p: p.stem)
def test_power_of_two_widest_value_gets_its_integer_bit(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                        cfg: Path, sets: tuple[str, ...]) -> None:
    """Issue 27: with a 1 ms period the T-type's widest scaled value is the angle guard, 8 rad = 2^3 exactly;
    the format gave it 3 integer bits (|x| < 16 with the margin 2 needs 4) and blamed
    controller.number_format.  Every such config now gets valid C (or one line naming a field)."""
    rc, err = _generate(tmp_path, capsys, cfg, *sets)
    assert "Traceback" not in err
    assert "controller.number_format sets this value" not in err, err
    if rc == 0:
        assert next((tmp_path / "o").glob("*_mpc.c")).stat().st_size > 0
    else:
        assert rc == 2 and re.search(r": (motor|controller|inverter)\.\w+ = ", err), err

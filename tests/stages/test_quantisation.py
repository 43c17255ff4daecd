"""The quantisation report: fixed point against the float64 ideal and the float32 controller.

For the seed configs in fixed point, every strategy: the fixed and float32
controllers pick the same vector (and switching state) on >= 99 % of the
recorded closed-loop states, and the fixed controller's closed-loop torque
ripple is within 10 % of the float32 controller's.

The comparison runs the seed scenarios with the timing each controller
assumes (``plant.actuation_delay_periods`` 0 without delay compensation, as
before the examples took the seed papers' uncompensated one-period delay).
With that delay the two-level loop is marginal at the SPMSM's speed reversal
(s2 holds the zero vector at the torque limit while the current rises): a run
can trip the current guard from a difference of one decision, so a ripple
ratio there measures the trip, not the quantisation (simulate reports such a
trip: its fault count and a warning, ``tests/stages/test_simulate_checks.py``).
"""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.numfmt import CONFIG_FORMATS, FORMATS
from codegen.numfmt.float64 import FLOAT64
from codegen.stages.quantisation import analyse
from codegen.stages.training import with_trained_tables
from codegen.topology import topology_of

from conftest import IPMSM, SPMSM, TTYPE


@pytest.fixture(scope="module")
def results():
    cache: dict[str, dict] = {}

    def get(path):
        if path not in cache:
            m = load_config(path, {"controller.number_format": "fixed"})
            m = m.replace(plant=dataclasses.replace(m.plant, actuation_delay_periods=None))
            m = with_trained_tables(m, topology_of(m).strategies)  # s2/s3: trained on the example's scenario
            cache[path] = analyse(m, random_states=5_000)
        return cache[path]

    return get


@pytest.mark.parametrize("path", [SPMSM, IPMSM, TTYPE], ids=["spmsm", "ipmsm", "tlevel"])
def test_fixed_decisions_agree_with_float32_and_ripple_matches(results, path):
    data = results(str(path))
    for s, d in data["strategies"].items():
        for key in ("closed_loop", "closed_loop_fixed"):
            a = d["agreement"][key]
            assert a["compared"] > 0.8 * a["states"], (s, key, a)
            assert "vector" in a, (s, key)
            for name in ("vector", "sw"):
                if name in a:  # the two-level step also outputs its switching state
                    assert a[name]["fraction"] >= 0.99, (s, key, name, a)
        # the fixed controller's own states, converted to float32, pass both guards
        assert d["agreement"]["closed_loop_fixed"]["fault_mismatch"] == 0, s
        for run, row in d["closed_loop"].items():
            r = row["T_rip_RMSE_nm"]
            assert 0.9 <= r["ratio"] <= 1.1, (s, run, r)
            assert row["faults"]["fixed"] == 0, (s, run)


@pytest.mark.parametrize("path", [SPMSM, TTYPE], ids=["spmsm", "tlevel"])
def test_fixed_error_is_bounded_and_float32_is_closer_to_the_ideal(results, path):
    data = results(str(path))
    for s, d in data["strategies"].items():
        for key, e in d["errors"].items():
            assert e["states"] > 0
            for name in ("te_est_nm", "psi_est_wb"):
                fx, f32 = e[name]["fixed"], e[name]["float32"]
                # a few thousand counts of resolution at most, and float32 more precise than fixed here
                assert fx["max"] < 1e-3 * max(e[name]["ideal_max_abs"], 1.0), (s, key, name, fx)
                assert f32["rms"] <= fx["rms"], (s, key, name)
        checked = [c for c in d["constants"] if c["name"] in ("I_TRIP_A", "UDC_MAX_V", "PSI_F_WB", "EPS_T_NM")]
        assert {c["name"] for c in checked} >= {"I_TRIP_A", "PSI_F_WB"}, s
        for c in checked:
            assert c["rel_error"] < 1e-4, c
        assert {r["field"] for r in d["signals"]} >= {"ia_a", "te_est_nm", "psi_est_wb"}


def test_float64_is_an_analysis_format_not_a_config_choice():
    assert FORMATS[FLOAT64.name] is FLOAT64 and FLOAT64.name not in CONFIG_FORMATS
    ops = FLOAT64.ops
    assert ops.mul(ops.const(0.1), ops.const(3.0)) == np.float64(0.1) * 3.0


def test_report_cli_writes_markdown_plots_and_json(tmp_path):
    out = tmp_path / "rep"
    assert main(["report", str(SPMSM), "--number-format", "fixed", "--strategies", "s3", "--states", "2000",
                 "-o", str(out), "--json", str(tmp_path / "q.json"), "-q"]) == 0
    md = (out / "spmsm_quantisation.md").read_text()
    for text in ("## Strategy s3", "Q format", "TE_GEO_K", "float64 ideal", "vector agrees", "T_rip_RMSE_nm"):
        assert text in md, text
    assert sorted(p.name for p in out.glob("*.png")) == ["spmsm_quant_s3_errors.png",
                                                         "spmsm_quant_s3_scenario_torque.png"]
    data = json.loads((tmp_path / "q.json").read_text())
    assert list(data["strategies"]) == ["s3"]


def test_report_of_a_float32_config_analyses_its_fixed_twin(capsys):
    assert main(["report", str(SPMSM), "--strategies", "s1", "--states", "500", "-q"]) == 0
    assert "quantisation report (fixed point)" in capsys.readouterr().out


def test_generate_writes_the_report_for_fixed_point_only(tmp_path):
    args = ["generate", str(IPMSM), "--strategy", "s1", "--target", "host", "-q"]
    assert main([*args, "-o", str(tmp_path / "f")]) == 0
    assert not list((tmp_path / "f").glob("*_quantisation.md"))
    assert main([*args, "--number-format", "fixed", "-o", str(tmp_path / "q")]) == 0
    md = (tmp_path / "q" / "ipmsm_quantisation.md").read_text()
    assert "## Strategy s1" in md and "## Strategy s2" not in md
    assert main([*args, "--number-format", "fixed", "-o", str(tmp_path / "q2")]) == 0
    assert (tmp_path / "q2" / "ipmsm_quantisation.md").read_text() == md


@pytest.mark.parametrize("sets", [["controller.dt_s=1e-3"], ["motor.ld_h=1e-5", "motor.lq_h=1e-5"]],
                         ids=["slow-period", "tiny-inductance"])
def test_generate_fixed_where_a_closed_loop_metric_cannot_be_computed(tmp_path, sets):
    """Configs float32 accepts (second user trial: a TypeError on a closed-loop metric the run could not
    compute, None in its JSON): the fixed-point C and its quantisation report are written; a metric that is
    None is shown as n/a, never formatted as a number."""
    argv = ["generate", str(SPMSM), "--number-format", "fixed", "-o", str(tmp_path), "-q"]
    for s in sets:
        argv += ["--set", s]
    assert main(argv) == 0
    text = next(tmp_path.glob("*_quantisation.md")).read_text()
    assert "| scenario | T_rip_RMSE_nm |" in text and "None" not in text


def test_a_metric_none_is_na_in_the_report():
    from codegen.stages.quantreport import _g

    assert _g(None) == "n/a" and _g(float("nan")) == "n/a" and _g(0.5) == "0.5"

"""`mpcgen verify`: >= 10^6 states per strategy, 0 mismatches, and it does catch a wrong C."""
from __future__ import annotations

import json

import numpy as np
import pytest

import codegen.topologies.twolevel.hostbuild as hostbuild
from codegen.cli import main
from codegen.compare import mismatch_mask
from codegen.stages.verify import verify_strategy
from codegen.topologies.twolevel import reference
from codegen.topologies.twolevel.states import adversarial_states, random_states
from codegen.topologies.twolevel.switch_tables import tables_for

from conftest import IPMSM, SPMSM, TWO_LEVEL, model_for


@pytest.mark.parametrize("cfg", [SPMSM, IPMSM], ids=["spmsm", "ipmsm"])
def test_verify_million_states_per_strategy(tmp_path, cfg):
    out = tmp_path / "verify.json"
    assert main(["verify", str(cfg), "--states", "1000000", "--json", str(out), "-q"]) == 0
    data = json.loads(out.read_text())
    assert set(data["strategies"]) == set(TWO_LEVEL)
    for s, r in data["strategies"].items():
        assert r["states"] >= 1_000_000, s
        assert r["mismatches"] == 0, r["first_mismatch"]
        assert r["sources"]["closed_loop"] > 0 and r["sources"]["adversarial"] > 0 and r["sources"]["random"] > 0
        assert r["faulted_states"] > 0  # the guard is part of what is compared


@pytest.mark.parametrize("delay", [False, True])
@pytest.mark.parametrize("predictor", ["flux-geometry", "dq-euler"])
def test_both_predictors_and_delay_compensation(predictor, delay):
    m = model_for(SPMSM, predictor=predictor, delay_compensation=delay, strategy="s3", tables="published")
    r = verify_strategy(m, 200_000, log=lambda s: None, closed_loop=True)
    assert r.mismatches == 0, r.first_mismatch
    assert r.states >= 200_000


def test_guard_gives_safe_decision_in_c_and_reference():
    m = model_for(SPMSM, strategy="conventional")
    t = tables_for(m)
    lib = hostbuild.build_host_library(m, t, with_sim=False)
    x = random_states(m, 8, seed=5)
    x["udc_v"] = 300.0
    x["ia_a"][:4] = [np.nan, 1e6, 0.0, 0.0]
    x["udc_v"][2] = 10.0  # DC link below its minimum
    x["ib_a"][3] = np.inf
    for out in (reference.step_batch(t, x), lib.step_batch(x)):
        assert np.all(out["fault"][:4] != 0)
        assert np.all(out["vector"][:4] == 0) and np.all(out["sw"][:4] == 0) and np.all(out["n_eval"][:4] == 0)
        assert out["fault"][2] & 2  # UDC_LOW
    assert not mismatch_mask(reference.step_batch(t, x), lib.step_batch(x))[0].any()


def test_verify_detects_a_one_ulp_change(monkeypatch):
    """A C constant off by one ulp must be caught and reported with both sides."""
    m = model_for(SPMSM, strategy="conventional", psi_ref_wb=0.31)  # a config hash of its own
    t = tables_for(m)
    real = hostbuild.render_two_level

    def tampered(model, tables, target):
        files = real(model, tables, target)
        name = f"{model.prefix}_mpc.c"
        lit = "SPMSM_INV_TN"
        line = next(l for l in files[name].splitlines() if l.startswith(f"#define {lit}"))
        val = tables.const("INV_TN")
        bumped = np.nextafter(val, np.float32(1)).astype(np.float32)
        from codegen.numfmt.float32 import c_float_literal

        files[name] = files[name].replace(line, line.replace(c_float_literal(val), c_float_literal(bumped)))
        assert files[name] != real(model, tables, target)[name]
        return files

    monkeypatch.setattr(hostbuild, "render_two_level", tampered)
    lib = hostbuild.build_host_library(m, t, with_sim=False)
    x = np.concatenate([random_states(m, 50_000), adversarial_states(m, t, reference.step_batch, 10_000)])
    bad, per_field = mismatch_mask(reference.step_batch(t, x), lib.step_batch(x))
    assert bad.sum() > 0 and "costs" in per_field


def test_parallel_reference_reports_what_the_serial_one_does(monkeypatch):
    """The reference in a process pool: the same counts, the same first mismatch, in state order."""
    import functools
    import time

    from codegen.stages import verify as verify_stage

    m = model_for(SPMSM, strategy="s1")
    t = tables_for(m)
    x = random_states(m, 120_000, seed=9)

    marked = x["theta_e_rad"][[0, 50_001, 100_002]]  # three states, found by content in any chunk

    def wrong_c(x: np.ndarray) -> np.ndarray:
        out = reference.step_batch(t, x)
        out["cost_best"][np.isin(x["theta_e_rad"], marked)] += np.float32(1.0)
        return out

    ref = functools.partial(reference.step_batch, t)
    results = []
    for jobs in ("1", "2"):
        monkeypatch.setenv("MPCGEN_JOBS", jobs)
        r = verify_stage.compare_batches("s1", {"random": x}, ref, wrong_c, lambda _m: None, time.perf_counter())
        results.append((r.states, r.mismatches, r.faulted_states, r.mismatches_per_field, r.first_mismatch))
    assert results[0] == results[1]
    assert results[0][1] == 3 and results[0][4].startswith("state #0:")


def test_fixed_point_summary_states_the_saturations(capsys):
    """A fixed-point verify prints the saturations inside the guard (none for s1; numerics.md), float32 none."""
    assert main(["verify", str(SPMSM), "--strategy", "s1", "--tables", "published", "--number-format", "fixed",
                 "--states", "20000", "-q"]) == 0
    out = capsys.readouterr().out
    assert "saturations inside the guard (states passing it): none" in out, out
    assert main(["verify", str(SPMSM), "--strategy", "s1", "--tables", "published", "--states", "20000", "-q"]) == 0
    assert "saturations inside the guard" not in capsys.readouterr().out

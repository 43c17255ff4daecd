"""`mpcgen tune` and the figures it reads: the all-bin THD, the locked-cycle flag, the anomalies.

The search on Dask gives the serial results bit for bit and writes its table, JSON, CSV and front
plots; bad input is one line and exit 2 before any run; the front and the recommendation follow their
stated rules; ``simulate``'s JSON carries both THDs, the locked-cycle flag and the anomalies of every run.
"""
from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.errors import UsageError
from codegen.metrics import cycle_period, thd, thd_all_bins
from codegen.stages import sweep_runner, tune

from conftest import SPMSM, TTYPE


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("mpcgen: error: ")
    return err[0]


# ---------------------------------------------------------------- shared figures
def test_all_bin_thd_sees_interharmonics_the_integer_thd_does_not():
    dt, f1 = 50e-6, 25.0
    t = np.arange(int(0.4 / dt)) * dt
    x = np.sin(2 * np.pi * f1 * t) + 0.1 * np.sin(2 * np.pi * 5 * f1 * t) + 0.2 * np.sin(2 * np.pi * 2.5 * f1 * t)
    harm, _ = thd(x, dt, 0.0, 0.4, f1)
    every, info = thd_all_bins(x, dt, 0.0, 0.4, f1)
    assert harm == pytest.approx(10.0, rel=1e-9)
    assert every == pytest.approx(100 * math.hypot(0.1, 0.2), rel=1e-9)
    assert info["interharmonic_percent"] == pytest.approx(20.0, rel=1e-9)
    assert info["bin_hz"] == pytest.approx(f1 / 10) and info["bins"][0] == 1


def test_cycle_period():
    rng = np.random.default_rng(3)
    cycle = rng.integers(0, 27, 800)
    assert cycle_period(np.tile(cycle, 5)) == 800
    assert cycle_period(np.tile(cycle, 5)[:-1]) == 800  # a part-cycle at the end still repeats
    broken = np.tile(cycle, 5)
    broken[3000] = (broken[3000] + 1) % 27
    assert cycle_period(broken) is None
    assert cycle_period(rng.integers(0, 27, 4000)) is None
    assert cycle_period(np.tile(cycle, 2)) == 800 and cycle_period(np.tile(cycle, 2), min_repeats=3) is None


def test_simulate_json_has_both_thds_the_locked_cycle_and_the_anomalies(tmp_path):
    """The T-type example (lambda1 as tune chose it): 63-MPDTC locks into an exact cycle at 300 r/min and
    no run has an anomaly; with the former lambda1 = 28, 27-MPDTC's currents spike to 3.9 x rated and its
    flux locus collapses there; 0.02 A of sensor noise breaks 63-MPDTC's lock."""
    out, old, noisy = tmp_path / "sim.json", tmp_path / "old.json", tmp_path / "noisy.json"
    assert main(["simulate", str(TTYPE), "-q", "--json", str(out)]) == 0
    assert main(["simulate", str(TTYPE), "-q", "--strategies", "mpdtc27", "--set", "controller.lambda_psi_nm_per_wb=28",
                 "--json", str(old)]) == 0
    assert main(["simulate", str(TTYPE), "-q", "--strategies", "mpdtc63", "--set", "plant.noise_a=0.02",
                 "--json", str(noisy)]) == 0
    data = json.loads(out.read_text())
    for runs in data["strategies"].values():
        for key, m in runs.items():
            assert isinstance(m["THD_ia_percent"], float)
            if key.endswith("_steady"):
                continue
            assert isinstance(m["THD_ia_all_bins_percent"], float) and isinstance(m["locked_cycle"], bool)
            info = m["drive_figures"]["THD_ia_all_bins_percent"]
            assert info["bins"][0] == 1 and "every bin" in info["description"]
            assert m["anomalies"] == [], (key, m["anomalies"])
    low63 = data["strategies"]["mpdtc63"]["300rpm"]
    assert low63["locked_cycle"] and low63["drive_figures"]["locked_cycle"]["period_samples"] > 0
    low27 = json.loads(old.read_text())["strategies"]["mpdtc27"]["300rpm"]
    assert not low27["locked_cycle"]
    assert low27["i_peak_per_rated"] > 3.5 and low27["psi_min_share"] < 0.6
    assert [a.split(":")[0] for a in low27["anomalies"]] == ["current spike", "flux collapse"]
    assert low27["tracking"] == "ok"  # the verdict is unchanged: the anomalies are reported beside it
    noise = json.loads(noisy.read_text())["strategies"]["mpdtc63"]["300rpm"]
    assert not noise["locked_cycle"] and noise["drive_figures"]["locked_cycle"]["period_samples"] is None


# ---------------------------------------------------------------- fields, front, recommendation
def test_axis_ranges():
    model = load_config(TTYPE)
    a = tune.parse_axis("--weight", "controller.lambda_psi_nm_per_wb", model)
    lam = model.controller.lambda_psi_nm_per_wb
    assert (a.role, a.nominal, a.log) == ("weight", lam, True)
    assert a.lo == pytest.approx(lam / 10 ** 1.5, rel=1e-5) and a.hi == pytest.approx(lam * 10 ** 1.5, rel=1e-5)
    b = tune.parse_axis("--weight", "controller.lambda_vo_nm_per_v=0.001:0.1", model)
    assert (b.lo, b.hi) == (0.001, 0.1)
    assert [b.value(i, 4) for i in range(5)] == [0.001, 0.00316228, 0.01, 0.0316228, 0.1]
    c = tune.parse_axis("--threshold", "controller.eps_t_nm", load_config(SPMSM))
    assert (c.role, c.lo, c.log) == ("threshold", 0.0, False) and c.hi == 2 * c.nominal


@pytest.mark.parametrize("option,text,says", [
    ("--weight", "controller.lambda_psi_nm_per_w=1:10", "did you mean 'controller.lambda_psi_nm_per_wb'"),
    ("--weight", "controller.eps_t_nm", "not a field of a 't-type' config"),
    ("--weight", "controller.strategy", "not a real-valued field"),
    ("--weight", "controller.lambda_psi_nm_per_wb=0:100", "LO must be > 0"),
    ("--weight", "controller.lambda_psi_nm_per_wb=1:2e6", "2e+06 is outside the allowed range [0, 1e+06]"),
    ("--weight", "controller.lambda_psi_nm_per_wb=100:10", "LO < HI"),
    ("--threshold", "controller.lambda_vo_nm_per_v=-1:1", "-1 is outside the allowed range [0, 1000]"),
])
def test_bad_axes(option, text, says):
    with pytest.raises(UsageError) as exc:
        tune.parse_axis(option, text, load_config(TTYPE))
    assert says in str(exc.value) and "\n" not in str(exc.value)


def _pt(t, p, ok=True):
    return {"figures": {"T_rip_RMSE_nm": t, "psi_rip_RMSE_wb": p}, "admissible": ok}


def test_front_and_recommendation_rules():
    objectives = tune.parse_objectives("T_rip,psi_rip")
    pts = [_pt(1.0, 9.0), _pt(2.0, 4.0), _pt(3.0, 3.5), _pt(2.5, 5.0), _pt(9.0, 1.0), _pt(0.5, 8.0, ok=False),
           _pt(None, 0.1)]
    assert tune.front(pts, objectives) == [1, 2, 4, 5]  # 0 and 3 dominated; 6 has no torque ripple
    adm = [i for i in tune.front([p for p in pts if p["admissible"]], objectives)]
    assert adm == [0, 1, 2, 4]
    best, scaled = tune.recommend(pts, [0, 1, 2, 4], objectives)
    assert best == 1  # scaled (0.125, 0.375): nearest to the ideal point
    assert scaled["T_rip_RMSE_nm"] == pytest.approx(1 / 8) and scaled["psi_rip_RMSE_wb"] == pytest.approx(3 / 8)
    assert tune.recommend(pts, [], objectives) == (None, {})


def test_refinement_bisects_around_the_admissible_front():
    model = load_config(TTYPE)
    axis = tune.parse_axis("--weight", "controller.lambda_psi_nm_per_wb=1:1000", model)
    search = tune.Search(str(TTYPE), {}, ["mpdtc27"], [axis], tune.parse_objectives(None), grid=4, rounds=2)
    assert search.top == 12 and [search.values(i) for i in search.grid_indices()] == [(1.0,), (10.0,), (100.0,), (1000.0,)]
    figs = [(0.1, 0.01, 50.0, False), (0.2, 0.002, 20.0, True), (0.3, 0.001, 25.0, True), (0.5, 0.0009, 30.0, True)]
    search.points["mpdtc27"] = [{"lattice": [i * 4], "params": {axis.field: search.values((i * 4,))[0]},
                                 "admissible": f[3], "figures": dict(zip(tune.DEFAULT_OBJECTIVES, f[:3]))}
                                for i, f in enumerate(figs)]
    search.seen["mpdtc27"] = {(i * 4,): i for i in range(4)}
    # front: all four; admissible front: 10, 100, 1000 (focus 3: all of it) -> their neighbours at +-2 (of 12)
    assert search.refine("mpdtc27", 1) == [(2,), (6,), (10,)]
    assert [search.values(i)[0] for i in search.refine("mpdtc27", 1)] == [3.16228, 31.6228, 316.228]
    # scaled (T, psi, THD): 10 -> (0, 1, 0), 100 -> (1/3, 1/11, 1/2), 1000 -> (1, 0, 1): 100 is the nearest
    assert [i for i, _z in tune.ranked(search.points["mpdtc27"], [1, 2, 3], search.objectives)] == [2, 1, 3]
    search.focus = 1
    assert search.refine("mpdtc27", 1) == [(6,), (10,)]


# ---------------------------------------------------------------- bad input: one line, exit 2, nothing run
BAD = {
    "nothing to tune": [],
    "unknown field": ["--weight", "controller.lambda=1:10"],
    "field of the other topology": ["--threshold", "controller.eps_t_nm"],
    "bad range": ["--weight", "controller.lambda_psi_nm_per_wb=1:x"],
    "out of the allowed range": ["--weight", "controller.lambda_vo_nm_per_v=0.01:5000"],
    "tuned twice": ["--weight", "controller.lambda_psi_nm_per_wb", "--threshold", "controller.lambda_psi_nm_per_wb"],
    "unknown objective": ["--weight", "controller.lambda_psi_nm_per_wb", "--objectives", "T_rip,speed"],
    "one objective": ["--weight", "controller.lambda_psi_nm_per_wb", "--objectives", "T_rip"],
    "grid": ["--weight", "controller.lambda_psi_nm_per_wb", "--grid", "1"],
    "rounds": ["--weight", "controller.lambda_psi_nm_per_wb", "--rounds", "-1"],
    "bad strategy": ["--weight", "controller.lambda_psi_nm_per_wb", "--strategies", "s1"],
    "serial and scheduler": ["--weight", "controller.lambda_psi_nm_per_wb", "--serial", "--scheduler", "tcp://h:1"],
    "tls without key": ["--weight", "controller.lambda_psi_nm_per_wb", "--scheduler", "tls://127.0.0.1:8786",
                        "--tls-ca-file", "x", "--tls-cert", "y"],
}


@pytest.mark.parametrize("extra", list(BAD.values()), ids=list(BAD))
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch, extra):
    monkeypatch.chdir(tmp_path)
    started = []
    monkeypatch.setattr(sweep_runner.Session, "__enter__", lambda self: started.append(self))
    assert main(["tune", str(TTYPE), "-q", *extra]) == 2
    _one_error_line(capsys)
    assert not started


# ---------------------------------------------------------------- Dask == serial, outputs
def test_local_cluster_tune_matches_serial_bit_for_bit(tmp_path, capsys):
    args = ["tune", str(TTYPE), "-q", "--strategies", "mpdtc27", "--weight", "controller.lambda_psi_nm_per_wb=10:300",
            "--grid", "3", "--rounds", "1"]
    serial, dask = tmp_path / "serial", tmp_path / "dask"
    assert main([*args, "--serial", "-o", str(serial)]) == 0
    assert main([*args, "--workers", "2", "-o", str(dask)]) == 0
    out = capsys.readouterr().out
    assert "mpdtc27: recommended controller.lambda_psi_nm_per_wb = " in out and "--set controller." in out
    a, b = (json.loads((d / "tune.json").read_text()) for d in (serial, dask))
    assert b["timing"]["runner"] == "local" and b["timing"]["workers"] == 2
    assert a["timing"]["runner"] == "serial"
    a.pop("timing"), b.pop("timing")
    assert a == b
    assert (serial / "tune.csv").read_bytes() == (dask / "tune.csv").read_bytes()
    d = a["strategies"]["mpdtc27"]
    lams = [p["params"]["controller.lambda_psi_nm_per_wb"] for p in d["points"]]
    assert lams[:3] == [10.0, 54.7723, 300.0] and len(lams) > 3 and {p["round"] for p in d["points"]} == {0, 1}
    rec = d["recommended"]
    assert rec is not None and d["points"][rec["index"]]["admissible"] and rec["index"] in d["admissible_front"]
    assert rec["set_line"] == f"--set controller.lambda_psi_nm_per_wb={rec['params']['controller.lambda_psi_nm_per_wb']!r}"
    assert len(rec["c_hash"]) == 64 and rec["config_hash"] == d["points"][rec["index"]]["config_hash"]
    # lambda1 = 10 lets the 27-MPDTC currents spike at 300 r/min: marked, never recommended
    low = d["points"][0]
    assert not low["admissible"] and any("current spike" in r for r in low["reasons"])
    assert a["rules"]["recommendation"].startswith("among the strategy's admissible front")
    with open(serial / "tune.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len(lams) and {"controller.lambda_psi_nm_per_wb", "THD_ia_all_bins_percent",
                                       "i_peak_per_rated", "admissible", "recommended"} <= set(rows[0])
    md = (serial / "tune.md").read_text()
    assert "**Recommended: `controller.lambda_psi_nm_per_wb = " in md and "misbehaves: " in md
    for name in ("front_T_rip_psi_rip.png", "front_T_rip_THD_all.png", "front_psi_rip_THD_all.png"):
        png = (serial / name).read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000

"""`mpcgen simulate`: the seed-001 scenarios for all four strategies, JSON and PNG plots; threshold sweep."""
from __future__ import annotations

import json

import pytest

from codegen.cli import main

from conftest import IPMSM, SPMSM, TWO_LEVEL

KEYS = ("T_rip_RMSE_nm", "psi_rip_RMSE_wb", "THD_ia_percent", "f_ave_hz", "Cal_ave", "wall_s")


@pytest.mark.parametrize("cfg,duration", [(SPMSM, 4.0), (IPMSM, 2.0)], ids=["spmsm", "ipmsm"])
def test_simulate_writes_metrics_and_plots(tmp_path, capsys, cfg, duration):
    js, plots = tmp_path / "sim.json", tmp_path / "plots"
    assert main(["simulate", str(cfg), "--json", str(js), "--plots", str(plots), "-q"]) == 0
    table = capsys.readouterr().out
    assert "Table 9 layout" in table
    data = json.loads(js.read_text())
    assert data["config_hash"] and data["versions"]["mpcgen"]
    assert set(data["strategies"]) == set(TWO_LEVEL)
    for s, m in data["strategies"].items():
        for k in KEYS:
            assert isinstance(m[k], float), (s, k)
        assert m["periods"] == round(duration / 50e-6)
        assert m["faults"] == 0
        assert 0 < m["T_rip_RMSE_nm"] < 3.0 and 0 < m["psi_rip_RMSE_wb"] < 0.05 and 0 < m["THD_ia_percent"] < 20
        assert 1e3 < m["f_ave_hz"] < 20e3
    cal = {s: data["strategies"][s]["Cal_ave"] for s in TWO_LEVEL}
    assert cal["conventional"] == 7.0
    # each simplification evaluates fewer candidates (seed Table 9 ordering)
    assert cal["conventional"] > cal["s1"] > cal["s2"] > cal["s3"] > 0
    pngs = sorted(p.name for p in plots.glob("*.png"))
    assert len(pngs) == 6 * len(TWO_LEVEL) and all((plots / p).stat().st_size > 10_000 for p in pngs)


def test_threshold_sweep(tmp_path, capsys):
    js = tmp_path / "sweep.json"
    assert main(["simulate", str(SPMSM), "--sweep-eps", "0.2:0.6:0.4", "--json", str(js), "-q"]) == 0
    out = capsys.readouterr().out
    assert "Table 1 layout" in out and "Table 2 layout" in out
    data = json.loads(js.read_text())
    eps = [r["eps_t_nm"] for r in data["table2"]]
    assert eps == [0.2, 0.6]
    # a wider band holds the zero vector more often: fewer evaluations (seed Table 2 trend)
    assert data["table2"][0]["Cal_ave"] > data["table2"][1]["Cal_ave"]
    t1 = data["table1"]
    assert t1[0]["N"] < t1[1]["N"] <= t1[-1]["N"]

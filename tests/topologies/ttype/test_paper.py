"""``mpcgen simulate examples/seed000_tlevel.toml --paper``: seed 000's Table 5 next to ours over the
steady window of the lengthened Table-5 runs, the reductions the paper prints, and the figures of its
text; the JSON carries both columns and the published numbers are the repository's data."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from codegen.cli import main
from codegen.topologies.ttype import published as pub

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


def test_table5_side_by_side(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    js = tmp_path / "sim.json"
    assert main(["simulate", str(EXAMPLES / "seed000_tlevel.toml"), "--paper", "--json", str(js), "-q"]) == 0
    out = capsys.readouterr().out
    data = json.loads(js.read_text())
    out = out[out.index("paper: seed 000"):]  # the side-by-side table (ours alone is printed above it)
    assert "seed 000 Table 5" in out and "paper    ours" in out
    # the steady windows exclude the start-up and are printed
    assert "over the steady window [0.2, 0.4) s" in out
    paper = data["paper"]
    assert paper["available"] is True
    rows = {(r["speed_rpm"], r["strategy"]): r for r in paper["rows"]}
    for p in pub.TABLE5_STEADY:
        r = rows[(p.speed_rpm, p.strategy)]
        ours = data["strategies"][p.strategy][f"{p.speed_rpm:g}rpm_steady"]
        assert r["T_rip_RMSE_nm"] == {"published": p.dte_nm, "ours": ours["T_rip_RMSE_nm"],
                                      "ours_over_published": ours["T_rip_RMSE_nm"] / p.dte_nm}
        assert r["psi_rip_RMSE_wb"]["published"] == p.dpsi_wb
        assert r["THD_ia_percent"]["published"] == p.thd_ia_percent
        assert r["THD_ia_percent"]["ours"] == ours["THD_ia_percent"]
        assert r["steady"] is True and r["window_s"] == [0.2, 0.4]
        assert not ours["not_steady"], ours["not_steady"]  # every metric window of a steady run is steady
        line = next(x for x in out.splitlines() if x.split()[:2] == [f"{p.speed_rpm:.0f}", p.strategy])
        assert f"{p.dte_nm:.4f}" in line and f"{ours['T_rip_RMSE_nm']:.4f}" in line  # both columns
    red = {(r["name"], r["speed_rpm"]): r for r in paper["ratios"]}
    for speed, printed in pub.TABLE5_REDUCTIONS_PERCENT.items():
        r = red[("torque ripple reduction 63 vs 27 / %", speed)]
        assert r["published"] == printed[0]
        a = data["strategies"]["mpdtc27"][f"{speed:g}rpm_steady"]["T_rip_RMSE_nm"]
        b = data["strategies"]["mpdtc63"][f"{speed:g}rpm_steady"]["T_rip_RMSE_nm"]
        assert r["ours"] == pytest.approx(100 * (1 - b / a))
        assert red[("i_a THD reduction 63 vs 27 / %", speed)]["published"] == printed[2]
    assert red[("execution time 63 / 27 / % (Fig. 9)", None)]["published"] == pytest.approx(100 * 33.8 / 38.2)
    assert "88.48" in out and "reductions 63- vs 27-MPDTC" in out
    uab = next(f for f in paper["text_figures"] if f["name"].startswith("u_ab THD"))
    assert uab["mpdtc27"]["published"] == pub.FIG11_UAB_THD_PERCENT["mpdtc27"]
    assert uab["mpdtc63"]["ours"] == data["strategies"]["mpdtc63"]["3000rpm_steady"]["THD_uab_percent"]


def test_config_scenario_has_no_published_figures(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    js = tmp_path / "sim.json"
    assert main(["simulate", str(EXAMPLES / "seed000_tlevel.toml"), "--paper", "--json", str(js), "-q",
                 "--strategy", "mpdtc63", "--set", "scenario.set=config", "--set", "scenario.duration_s=0.05"]) == 0
    lines = [x for x in capsys.readouterr().out.splitlines() if x.startswith("paper:")]
    assert len(lines) == 1 and "no published figures" in lines[0] and "mpdtc-table5" in lines[0]
    assert json.loads(js.read_text())["paper"]["available"] is False

"""`mpcgen study`: the lambda_u search matching every horizon's switching frequency, and its outputs.

The search follows its stated rule on known curves (converges within the tolerance, stops on a target out
of reach and on a jump); a short study of the two-level example writes study.md, study.json and study.png
with consistent numbers (f_ave within the tolerance of the N = 1 target, nodes >= 1, the config and C
hashes of every N); bench files fill the cycle column of the N whose config hash they name; bad input is
one line and exit 2 before any run.
"""
from __future__ import annotations

import json
import math
import re

import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.manifest import c_hash
from codegen.stages import study, sweep_runner

from conftest import EXAMPLES, SPMSM

MPCC_SPMSM = EXAMPLES / "mpcc_spmsm.toml"
#: a 0.5 s constant-reference scenario (the THD window is its last 0.2 s)
SHORT = ["--set", "scenario.duration_s=0.5", "--set", "scenario.speed_ref_rpm=[[0.0, 500.0]]",
         "--set", "scenario.load_nm=[[0.0, 10.0]]"]


def _search(curve, target: float, lam0: float = 0.1, tol: float = 0.03, max_runs: int = 12) -> study.Match:
    """The search of one N on ``curve`` (lambda_u -> f_ave), run to its end."""
    m = study.Match(1, math.log(lam0 / 1e6), math.log(lam0 * 1e6))
    lam: float | None = lam0
    while lam is not None:
        m.points.append({"lambda_u": lam, "f_ave_hz": curve(lam), "round": len(m.points)})
        lam = m.update(target, tol, max_runs)
    return m


def test_search_matches_a_decreasing_curve_within_the_tolerance():
    def curve(lam: float) -> float:
        return 4000.0 / math.sqrt(1.0 + lam / 0.3)

    for target in (3900.0, 3000.0, 1500.0, 400.0):
        m = _search(curve, target, tol=0.01)
        last = m.points[-1]
        assert m.status == "matched" and abs(last["f_ave_hz"] / target - 1) <= 0.01, (target, m.points)
        assert len(m.points) <= 8
        assert all(p["lambda_u"] == float(f"{p['lambda_u']:.6g}") for p in m.points)


def test_search_stops_when_the_target_is_out_of_reach_or_f_ave_jumps():
    def saturating(lam: float) -> float:  # at most 4 kHz however small lambda_u is
        return 4000.0 - 2000.0 * lam / (lam + 1.0)

    m = _search(saturating, 5000.0)
    assert m.status.startswith("not matched") and len(m.points) <= 12
    assert m.best(5000.0)["lambda_u"] == min(p["lambda_u"] for p in m.points)

    def step(lam: float) -> float:
        return 3500.0 if lam < 0.5 else 1700.0

    m = _search(step, 2600.0, max_runs=40)
    assert "jumps from 3500 to 1700 Hz" in m.status
    m = _search(step, 2600.0, max_runs=5)
    assert m.status == "not matched within 5 runs" and len(m.points) == 5


def test_bench_files_fill_the_cycles_of_their_config_hash(tmp_path):
    rows = [{"config_hash": "a" * 16}, {"config_hash": "b" * 16}]
    bench = [{"file": "x.json", "config_hash": "a" * 16,
              "strategies": {"mpcc": {"m7_cycles_est_median": 4100.0, "m7_cycles_est_max": 9800.0}}},
             {"file": "y.json", "config_hash": "c" * 16, "strategies": {}}]
    assert study.attach_cycles(rows, bench, "mpcc") == ["y.json"]
    assert rows[0]["cycles"] == {"median": 4100.0, "max": 9800.0, "file": "x.json"}
    assert rows[1]["cycles"] is None and rows[1]["cycles_note"] == "not measured"
    f = tmp_path / "bench.json"
    f.write_text(json.dumps({"config_hash": "a" * 16, "strategies": {}}))
    assert study.read_bench([str(f)])[0]["config_hash"] == "a" * 16


def test_short_study_writes_consistent_files(tmp_path, capsys):
    out = tmp_path / "study"
    assert main(["study", str(MPCC_SPMSM), "--serial", "--horizons", "1-2", "--tolerance", "1", *SHORT,
                 "-o", str(out)]) == 0
    cap = capsys.readouterr()
    assert cap.out.split() == [str(out / n) for n in ("study.md", "study.json", "study.png")]
    assert "study round 0: run 1/2 done" in cap.err and "study: target f_ave" in cap.err
    data = json.loads((out / "study.json").read_text())
    target = data["target"]["f_ave_hz"]
    rows = {r["horizon"]: r for r in data["rows"]}
    assert sorted(rows) == [1, 2]
    assert rows[1]["lambda_u"] == 0.1 and rows[1]["f_ave_hz"] == target and len(rows[1]["runs"]) == 1
    assert len(rows[2]["runs"]) > 1  # N = 2 at the config's lambda_u switches more than 1 % faster
    for n, r in rows.items():
        assert r["status"] == "matched" and abs(r["f_ave_hz"] / target - 1) <= 0.01
        assert r["f_error_percent"] == pytest.approx(100 * (r["f_ave_hz"] / target - 1))
        assert r["runs"][-1]["lambda_u"] == r["lambda_u"]
        nd = r["nodes"]
        assert nd["mean"] >= 1 and nd["max"] >= 1 and nd["max"] <= nd["node_budget"]
        assert 0 <= nd["budget_hit_percent"] <= 100 and nd["searched_periods"] == nd["periods"] > 1000
        assert r["THD_ia_percent"] > 0 and r["T_rip_RMSE_nm"] > 0 and r["admissible"]
        assert "[0.3, 0.5) s" in r["thd_windows"][0]["window"]
        assert r["cycles"] is None and r["cycles_note"] == "not measured"
        variant = load_config(MPCC_SPMSM, {**dict(data["overrides"]), "controller.horizon": n,
                                           "controller.lambda_u": r["lambda_u"]})
        assert r["config_hash"] == variant.config_hash() and r["c_hash"] == c_hash(variant)
        assert f"--set controller.lambda_u={r['lambda_u']!r}" in r["simulate_command"]
    assert rows[1]["c_hash"] != rows[2]["c_hash"] and re.fullmatch(r"[0-9a-f]{64}", rows[2]["c_hash"])
    assert rows[2]["nodes"]["mean"] > rows[1]["nodes"]["mean"]
    assert data["command"].startswith(f"mpcgen study {MPCC_SPMSM} --horizons 1-2 --set scenario.duration_s=0.5")
    assert data["config_hash"] == load_config(MPCC_SPMSM, dict(data["overrides"])).config_hash()
    md = (out / "study.md").read_text()
    assert data["command"] in md and f"| 2 | {rows[2]['lambda_u']:.6g} |" in md and rows[2]["c_hash"] in md
    from PIL import Image

    png = Image.open(out / "study.png")
    shown = json.loads(png.info["Description"])
    assert shown["horizons"] == [1, 2] and shown["nodes_mean"] == [rows[n]["nodes"]["mean"] for n in (1, 2)]
    assert shown["THD_ia_percent"] == [rows[n]["THD_ia_percent"] for n in (1, 2)]


BAD = {
    "horizon 0": (MPCC_SPMSM, ["--horizons", "0-2"], "--horizons = '0-2': 0 is outside [1, 6]"),
    "horizon 7": (MPCC_SPMSM, ["--horizons", "1,7"], "7 is outside [1, 6]"),
    "reversed": (MPCC_SPMSM, ["--horizons", "3-1"], "expected A-B"),
    "not a number": (MPCC_SPMSM, ["--horizons", "x"], "expected A-B"),
    "not a long-horizon config": (SPMSM, [], "has no controller.horizon"),
    "fsw": (MPCC_SPMSM, ["--fsw-khz", "-1"], "--fsw-khz = -1"),
    "fsw above half the control frequency": (MPCC_SPMSM, ["--fsw-khz", "12"], "--fsw-khz = 12"),
    "tolerance": (MPCC_SPMSM, ["--tolerance", "0"], "--tolerance = 0"),
    "max runs": (MPCC_SPMSM, ["--max-runs", "0"], "--max-runs = 0"),
    "bench missing": (MPCC_SPMSM, ["--bench", "missing.json"], "--bench = missing.json: cannot read it"),
    "bench not JSON": (MPCC_SPMSM, ["--bench", str(MPCC_SPMSM)], "not JSON"),
    "serial and scheduler": (MPCC_SPMSM, ["--serial", "--scheduler", "tcp://h:1"], "exclude each other"),
}


@pytest.mark.parametrize("config,extra,says", list(BAD.values()), ids=list(BAD))
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch, config, extra, says):
    monkeypatch.chdir(tmp_path)
    started = []
    monkeypatch.setattr(sweep_runner.Session, "__enter__", lambda self: started.append(self))
    assert main(["study", str(config), "-q", *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mpcgen: error: ") and says in err[0], err
    assert not started


def test_local_cluster_study_matches_serial(tmp_path, capsys):
    args = ["study", str(MPCC_SPMSM), "-q", "--horizons", "1,3", *SHORT]
    serial, dask = tmp_path / "serial", tmp_path / "dask"
    assert main([*args, "--serial", "-o", str(serial)]) == 0
    assert main([*args, "--workers", "2", "-o", str(dask)]) == 0
    a, b = (json.loads((d / "study.json").read_text()) for d in (serial, dask))
    assert (a["timing"]["runner"], b["timing"]["runner"], b["timing"]["workers"]) == ("serial", "local", 2)
    for d in (a, b):
        d.pop("timing"), d.pop("machine")
        d["command"] = d["command"].rpartition(" -o ")[0]
    assert a == b

"""`mpcgen simulate` refuses or flags what it cannot state right: steady windows, T-type scenario set,
guard faults, metrics that cannot be computed, runs too large for memory, and exports the traces."""
from __future__ import annotations

import csv
import json

import numpy as np

from codegen.cli import main

from conftest import EXAMPLES, SPMSM, TTYPE

SERVO = EXAMPLES / "servo400w.toml"
#: a short servo run at rated speed without load steps (one segment from start-up)
SHORT = ["--set", "scenario.load_nm=[[0, 0]]", "--strategies", "conventional", "-q"]


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(["simulate", *argv])
    out = capsys.readouterr()
    return rc, out.out, out.err


def _conventional(capsys, tmp_path, duration_s: float, window_s: float) -> tuple[dict, dict, str]:
    """The servo's conventional run: its metrics, the THD window entry and the printed table."""
    js = tmp_path / "s.json"
    rc, out, _ = _run(capsys, str(SERVO), *SHORT, "--set", f"scenario.duration_s={duration_s}",
                      "--set", f"scenario.window_s={window_s}", "--json", str(js))
    assert rc == 0
    m = json.loads(js.read_text())["strategies"]["conventional"]
    return m, m["window"]["THD_ia_percent"], out


def test_window_with_startup_is_flagged(tmp_path, capsys):
    m, w, out = _conventional(capsys, tmp_path, 0.1, 0.1)
    assert w["steady"] is False and "start-up" in w["not_steady_reason"]
    assert "THD_ia_percent" in m["not_steady"] and "T_rip_std_nm" in m["not_steady"]
    assert m["window"]["ripple_std_pp"]["steady"] is False
    row = next(line for line in out.splitlines() if line.startswith("conventional"))
    assert "*" in row and "* conventional THD_ia_percent: window not steady" in out
    assert "[0, 0.09" in row  # the window (t0, t1) is printed with the fundamental and its periods
    assert m["steady"][0]["steady"] is False


def test_settled_window_is_not_flagged(tmp_path, capsys):
    m, w, out = _conventional(capsys, tmp_path, 0.4, 0.1)
    assert w["steady"] is True and m["not_steady"] == {} and m["not_computed"] == {}
    assert w["t0_s"] == 0.3 and w["n_periods"] in (19, 20) and abs(w["f1_hz"] - 200.0) < 2.0
    assert "*" not in next(line for line in out.splitlines() if line.startswith("conventional"))


def test_ttype_runs_the_config_scenario(tmp_path, capsys):
    js = tmp_path / "t.json"
    rc, out, _ = _run(capsys, str(TTYPE), "--set", "scenario.set=config", "--set", "scenario.duration_s=0.1",
                      "--set", "scenario.window_s=0.05", "--set", "scenario.speed_ref_rpm=[[0, 1500]]",
                      "--strategies", "mpdtc63", "-q", "--json", str(js))
    assert rc == 0 and "Table 5" not in out
    data = json.loads(js.read_text())
    assert data["scenario_set"] == "config"
    runs = data["strategies"]["mpdtc63"]
    assert list(runs) == ["scenario"]
    m = runs["scenario"]
    assert m["window"]["T_rip_RMSE_nm"]["n_samples"] == 2000
    assert abs(m["window"]["THD_ia_percent"]["f1_hz"] - 1500 / 60 * 5) < 1.0  # 5 pole pairs at 1500 r/min
    assert "faults" in out.splitlines()[1]


def test_two_level_refuses_the_table5_set(capsys):
    rc, _, err = _run(capsys, str(SPMSM), "--set", "scenario.set=mpdtc-table5", "-q")
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "scenario.set" in err


def test_faults_column_stderr_and_counts(tmp_path, capsys):
    js = tmp_path / "f.json"
    rc, out, err = _run(capsys, str(SERVO), *SHORT, "--set", "inverter.i_trip_a=6",
                        "--set", "scenario.duration_s=0.1", "--set", "scenario.window_s=0.05", "--json", str(js))
    assert rc == 0
    m = json.loads(js.read_text())["strategies"]["conventional"]
    assert m["faults"] > 0 and m["fault_counts"]["CURRENT"] == m["faults"]
    assert set(m["fault_counts"]) >= {"CURRENT", "UDC_LOW", "UDC_HIGH", "STATE"}
    head, row = out.splitlines()[1:3]
    assert "faults" in head and f" {m['faults']} " in row
    lines = [line for line in err.splitlines() if "returned the safe decision" in line]
    assert len(lines) == 1 and f"{m['faults']} of 4000 periods" in lines[0] and "CURRENT" in lines[0]


def test_long_period_metric_not_computed(tmp_path, capsys):
    js = tmp_path / "d.json"
    rc, out, err = _run(capsys, str(SERVO), "--set", "controller.dt_s=1e-3", "--strategies", "conventional", "-q",
                        "--json", str(js))
    assert rc == 0 and "Traceback" not in err
    m = json.loads(js.read_text())["strategies"]["conventional"]
    assert m["THD_ia_percent"] is None and "Nyquist" in m["not_computed"]["THD_ia_percent"]
    assert "Nyquist" in m["window"]["THD_ia_percent"]["not_computed_reason"]
    assert "n/a" in next(line for line in out.splitlines() if line.startswith("conventional"))


def test_tiny_inertia_no_traceback(capsys):
    rc, _, err = _run(capsys, str(SERVO), "--set", "motor.j_kgm2=1e-9", "--strategies", "conventional", "-q")
    assert rc in (0, 1) and "Traceback" not in err
    assert all(line.startswith("mpcgen: ") for line in err.strip().splitlines())


def test_run_too_large_for_memory_refused(capsys):
    rc, out, err = _run(capsys, str(SPMSM), "--set", "scenario.duration_s=100", "--set", "controller.dt_s=1e-6", "-q")
    assert rc == 2 and out == ""
    line, = err.strip().splitlines()
    assert "scenario.duration_s" in line and "controller.dt_s" in line and "GB" in line and "limit" in line


def test_ttype_table5_run_too_large_refused(capsys):
    rc, _, err = _run(capsys, str(TTYPE), "--set", "scenario.duration_s=100", "--set", "controller.dt_s=1e-5",
                      "--set", "controller.t_n_min_s=1e-6", "-q")
    assert rc == 2 and "scenario.duration_s" in err


def test_traces_npz_and_csv(tmp_path, capsys):
    npz, csvf = tmp_path / "tr.npz", tmp_path / "tr.csv"
    argv = [str(SERVO), *SHORT, "--set", "scenario.duration_s=0.01", "--set", "scenario.window_s=0.01"]
    assert _run(capsys, *argv, "--traces", str(npz))[0] == 0
    z = np.load(npz)
    assert z["conventional/scenario/t_s"].shape == (400,)
    assert {"conventional/scenario/ia_a", "conventional/scenario/te_nm", "conventional/scenario/load_nm",
            "conventional/scenario/applied_sw"} <= set(z.files)
    assert _run(capsys, *argv, "--traces", str(csvf))[0] == 0
    with open(csvf) as f:
        rows = list(csv.reader(f))
    assert rows[0][:4] == ["strategy", "run", "t_s", "speed_ref_rad_s"] and "ia_a" in rows[0]
    assert len(rows) == 401 and rows[1][:2] == ["conventional", "scenario"]
    col = rows[0].index("ia_a")
    assert [float(r[col]) for r in rows[1:]] == z["conventional/scenario/ia_a"].tolist()

"""`mpcgen sweep`: grids and Monte Carlo studies on Dask give the serial results bit for bit; bad input is one line.

The checks of the results sweep controller fields (eps_T, lambda1, dt), which change the
generated controller, and the Monte Carlo checks spread a controller field; the plant
overrides a mismatch study spreads are tested in tests/simulator/test_plant_overrides.py.
"""
from __future__ import annotations

import csv
import json

import pytest

from codegen.cli import main
from codegen.errors import UsageError
from codegen.stages import sweep, sweep_runner

from conftest import IPMSM, SPMSM, TTYPE

#: a 0.3 s scenario at 500 r/min and 10 N*m (both two-level examples)
SHORT = ["--set", "scenario.duration_s=0.3", "--set", "scenario.window_s=0.1",
         "--set", "scenario.speed_ref_rpm=[[0.0, 500.0]]", "--set", "scenario.load_nm=[[0.0, 10.0]]"]


def _without_timing(path) -> dict:
    data = json.loads(path.read_text())
    assert data["timing"]["wall_s"] > 0 and len(data["timing"]["runs"]) == len(data["runs"])
    data.pop("timing")
    return data


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("mpcgen: error: ")
    return err[0]


# ---------------------------------------------------------------- parsing
def test_parse_param_lists_and_ranges():
    assert sweep.parse_param("controller.eps_t_nm=0.1:1.5:0.1").values == tuple(round(0.1 * i, 1) for i in range(1, 16))
    assert sweep.parse_param("controller.eps_t_nm=0.2,0.5,1").values == (0.2, 0.5, 1)
    assert sweep.parse_param("plant.dead_time_s=0:1e-6:2.5e-7").values == (0.0, 2.5e-7, 5e-7, 7.5e-7, 1e-6)
    assert sweep.parse_param("controller.dt_s=25e-6:50e-6:5e-6").values == (2.5e-5, 3e-5, 3.5e-5, 4e-5, 4.5e-5, 5e-5)
    assert sweep.parse_param("plant.adc_bits=10:16:2").values == (10, 12, 14, 16)
    assert sweep.parse_param("controller.predictor=dq-euler,flux-geometry").values == ("dq-euler", "flux-geometry")
    assert sweep.parse_param("scenario.load_nm=[[[0.0, 5.0]], [[0.0, 10.0]]]").values == ([[0.0, 5.0]], [[0.0, 10.0]])
    s = sweep.parse_spread("plant.rs_ohm=+-20")
    assert (s.field, s.percent) == ("plant.rs_ohm", 20.0)
    assert sweep.parse_spread("plant.ld_h=±10%").percent == 10.0


@pytest.mark.parametrize("text", ["controller.eps_t=0.1,0.2", "controller.eps_t_nm=0.1,,0.2", "controller.eps_t_nm=a:b:c",
                                  "controller.eps_t_nm=1.5:0.1:0.1", "controller.eps_t_nm=0.1:1.5:0",
                                  "controller.eps_t_nm=0.1:1.5", "controller.eps_t_nm", "controller.eps_t_nm=0.1,0.1",
                                  "controller.predictor=0:1:0.5", "plant.adc_bits=1:2:0.5", "controller.eps_t_nm=0:1e9:1",
                                  "scenario.load_nm=[[0, 5]", "scenario.load_nm=[]"])
def test_parse_param_rejects(text):
    with pytest.raises(UsageError) as exc:
        sweep.parse_param(text)
    assert "\n" not in str(exc.value) and "--param" in str(exc.value)


@pytest.mark.parametrize("text", ["plant.rs_ohm=20", "plant.rs_ohm=+-0", "plant.rs_ohm=+-100", "plant.rs_ohm=+-x",
                                  "plant.rs=+-20", "controller.strategy=+-10", "plant.adc_bits=+-10"])
def test_parse_spread_rejects(text):
    with pytest.raises(UsageError):
        sweep.parse_spread(text)


def test_monte_carlo_plan_is_reproducible_and_centred_on_the_controllers_values():
    from codegen.config import load_config

    model = load_config(IPMSM)
    spreads = ["plant.rs_ohm=+-20", "plant.psi_f_wb=+-10", "controller.eps_t_nm=+-50"]

    def plan(seed):
        return sweep.build_plan(str(IPMSM), model, {}, ["s1"], ["controller.dt_s=40e-6,50e-6"], spreads, 50, seed)

    a, b, c = plan(7), plan(7), plan(8)
    assert a.runs == b.runs and a.runs != c.runs
    assert len(a.runs) == 100 and a.kind == "grid+monte-carlo"
    assert [s.nominal for s in a.spreads] == [0.25, 0.2264, 0.75]  # plant.rs_ohm unset: motor.rs_ohm
    rs = [r["params"]["plant.rs_ohm"] for r in a.runs[:50]]
    assert all(0.2 <= v <= 0.3 for v in rs) and max(rs) - min(rs) > 0.05
    # every grid point gets the same draws
    assert [r["params"]["plant.rs_ohm"] for r in a.runs[50:]] == rs


# ---------------------------------------------------------------- bad input: one line, exit 2
BAD = {
    "unknown field": ["--param", "controller.eps=0.1,0.2"],
    "unparsable list": ["--param", "controller.eps_t_nm=0.1;0.2"],
    "empty range": ["--param", "controller.eps_t_nm=1.0:0.5:0.1"],
    "value out of range": ["--param", "controller.eps_t_nm=0.5,99"],
    "value of the wrong type": ["--param", "controller.predictor=euler"],
    "dt makes a fixed field inconsistent": ["--set", "plant.dead_time_s=4e-6", "--param", "controller.dt_s=30e-6,50e-6"],
    "monte carlo without spread": ["--monte-carlo", "10"],
    "spread without monte carlo": ["--param", "controller.eps_t_nm=0.5", "--spread", "plant.rs_ohm=+-20"],
    "spread value beyond the field's range": ["--monte-carlo", "10", "--spread", "controller.eps_t_nm=+-50", "--set",
                                              "controller.eps_t_nm=14"],
    "nothing to sweep": [],
    "field swept twice": ["--param", "controller.eps_t_nm=0.5", "--param", "controller.eps_t_nm=0.6"],
    "negative runs": ["--monte-carlo", "-1", "--spread", "plant.rs_ohm=+-20"],
    "bad strategy": ["--param", "controller.eps_t_nm=0.5", "--strategies", "s9"],
    "plot not png": ["--param", "controller.eps_t_nm=0.5", "--plot", "out.pdf"],
    "serial and scheduler": ["--param", "controller.eps_t_nm=0.5", "--serial", "--scheduler", "tcp://127.0.0.1:8786"],
    "workers 0": ["--param", "controller.eps_t_nm=0.5", "--workers", "0"],
    "scheduler address": ["--param", "controller.eps_t_nm=0.5", "--scheduler", "127.0.0.1 port 8786"],
}


@pytest.mark.parametrize("extra", list(BAD.values()), ids=list(BAD))
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch, extra):
    monkeypatch.chdir(tmp_path)
    started = []
    monkeypatch.setattr(sweep_runner, "run_plan", lambda *a, **k: started.append(a))
    assert main(["sweep", str(IPMSM), "-q", *extra]) == 2
    _one_error_line(capsys)
    assert not started  # checked before any run or cluster
    assert not list(tmp_path.iterdir())


def test_unreachable_scheduler_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch):
    import socket

    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    monkeypatch.setattr(sweep_runner, "CONNECT_TIMEOUT_S", 2)
    js = tmp_path / "s.json"
    assert main(["sweep", str(IPMSM), "-q", "--param", "controller.eps_t_nm=0.5", "--scheduler",
                 f"tcp://127.0.0.1:{port}", "--json", str(js)]) == 2
    line = _one_error_line(capsys)
    assert f"127.0.0.1:{port}" in line and "cannot connect" in line
    assert not js.exists()


# ---------------------------------------------------------------- Dask == serial, outputs
def test_small_plan_runs_serially_by_default(tmp_path, capsys):
    """A plan of fewer runs than LOCAL_CLUSTER_FROM_RUNS starts no LocalCluster (it would take longer than
    the runs) unless --workers asks for one; the JSON says where the runs went."""
    from codegen.stages.sweep import LOCAL_CLUSTER_FROM_RUNS

    js = tmp_path / "small.json"
    assert main(["sweep", str(SPMSM), *SHORT, "--strategies", "s1", "--param", "controller.eps_t_nm=0.2,0.4",
                 "--json", str(js)]) == 0
    err = capsys.readouterr().err
    assert LOCAL_CLUSTER_FROM_RUNS > 2
    assert "2 run(s): serially in this process" in err and "LocalCluster started" not in err
    assert json.loads(js.read_text())["timing"]["runner"] == "serial"


def test_local_cluster_grid_matches_serial_bit_for_bit(tmp_path, capsys):
    args = ["sweep", str(SPMSM), *SHORT, "-q", "--strategies", "conventional,s1",
            "--param", "controller.eps_t_nm=0.2:0.8:0.3", "--param", "controller.dt_s=40e-6,50e-6"]
    serial, dask = tmp_path / "serial.json", tmp_path / "dask.json"
    out = {n: tmp_path / f"sweep.{n}" for n in ("csv", "png")}
    assert main([*args, "--serial", "--json", str(serial)]) == 0
    table = capsys.readouterr().out
    assert "grid sweep, 6 runs x 2 strategies" in table and "eps_t_nm" in table
    assert main([*args, "--workers", "2", "--json", str(dask), "--csv", str(out["csv"]), "--plot", str(out["png"])]) == 0
    a, b = _without_timing(serial), _without_timing(dask)
    assert a == b
    assert json.loads(dask.read_text())["timing"]["runner"] == "local"
    assert json.loads(dask.read_text())["timing"]["workers"] == 2
    assert all(r["worker"] and r["run_wall_s"] > 0 for r in json.loads(dask.read_text())["timing"]["runs"])
    # the metrics move with the swept fields and every run is a real closed-loop run
    assert [r["params"] for r in a["runs"]][:2] == [{"controller.eps_t_nm": 0.2, "controller.dt_s": 4e-5},
                                                   {"controller.eps_t_nm": 0.2, "controller.dt_s": 5e-5}]
    cal = [r["strategies"]["s1"]["Cal_ave"] for r in a["runs"] if r["params"]["controller.dt_s"] == 5e-5]
    assert cal[0] > cal[1] > cal[2]  # a wider band holds the zero vector more often (seed Table 2)
    assert len({r["config_hash"] for r in a["runs"]}) == 6
    for r in a["runs"]:
        for m in r["strategies"].values():
            assert m["faults"] == 0 and "wall_s" not in m and "periods_per_s" not in m
    with open(out["csv"]) as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 12 and {"controller.eps_t_nm", "controller.dt_s", "strategy", "T_rip_RMSE_nm"} <= set(rows[0])
    assert float(rows[0]["T_rip_RMSE_nm"]) == a["runs"][0]["strategies"]["conventional"]["T_rip_RMSE_nm"]
    assert out["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out["png"].stat().st_size > 20_000


def test_local_cluster_monte_carlo_matches_serial(tmp_path, capsys):
    args = ["sweep", str(IPMSM), *SHORT, "-q", "--strategies", "s1", "--monte-carlo", "6", "--seed", "3",
            "--spread", "controller.eps_t_nm=+-40", "--spread", "plant.rs_ohm=+-20"]
    serial, dask, png = tmp_path / "serial.json", tmp_path / "dask.json", tmp_path / "mc.png"
    assert main([*args, "--serial", "--json", str(serial)]) == 0
    assert main([*args, "--workers", "2", "--json", str(dask), "--plot", str(png)]) == 0
    table = capsys.readouterr().out
    assert "monte-carlo sweep, 6 runs" in table and "T_rip_RMSE_nm" in table and "plant.rs_ohm 0.25 +-20%" in table
    a, b = _without_timing(serial), _without_timing(dask)
    assert a == b
    assert a["monte_carlo"]["spreads"][1] == {"field": "plant.rs_ohm", "percent": 20.0, "nominal": 0.25}
    eps = [r["params"]["controller.eps_t_nm"] for r in a["runs"]]
    assert len(set(eps)) == 6 and all(0.45 <= e <= 1.05 for e in eps)
    assert len({r["strategies"]["s1"]["T_rip_RMSE_nm"] for r in a["runs"]}) == 6
    assert png.stat().st_size > 20_000


def test_ttype_lambda1_sweep(tmp_path, capsys):
    js = tmp_path / "lambda.json"
    assert main(["sweep", str(TTYPE), "--set", "scenario.duration_s=0.05", "-q", "--serial", "--strategies", "mpdtc63",
                 "--param", "controller.lambda_psi_nm_per_wb=0,28", "--json", str(js)]) == 0
    data = json.loads(js.read_text())
    assert "lambda_psi_nm_per_wb" in capsys.readouterr().out
    runs = data["runs"]
    assert [r["params"]["controller.lambda_psi_nm_per_wb"] for r in runs] == [0, 28]
    scen = runs[0]["strategies"]["mpdtc63"]
    assert scen and all("T_rip_RMSE_nm" in m for m in scen.values())
    assert runs[0]["strategies"] != runs[1]["strategies"]


def test_remote_scheduler_matches_serial(tmp_path):
    from distributed import LocalCluster

    args = ["sweep", str(SPMSM), *SHORT, "-q", "--strategies", "s1", "--param", "controller.eps_t_nm=0.3,0.9"]
    serial, remote = tmp_path / "serial.json", tmp_path / "remote.json"
    assert main([*args, "--serial", "--json", str(serial)]) == 0
    with LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=None) as cluster:
        assert main([*args, "--scheduler", cluster.scheduler_address, "--json", str(remote)]) == 0
    assert _without_timing(serial) == _without_timing(remote)
    assert json.loads(remote.read_text())["timing"]["runner"] == "scheduler"

"""The plant's actuation delay with the generated controllers (compiled C in the loop).

``plant.actuation_delay_periods = d`` is the plant's timing, set independently of
``controller.delay_compensation`` (what the controller assumes): every combination
runs through ``mpcgen simulate`` for both topologies.  With the plant's delay
matching the controller's assumption (d >= 1 with compensation), the two-level
dq-euler step's k+1 prediction (``te_est_nm``, ``psi_est_wb``) equals the plant's
torque and flux at k+1 up to the forward-Euler error of one period; with d = 0 the
prediction assumes a vector that is never applied, and misses by far more.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.topologies.twolevel import sim
from codegen.topology import topology_of

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SPMSM, IPMSM, TLEVEL = (EXAMPLES / f"{n}.toml" for n in ("seed001_spmsm", "seed001_ipmsm", "seed000_tlevel"))

SHORT_2L = ["--set", "scenario.duration_s=0.1", "--set", "scenario.speed_ref_rpm=[[0.0,500.0]]",
            "--set", "scenario.load_nm=[[0.0,5.0]]", "--set", "scenario.window_s=0.05"]
SHORT_3L = ["--set", "scenario.set=config", "--set", "scenario.duration_s=0.05", "--set", "scenario.window_s=0.02"]


def _simulate(tmp_path: Path, *argv: str) -> dict:
    out = tmp_path / "sim.json"
    assert main(["simulate", *argv, "--json", str(out), "-q"]) == 0
    return json.loads(out.read_text())


@pytest.mark.parametrize("d", [0, 1, 2])
@pytest.mark.parametrize("config,strategy,short,comps", [
    (SPMSM, "conventional", SHORT_2L, ["--delay-compensation", "--no-delay-compensation"]),
    (TLEVEL, "mpdtc63", SHORT_3L, ["--delay-compensation"]),
], ids=["two-level", "t-type"])
def test_every_delay_and_compensation_runs(tmp_path, config, strategy, short, comps, d):
    for comp in comps:
        data = _simulate(tmp_path, str(config), "--strategies", strategy, comp,
                         "--set", f"plant.actuation_delay_periods={d}", *short)
        assert list(data["strategies"]) == [strategy]
        _assert_metrics(data["strategies"][strategy])


def test_the_issue_command_runs(tmp_path):
    """``simulate CONFIG --set plant.actuation_delay_periods=1 --no-delay-compensation``."""
    data = _simulate(tmp_path, str(SPMSM), "--set", "plant.actuation_delay_periods=1", "--no-delay-compensation")
    assert data["strategies"]
    for result in data["strategies"].values():
        _assert_metrics(result)


def test_no_delay_compensation_is_refused_where_the_step_always_compensates(tmp_path, capsys):
    """The T-type MPDTC step always compensates the one-period delay: ``--no-delay-compensation`` would
    change only the simulated plant, so it is refused in one line (exit 2), before any run."""
    out = tmp_path / "sim.json"
    assert main(["simulate", str(TLEVEL), "--no-delay-compensation", "--json", str(out), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "controller.delay_compensation = False" in err and "allowed: true" in err, err
    assert not out.exists()


def _values(d: object, key: str) -> list[object]:
    """Every value stored under ``key`` anywhere in a simulate result (the topologies nest differently)."""
    if isinstance(d, dict):
        return [v for k, v in d.items() if k == key] + [x for v in d.values() for x in _values(v, key)]
    if isinstance(d, list):
        return [x for v in d for x in _values(v, key)]
    return []


def _assert_metrics(result: dict) -> None:
    """The run has a finite torque ripple and a positive switching frequency."""
    def numbers(key: str) -> list[float]:  # the metric values (a window's description shares the key)
        return [v for v in _values(result, key) if isinstance(v, (int, float))]

    ripple, f_ave = numbers("T_rip_RMSE_nm"), numbers("f_ave_hz")
    assert ripple and f_ave
    assert all(math.isfinite(r) and r > 0 for r in ripple), ripple
    assert all(math.isfinite(f) and f > 0 for f in f_ave), f_ave


def _forward_euler_bound(model, tr) -> tuple[float, float]:
    """Largest torque and flux errors of one forward-Euler step of the dq current equations over dt.

    The step's local error is |i(t+dt) - i_Euler| <= dt^2/2 max|d^2i/dt^2|; differentiating
    L di/dt = u_dq - Rs i -+ w_e L i - w_e psi_f (the applied alpha-beta voltage rotating at w_e in
    the rotor frame, the speed changing by dw_e/dt):
      |d^2i/dt^2| <= w_e |u|/L_min + (Rs/L_min + w_e L_max/L_min) |di/dt| + |dw_e/dt| (L_max |i| + psi_f)/L_min,
      |di/dt|     <= (|u| + (Rs + w_e L_max) |i| + w_e psi_f)/L_min,
    with |u| = 2/3 Udc, and maxima over the run.  Torque and flux follow from the current error:
    |dTe| <= 1.5 p (psi_f + |Ld - Lq| 2|i|) |di|, |d psi| <= L_max |di|; plus float32 rounding.
    """
    m, dt = model.motor, model.controller.dt_s
    lmin, lmax = min(m.ld_h, m.lq_h), max(m.ld_h, m.lq_h)
    u = 2.0 / 3.0 * model.inverter.udc_v
    w = m.pole_pairs * float(np.max(np.abs(tr.omega_m_rad_s)))
    dw = m.pole_pairs * float(np.max(np.abs(np.diff(tr.omega_m_rad_s)))) / dt
    i = float(np.max(np.hypot(tr.ia_a, (tr.ia_a + 2 * tr.ib_a) / math.sqrt(3))))
    di = (u + (m.rs_ohm + w * lmax) * i + w * m.psi_f_wb) / lmin
    d2i = w * u / lmin + (m.rs_ohm / lmin + w * lmax / lmin) * di + dw * (lmax * i + m.psi_f_wb) / lmin
    e_i = dt * dt / 2.0 * d2i
    te = 1.5 * m.pole_pairs * (m.psi_f_wb + abs(m.ld_h - m.lq_h) * 2 * i) * e_i
    return te + 1e-4, lmax * e_i + 1e-6  # + float32 rounding of the estimates


@pytest.mark.parametrize("config", [SPMSM, IPMSM], ids=["spmsm", "ipmsm"])
def test_k_plus_1_prediction_matches_the_plant_when_the_delay_does(config):
    ov = {"controller.predictor": "dq-euler", "controller.delay_compensation": True, "scenario.duration_s": 0.3,
          "scenario.speed_ref_rpm": [[0.0, 500.0]], "scenario.load_nm": [[0.0, 8.0]]}
    errs = {}
    for d in (1, 2, 0):
        model = load_config(config, {**ov, "plant.actuation_delay_periods": d})
        topo = topology_of(model)
        lib = topo.host_library(model, topo.derive(model), with_sim=True)
        tr = sim.run_closed_loop(lib.ffi, lib.lib, model)
        assert np.all(tr.fault == 0)
        e_te = np.abs(tr.te_est_nm[:-1].astype(np.float64) - tr.te_nm[1:])
        e_psi = np.abs(tr.psi_est_wb[:-1].astype(np.float64) - tr.psi_wb[1:])
        errs[d] = (float(e_te.max()), float(e_psi.max()), float(np.sqrt(np.mean(e_te**2))), _forward_euler_bound(model, tr))
    for d in (1, 2):  # the vector the step predicts under (prev_sw) is the one applied during [k, k+1)
        te_max, psi_max, _, (te_bound, psi_bound) = errs[d]
        assert te_max <= te_bound and psi_max <= psi_bound, (d, errs[d])
    te_max, psi_max, te_rms, (te_bound, psi_bound) = errs[0]
    assert te_max > 20 * te_bound and te_rms > 10 * te_bound and psi_max > 10 * psi_bound, errs[0]

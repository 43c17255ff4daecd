"""``[plant]`` parameter overrides change the simulated plant, never the generated controller.

The generated C is byte-identical with and without overrides (they are left
out of the config hash); the plant the simulator integrates takes them, so a
mismatch between the controller's model and the plant shows in the run: with
a plant magnet flux psi_f' the plant's torque differs from the controller's
current-model estimate by 1.5 p (psi_f' - psi_f) i_q.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.topologies.ttype import sim as ttype_sim
from codegen.topologies.twolevel import sim as twolevel_sim
from codegen.topology import topology_of

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SPMSM, TLEVEL = EXAMPLES / "seed001_spmsm.toml", EXAMPLES / "seed000_tlevel.toml"
OVERRIDES = ["plant.rs_ohm=0.5", "plant.ld_h=9e-3", "plant.lq_h=9.5e-3", "plant.psi_f_wb=0.2", "plant.j_kgm2=0.02",
             "plant.b_nms=0.01", "plant.udc_v=300", "plant.dead_time_s=1e-6", "plant.noise_a=0.1",
             "plant.actuation_delay_periods=2", "plant.encoder_bits=12"]
SHORT_2L = {"scenario.duration_s": 0.2, "scenario.speed_ref_rpm": [[0.0, 500.0]], "scenario.load_nm": [[0.0, 8.0]]}


def _files(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("config,strategy", [(SPMSM, "conventional"), (TLEVEL, "mpdtc63")])
def test_generated_code_is_byte_identical_with_plant_overrides(tmp_path, config, strategy):
    plain, over = tmp_path / "plain", tmp_path / "over"
    assert main(["generate", str(config), "--strategy", strategy, "-o", str(plain), "-q"]) == 0
    sets = [a for o in OVERRIDES + (["plant.c_f=5e-4"] if config == TLEVEL else []) for a in ("--set", o)]
    assert main(["generate", str(config), "--strategy", strategy, "-o", str(over), "-q", *sets]) == 0
    a, b = _files(plain), _files(over)
    assert a and a.keys() == b.keys()
    assert [k for k in a if a[k] != b[k]] == []


def _run(config: Path, overrides: dict):
    model = load_config(config, overrides)
    topo = topology_of(model)
    lib = topo.host_library(model, topo.derive(model), with_sim=True)
    sim = twolevel_sim if topo.name == "two-level" else ttype_sim
    return model, lib, sim.run_closed_loop(lib.ffi, lib.lib, model)


def _iq(tr) -> np.ndarray:
    """Plant q-axis current from the plant's phase currents and angle (Clarke, Park)."""
    i_al = tr.ia_a
    i_be = (tr.ia_a + 2 * tr.ib_a) / np.sqrt(3)
    return i_be * np.cos(tr.theta_e_rad) - i_al * np.sin(tr.theta_e_rad)


def test_override_changes_the_plant_not_the_controller():
    base_model, base_lib, base = _run(SPMSM, SHORT_2L)
    model, lib, tr = _run(SPMSM, {**SHORT_2L, "plant.psi_f_wb": 0.2, "plant.rs_ohm": 0.4})
    assert lib.build_dir == base_lib.build_dir  # the same compiled controller
    p = twolevel_sim.params_from_model(lib.ffi, model)
    assert (p.common.psi_f_wb, p.common.rs_ohm, p.common.ld_h) == (0.2, 0.4, model.motor.ld_h)
    assert model.motor.psi_f_wb == 0.175
    assert not np.array_equal(tr.ia_a, base.ia_a)  # the simulated currents change
    # the controller's estimate (its own psi_f, from the sampled currents at k) against the plant's torque
    te_est = tr.te_est_nm.astype(np.float64)
    np.testing.assert_allclose(base.te_nm, base.te_est_nm.astype(np.float64), atol=2e-3)
    mismatch = 1.5 * model.motor.pole_pairs * (0.2 - 0.175) * _iq(tr)
    np.testing.assert_allclose(tr.te_nm - te_est, mismatch, atol=2e-3)
    assert np.max(np.abs(mismatch)) > 0.5
    # the speed loop holds the same speed with the stronger magnet, with less current for the same torque
    assert abs(np.mean(tr.speed_rpm[-500:]) - np.mean(base.speed_rpm[-500:])) < 2.0
    ratio = np.mean(np.abs(_iq(tr)[-500:])) / np.mean(np.abs(_iq(base)[-500:]))
    assert ratio == pytest.approx(0.175 / 0.2, rel=0.03)


def test_ttype_override_of_the_dc_link():
    model, lib, tr = _run(TLEVEL, {"scenario.set": "config", "scenario.duration_s": 0.05, "plant.udc_v": 240.0,
                                   "plant.c_f": 2e-4})
    p = ttype_sim.params_from_model(lib.ffi, model)
    assert (p.common.udc_v, p.c_f) == (240.0, 2e-4) and model.inverter.udc_v == 220.0
    assert tr.udc_v == 240.0
    rec = ttype_sim.controller_inputs(tr, model)
    # the controller measures the plant's DC link: u_c1 + u_c2 = 240 V
    np.testing.assert_allclose(rec["uc1_v"].astype(float) + rec["uc2_v"].astype(float), 240.0, atol=1e-4)
    _, _, small = _run(TLEVEL, {"scenario.set": "config", "scenario.duration_s": 0.05, "plant.udc_v": 240.0,
                                "plant.c_f": 1e-3})
    assert np.std(tr.vo_v[200:]) > 2 * np.std(small.vo_v[200:])  # a smaller capacitor: more V_o ripple

"""Plots (codegen/plots.py) write non-empty PNGs."""
from __future__ import annotations

import dataclasses

from codegen.topologies.twolevel.metrics import two_level_metrics
from codegen.topologies.twolevel.plots import plot_two_level
from codegen.topologies.twolevel.sim import run_closed_loop


def test_plots_write_pngs(stub, spmsm_model, tmp_path):
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    model = spmsm_model.replace(
        scenario=dataclasses.replace(spmsm_model.scenario, duration_s=0.6,
                                     load_nm=((0.0, 10.0), (0.3, -10.0))))
    tr = run_closed_loop(ffi, lib, model)
    paths = plot_two_level(tr, model, "conventional", tmp_path / "plots", two_level_metrics(tr, model))
    names = sorted(p.name for p in paths)
    assert names == sorted(f"conventional_{w}.png" for w in ("speed", "torque", "flux", "locus", "currents",
                                                                 "spectrum"))
    for p in paths:
        data = p.read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5_000, p


def test_plots_without_running_window(stub, spmsm_model, tmp_path):
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    model = spmsm_model.replace(
        scenario=dataclasses.replace(spmsm_model.scenario, duration_s=0.1, speed_ref_rpm=((0.0, 0.0),)))
    tr = run_closed_loop(ffi, lib, model)
    paths = plot_two_level(tr, model, "s1", tmp_path, two_level_metrics(tr, model))
    assert len(paths) >= 5 and all(p.stat().st_size > 5_000 for p in paths)

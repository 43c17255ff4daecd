"""`simulate --plots`: every topology's plot set, titles that name what they cover, and spectra drawn over
exactly the THD window, fundamental and THD the table and the JSON report (issue 28)."""
from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

from codegen.cli import main
from codegen.metrics import thd
from codegen.simulator.figures import flux_alpha_beta, plot_spectrum

from conftest import EXAMPLES, IPMSM, SPMSM, TTYPE, TTYPE_STRATEGIES, TWO_LEVEL

#: short scenarios of the examples: a start, a load step, a steady window after it
SHORT = {
    "ipmsm": (IPMSM, ["scenario.duration_s=0.3", "scenario.speed_ref_rpm=[[0.0, 1000.0]]",
                      "scenario.load_nm=[[0.0, 0.0], [0.15, 15.0]]", "scenario.window_s=0.08"]),
    "spmsm": (SPMSM, ["scenario.duration_s=0.3", "scenario.speed_ref_rpm=[[0.0, 500.0]]",
                      "scenario.load_nm=[[0.0, 0.0], [0.15, 10.0]]", "scenario.window_s=0.08"]),
    "servo400w": (EXAMPLES / "servo400w.toml", ["scenario.duration_s=0.2", "scenario.load_nm=[[0.0, 0.0], [0.1, 1.27]]",
                                                "scenario.window_s=0.05"]),
    # the T-type config scenario: +1000 then -1000 r/min (the trial's run)
    "tlevel": (TTYPE, ["scenario.set=config", "scenario.duration_s=0.3",
                       "scenario.speed_ref_rpm=[[0.0, 1000.0], [0.15, -1000.0]]", "scenario.window_s=0.1"]),
    # the T-type Table 5 set, shortened: steady runs of 0.25 s, the load step of 0.2 s
    "tlevel-table5": (TTYPE, ["scenario.duration_s=0.1", "scenario.window_s=0.05"]),
}
PLOTS = ("speed", "torque", "flux", "locus", "currents", "spectrum")


def _png_text(path: Path) -> dict[str, str]:
    with Image.open(path) as im:
        return dict(im.text)  # type: ignore[attr-defined]


def _simulate(tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str) -> tuple[dict[str, Any], str, Path]:
    cfg, sets = SHORT[name]
    js, plots = tmp_path / "sim.json", tmp_path / "plots"
    args = ["simulate", str(cfg), "--json", str(js), "--plots", str(plots), "-q"]
    for s in sets:
        args += ["--set", s]
    assert main(args) == 0
    return json.loads(js.read_text()), capsys.readouterr().out, plots


def _shown_runs(data: dict[str, Any]) -> list[tuple[str, dict[str, Any], dict[str, Any]]]:
    """(label, the run's entry holding ``plots``, the metrics its table row prints) of every run."""
    out = []
    for s, per in data["strategies"].items():
        if "plots" in per:  # two-level: one run per strategy
            out.append((s, per, per))
            continue
        for key, m in per.items():
            if key.endswith("_steady") or "plots" not in m:
                continue
            out.append((f"{s}/{key}", m, per.get(f"{key}_steady", m)))
    return out


def _check_spectrum(label: str, png: Path, shown: dict[str, Any], table: str) -> None:
    info, value = shown["window"]["THD_ia_percent"], shown["THD_ia_percent"]
    text = _png_text(png)
    desc = json.loads(text["Description"])
    assert desc["computed"], (label, desc)
    # the plotted window, fundamental and THD are the JSON's, to the last bit
    assert (desc["t0_s"], desc["t1_s"], desc["f1_hz"], desc["n_periods"]) == (
        info["t0_s"], info["t1_s"], info["f1_hz"], info["n_periods"]), label
    assert desc["thd_percent"] == value, label
    # the title states them as the table prints them
    span = f"[{info['t0_s']:.4g}, {info['t1_s']:.4g}) s"
    title = text["Title"]
    assert f"THD window {span}" in title and f"f1 = {info['f1_hz']:.4g} Hz" in title, (label, title)
    assert f"THD = {value:.2f} %" in title and f"{info['n_periods']} periods" in title, (label, title)
    rows = [r for r in table.splitlines() if f"[{info['t0_s']:.4g}, {info['t1_s']:.4g})" in r
            and f"{info['f1_hz']:8.4g}" in r and f"{value:.2f}" in r]
    assert rows, (label, "no table row with the plotted window, f1 and THD", table)


@pytest.mark.parametrize("name", ["ipmsm", "spmsm", "servo400w", "tlevel", "tlevel-table5"])
def test_spectrum_plots_show_the_tables_thd(tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str) -> None:
    data, table, plots = _simulate(tmp_path, capsys, name)
    runs = _shown_runs(data)
    assert runs
    for label, entry, shown in runs:
        spectra = [Path(p) for p in entry["plots"] if p.endswith("_spectrum.png")]
        assert len(spectra) == 1, (label, entry["plots"])
        _check_spectrum(label, spectra[0], shown, table)


def test_two_level_plot_set(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data, _table, plots = _simulate(tmp_path, capsys, "ipmsm")
    names = {p.name for p in plots.glob("*.png")}
    assert names == {f"{s}_{k}.png" for s in TWO_LEVEL for k in PLOTS}
    speed = _png_text(plots / "conventional_speed.png")["Title"]
    assert "config scenario (n* = 1000 r/min, T_L = 0/15 N*m)" in speed and "whole run [0, 0.3) s" in speed
    locus = _png_text(plots / "conventional_locus.png")["Title"]
    info = data["strategies"]["conventional"]["window"]["THD_ia_percent"]
    assert f"stator-flux locus, THD window [{info['t0_s']:.4g}, {info['t1_s']:.4g}) s" in locus


def test_ttype_config_run_plots(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The +1000/-1000 r/min run: named after the strategy (not a speed), titled with its whole profile."""
    data, _table, plots = _simulate(tmp_path, capsys, "tlevel")
    names = {p.name for p in plots.glob("*.png")}
    assert names == {f"{s}_{k}.png" for s in TTYPE_STRATEGIES for k in (*PLOTS, "vo", "uab")}
    for s in TTYPE_STRATEGIES:
        for k in (*PLOTS, "vo", "uab"):
            title = _png_text(plots / f"{s}_{k}.png")["Title"]
            assert f"{s}, config scenario (n* = 1000/-1000 r/min" in title, title
            assert "rpm" not in title
        assert "rotor speed, whole run [0, 0.3) s" in _png_text(plots / f"{s}_speed.png")["Title"]
        info = data["strategies"][s]["scenario"]["window"]["THD_ia_percent"]
        assert f"THD window [{info['t0_s']:.4g}, {info['t1_s']:.4g}) s" in _png_text(plots / f"{s}_locus.png")["Title"]


def test_ttype_table5_plots(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data, _table, plots = _simulate(tmp_path, capsys, "tlevel-table5")
    names = {p.name for p in plots.glob("*.png")}
    runs = ("300rpm", "1800rpm", "3000rpm", "loadstep")
    assert names == {f"{s}_{r}_{k}.png" for s in TTYPE_STRATEGIES for r in runs for k in (*PLOTS, "vo", "uab")}
    title = _png_text(plots / "mpdtc63_1800rpm_speed.png")["Title"]
    assert "steady run, speed imposed (n* = 1800 r/min" in title and "whole run [0, 0.25) s" in title, title
    title = _png_text(plots / "mpdtc63_loadstep_torque.png")["Title"]
    assert "rated-load step" in title and "whole run [0, 0.2) s" in title, title
    assert data["strategies"]["mpdtc63"]["1800rpm"]["plots"]


def test_flux_locus_has_the_plant_flux_magnitude() -> None:
    """psi_alpha, psi_beta from the plant's currents and angle (the plant's Ld): their magnitude is the
    trace's psi_wb."""
    from codegen.config import load_config
    from codegen.topologies.twolevel.scenarios import run_variant

    model = load_config(IPMSM, {"scenario.duration_s": 0.05, "scenario.speed_ref_rpm": [[0.0, 1000.0]],
                                "scenario.load_nm": [[0.0, 5.0]], "plant.ld_h": 0.006})  # the plant's Ld differs
    trace, _wall = run_variant(model, lambda _m: None)
    psi_a, psi_b = flux_alpha_beta(trace, model)
    np.testing.assert_allclose(np.hypot(psi_a, psi_b), trace.psi_wb, rtol=1e-12, atol=1e-15)
    # it turns with the rotor: the flux angle minus theta_e is the load angle, well inside +-90 degrees
    delta = np.angle(np.exp(1j * (np.arctan2(psi_b, psi_a) - trace.theta_e_rad)))
    assert np.all(np.abs(delta[len(delta) // 2:]) < math.pi / 2)


def _synthetic(f1: float = 50.0, dt: float = 1e-4, n: int = 4000) -> tuple[np.ndarray, dict[str, Any]]:
    t = np.arange(n) * dt
    x = 10 * np.sin(2 * np.pi * f1 * t) + 0.5 * np.sin(2 * np.pi * 5 * f1 * t) + 0.2 * np.sin(2 * np.pi * 7 * f1 * t)
    value, info = thd(x, dt, 0.1, 0.4, f1, 2e3)
    return x, {"THD_ia_percent": value, "window": {"THD_ia_percent": info}}


def test_spectrum_over_the_metrics_window(tmp_path: Path) -> None:
    x, m = _synthetic()
    path = plot_spectrum(tmp_path / "s.png", "synthetic", x, 1e-4, m)
    desc = json.loads(_png_text(path)["Description"])
    assert desc["t0_s"] == 0.1 and desc["n_periods"] == 15 and desc["thd_percent"] == m["THD_ia_percent"]
    assert math.isclose(desc["thd_percent"], 100 * math.hypot(0.5, 0.2) / 10, rel_tol=1e-9)
    assert re.search(r"THD window \[0\.1, 0\.4\) s, 15 periods of f1 = 50 Hz, THD = 5\.39 %", _png_text(path)["Title"])


@pytest.mark.parametrize("tamper", ["samples", "thd"])
def test_spectrum_refuses_another_window(tmp_path: Path, tamper: str) -> None:
    """A spectrum whose samples or THD would differ from the metric's is an error, never a figure."""
    x, m = _synthetic()
    if tamper == "samples":
        m["window"]["THD_ia_percent"]["n_samples"] -= 7
    else:
        m["THD_ia_percent"] *= 1.01
    with pytest.raises(RuntimeError, match="spectrum"):
        plot_spectrum(tmp_path / "s.png", "synthetic", x, 1e-4, m)
    assert not (tmp_path / "s.png").exists()


def test_spectrum_without_thd_says_why(tmp_path: Path) -> None:
    x, _m = _synthetic()
    m = {"THD_ia_percent": math.nan,
         "window": {"THD_ia_percent": {"not_computed_reason": "no steady window with a nonzero speed reference"}}}
    path = plot_spectrum(tmp_path / "s.png", "synthetic", x, 1e-4, m)
    text = _png_text(path)
    assert not json.loads(text["Description"])["computed"]
    assert "not computed (no steady window with a nonzero speed reference)" in text["Title"]

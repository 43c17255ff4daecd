"""Seed 001's published figures next to ours (``mpcgen simulate --paper``).

Which tables apply depends on the config's motor: the seed's SPMSM
(section 3: Table 2's conventional and eps_T rows, Table 11's counts and
computation-time ratios; with ``--sweep-eps`` Tables 1 and 2) or its IPMSM
(section 6: Table 9 and the ratios its text draws).  Any other motor has no
published figures (one line says so).  The published numbers are the data
of :mod:`codegen.topologies.twolevel.published`, never typed here.
"""
from __future__ import annotations

import math
from typing import Any

from codegen.model import Model
from codegen.paper import no_figures, pair_cell, pair_head, pct_cell, percent, side
from codegen.results import clean_json
from codegen.topologies.twolevel import published as pub

__all__ = ["seed_case", "paper_table"]

SIMPLIFIED = ("s1", "s2", "s3")
#: (result key, Table 9 field, heading, format, scale)
T9_COLUMNS = (("T_rip_RMSE_nm", "t_rip_nm", "T_rip/N*m", "7.4f", 1.0),
              ("psi_rip_RMSE_wb", "psi_rip_wb", "psi_rip/Wb", "7.4f", 1.0),
              ("THD_ia_percent", "thd_percent", "THD/%", "6.2f", 1.0),
              ("Cal_ave", "cal_ave", "Cal_ave", "5.2f", 1.0),
              ("f_ave_hz", "f_ave_khz", "f_ave/kHz", "5.2f", 1e-3))


def _same(a: float, b: float) -> bool:
    return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=0.0)


def seed_case(model: Model) -> str | None:
    """"spmsm" or "ipmsm" when the config's motor is the seed's of that section, else None."""
    m = model.motor
    for case, seed in (("spmsm", pub.SPMSM_MOTOR), ("ipmsm", pub.IPMSM_MOTOR)):
        if m.pole_pairs == seed.pole_pairs and all(_same(getattr(m, f), getattr(seed, f))
                                                   for f in ("rs_ohm", "ld_h", "lq_h", "psi_f_wb")):
            return case
    return None


def _scenario_note(model: Model, paper_s: float) -> str:
    d = model.scenario.duration_s
    if _same(d, paper_s):
        return f"our run: the paper's {paper_s:g} s scenario"
    return f"our run: {d:g} s, the paper's {paper_s:g} s (figures over a different run: compare with care)"


def _no_motor(model: Model, what: str) -> dict[str, Any]:
    return no_figures(f"{model.name}'s motor is neither seed 001's SPMSM (section 3) nor its IPMSM (section 6); "
                      f"{what}")


def paper_table(model: Model, data: dict[str, Any]) -> dict[str, Any]:
    """Published vs ours for the result ``data`` of ``simulate`` (or of ``--sweep-eps``: it has
    ``table2``); JSON-ready with a printable ``_table``."""
    case = seed_case(model)
    if "table2" in data:
        if case != "spmsm":
            return _no_motor(model, "Tables 1-2 (the eps_T sweep) belong to the SPMSM") if case is None else \
                no_figures("Tables 1-2 (the eps_T sweep) belong to seed 001's SPMSM; this is its IPMSM")
        return clean_json(_sweep(model, data))
    if case == "ipmsm":
        return clean_json(_table9(model, data["strategies"]))
    if case == "spmsm":
        return clean_json(_spmsm(model, data["strategies"]))
    return _no_motor(model, "Table 9 belongs to the IPMSM, Tables 2 and 11 to the SPMSM")


# ---------------------------------------------------------------------------
# IPMSM: Table 9 and its ratios
# ---------------------------------------------------------------------------
def _ratio_lines(rows: list[dict[str, Any]], title: str) -> list[str]:
    """``title`` then one line per ratio: published and ours per strategy s1..s3."""
    out = [title, f"  {'':48s}" + "".join(f"{s + ' paper':>9s} {s + ' ours':>8s}  " for s in SIMPLIFIED)]
    names = list(dict.fromkeys(r["name"] for r in rows))
    for name in names:
        cells = {r["strategy"]: r for r in rows if r["name"] == name}
        line = f"  {name:48s}"
        for s in SIMPLIFIED:
            r = cells.get(s, {"published": None, "ours": None})
            line += f"{pct_cell(r['published'], 9)} {pct_cell(r['ours'], 8)}  "
        out.append(line.rstrip())
    return out


def _table9(model: Model, results: dict[str, dict[str, Any]]) -> dict[str, Any]:
    published = {r.strategy: r for r in pub.TABLE9_IPMSM}
    zero = dict(pub.TABLE9_ZERO_VECTOR_PERCENT)
    rows: list[dict[str, Any]] = []
    for s, p in published.items():
        ours = results.get(s, {})
        rows.append({"strategy": s, **{key: side(_published(p, f), ours.get(key)) for key, f, *_ in T9_COLUMNS},
                     "zero_vector_percent": side(zero[s], ours.get("zero_vector_percent"))})
    conv = results.get("conventional", {})
    ratios: list[dict[str, Any]] = []
    for s in SIMPLIFIED:
        ours = results.get(s, {})
        ratios += [
            {"name": "f_ave vs conventional / %", "strategy": s, "published": pub.TABLE9_F_AVE_RATIO_PERCENT[s],
             "ours": percent(ours.get("f_ave_hz"), conv.get("f_ave_hz")), "source": "seed 001 section 6 text"},
            {"name": "Cal_ave vs conventional / %", "strategy": s, "published": pub.TABLE9_CAL_AVE_RATIO_PERCENT[s],
             "ours": percent(ours.get("Cal_ave"), conv.get("Cal_ave")), "source": "seed 001 section 6 text"},
            {"name": "T_rip vs conventional / %", "strategy": s,
             "published": percent(published[s].t_rip_nm, published["conventional"].t_rip_nm),
             "ours": percent(ours.get("T_rip_RMSE_nm"), conv.get("T_rip_RMSE_nm")), "source": "seed 001 Table 9"},
            {"name": "zero-vector use / %", "strategy": s,
             "published": zero[s], "ours": ours.get("zero_vector_percent"), "source": "seed 001 section 6 text"},
        ]
    head = "".join(f" {pair_head(h, spec)}  " for _k, _f, h, spec, _x in T9_COLUMNS)
    lines = [f"paper: seed 001 Table 9 (IPMSM, section 6), published | ours; {_scenario_note(model, pub.IPMSM_DURATION_S)}",
             f"  {'strategy':12s}{head}",
             f"  {'':12s}" + "".join(f" {pair_head('paper    ours', spec)}  " for *_a, spec, _x in T9_COLUMNS)]
    for r in rows:
        lines.append(f"  {r['strategy']:12s}" + "".join(f" {pair_cell(r[k], spec, x)}  "
                                                        for k, _f, _h, spec, x in T9_COLUMNS))
    lines += _ratio_lines(ratios, "ratios the paper draws (strategy / conventional, %):")
    lines.append(f"  zero-vector use of the conventional controller: {_zero_conv(zero, conv)} %")
    lines.append("  computation time vs conventional (seed 001 Table 11, the SPMSM on an STM32H743): published "
                 + "/".join(f"{pub.TABLE11_TIME_RATIO_PERCENT[s]:.2f}" for s in SIMPLIFIED)
                 + " %; ours: not measured by simulate (mpcgen bench times the step)")
    return {"available": True, "source": "seed 001 Table 9 (IPMSM)", "rows": rows, "ratios": ratios,
            "_table": "\n".join(lines)}


def _zero_conv(zero: dict[str, float], conv: dict[str, Any]) -> str:
    ours = conv.get("zero_vector_percent")
    return f"paper {zero['conventional']:.2f}, ours " + ("n/a" if ours is None else f"{ours:.2f}")


# ---------------------------------------------------------------------------
# SPMSM scenario: Table 2's conventional and eps_T rows, Table 11
# ---------------------------------------------------------------------------
T2_COLUMNS = (("T_rip_RMSE_nm", "t_rip_nm", "T_rip/N*m", "7.4f", 1.0),
              ("psi_rip_RMSE_wb", "psi_rip_wb", "psi_rip/Wb", "7.4f", 1.0),
              ("Cal_ave", "cal_ave", "Cal_ave", "5.2f", 1.0),
              ("f_ave_hz", "f_ave_khz", "f_ave/kHz", "5.2f", 1e-3))


def _published(p: Any, f: str) -> float | None:
    """Field ``f`` of a published row in our units (kHz -> Hz); None without a row."""
    if p is None:
        return None
    return float(getattr(p, f)) * (1e3 if f == "f_ave_khz" else 1.0)


def _t2_row(label: str, p: pub.Table2Row | None, ours: dict[str, Any]) -> dict[str, Any]:
    return {"row": label, **{k: side(_published(p, f), ours.get(k)) for k, f, *_ in T2_COLUMNS}}


def _t2_lines(rows: list[dict[str, Any]], label_head: str) -> list[str]:
    head = "".join(f" {pair_head(h, spec)}  " for _k, _f, h, spec, _x in T2_COLUMNS)
    lines = [f"  {label_head:14s}{head}",
             f"  {'':14s}" + "".join(f" {pair_head('paper    ours', spec)}  " for *_a, spec, _x in T2_COLUMNS)]
    for r in rows:
        lines.append(f"  {r['row']:14s}" + "".join(f" {pair_cell(r[k], spec, x)}  " for k, _f, _h, spec, x in T2_COLUMNS))
    return lines


def _table2_at(eps: float) -> pub.Table2Row | None:
    return next((r for r in pub.TABLE2_THRESHOLD_SWEEP if _same(r.band_nm, eps)), None)


def _spmsm(model: Model, results: dict[str, dict[str, Any]]) -> dict[str, Any]:
    eps = float(model.controller.eps_t_nm)
    t2 = _table2_at(eps)
    rows = [_t2_row("conventional", pub.TABLE2_CONVENTIONAL, results.get("conventional", {})),
            _t2_row(f"s1 eps_T {eps:g}", t2, results.get("s1", {}))]
    conv = results.get("conventional", {})
    t11 = {r.strategy: r for r in pub.TABLE11_TIMING}
    ratios: list[dict[str, Any]] = []
    for s in SIMPLIFIED:
        ours = results.get(s, {})
        ratios += [
            {"name": "V0 output directly / % of steps (Table 11)", "strategy": s,
             "published": 100.0 * t11[s].zero_outputs / pub.TABLE11_STEPS, "ours": ours.get("shortcut_percent"),
             "source": "seed 001 Table 11"},
            {"name": "computation time vs conventional / % (Table 11)", "strategy": s,
             "published": pub.TABLE11_TIME_RATIO_PERCENT[s], "ours": None,
             "source": "seed 001 section 7 text; ours: mpcgen bench"},
            {"name": "Cal_ave vs conventional / % (ours; no paper figure)", "strategy": s, "published": None,
             "ours": percent(ours.get("Cal_ave"), conv.get("Cal_ave")), "source": "ours"},
            {"name": "f_ave vs conventional / % (ours; no paper figure)", "strategy": s, "published": None,
             "ours": percent(ours.get("f_ave_hz"), conv.get("f_ave_hz")), "source": "ours"},
        ]
    lines = [f"paper: seed 001 Table 2 (SPMSM, section 3), published | ours; "
             f"{_scenario_note(model, pub.SPMSM_DURATION_S)}"]
    if t2 is None:
        lines.append(f"  (Table 2 has no row at this config's eps_T = {eps:g} N*m: its s1 row is n/a)")
    lines += _t2_lines(rows, "run")
    lines += _ratio_lines(ratios, "Table 11 (STM32H743, 80 000 steps) and the ratios vs conventional, %:")
    lines.append("  ours has no computation time: simulate counts evaluations (Cal_ave); mpcgen bench times the step")
    return {"available": True, "source": "seed 001 Tables 2 and 11 (SPMSM)", "rows": rows, "ratios": ratios,
            "_table": "\n".join(lines)}


# ---------------------------------------------------------------------------
# SPMSM eps_T sweep: Tables 1 and 2
# ---------------------------------------------------------------------------
def _sweep(model: Model, data: dict[str, Any]) -> dict[str, Any]:
    t1_ours = {("all" if r["band_nm"] == "all" else round(float(r["band_nm"]), 9)): r for r in data["table1"]}
    table1: list[dict[str, Any]] = []
    for p in pub.TABLE1_ZERO_VECTOR_UTILISATION:
        key: Any = "all" if math.isinf(p.band_nm) else round(p.band_nm, 9)
        o = t1_ours.get(key, {})
        table1.append({"band_nm": "all" if key == "all" else p.band_nm, "N": side(p.n, o.get("N")),
                       "N_V0": side(p.n_v0, o.get("N_V0")), "eta_V0_percent": side(p.eta_v0_percent,
                                                                                    o.get("eta_V0_percent"))})
    ours2 = {round(float(r["eps_t_nm"]), 9): r for r in data["table2"]}
    table2 = [_t2_row(f"{p.band_nm:.1f}", p, ours2.get(round(p.band_nm, 9), {})) for p in pub.TABLE2_THRESHOLD_SWEEP]
    table2.append(_t2_row("conventional", pub.TABLE2_CONVENTIONAL, data["conventional"]))
    conv_p, conv_o = pub.TABLE2_CONVENTIONAL, data["conventional"]
    ratios: list[dict[str, Any]] = [{"name": f"s1 eps_T {r['row']}: Cal_ave / f_ave vs conventional / %", "strategy": "s1",
               "Cal_ave": side(percent(r["Cal_ave"]["published"], conv_p.cal_ave),
                               percent(r["Cal_ave"]["ours"], conv_o.get("Cal_ave"))),
               "f_ave": side(percent(r["f_ave_hz"]["published"], conv_p.f_ave_khz * 1e3),
                             percent(r["f_ave_hz"]["ours"], conv_o.get("f_ave_hz")))} for r in table2[:-1]]
    lines = [f"paper: seed 001 Table 1 (SPMSM conventional run, zero-vector use per torque-error band), "
             f"published | ours; {_scenario_note(model, pub.SPMSM_DURATION_S)}",
             f"  {'band/N*m':>9s} {pair_head('N', '7d')}  {pair_head('N_V0', '7d')}  {pair_head('eta_V0/%', '6.2f')}",
             f"  {'':9s} {pair_head('paper    ours', '7d')}  {pair_head('paper    ours', '7d')}  "
             f"{pair_head('paper  ours', '6.2f')}"]
    for row in table1:
        band = "all" if row["band_nm"] == "all" else f"<= {row['band_nm']:g}"
        lines.append(f"  {band:>9s} {_int_pair(row['N'])}  {_int_pair(row['N_V0'])}  "
                     f"{pair_cell(row['eta_V0_percent'], '6.2f')}")
    lines += ["", "paper: seed 001 Table 2 (s1 at each eps_T, whole run), published | ours, and the ratios to the "
              "conventional row (%)"]
    t2_lines = _t2_lines(table2, "eps_T/N*m")
    lines += [t2_lines[0] + f"{'Cal/conv %':>17s}  {'f_ave/conv %':>17s}",
              t2_lines[1] + f"{'paper    ours':>17s}  {'paper    ours':>17s}"]
    for line, rr in zip(t2_lines[2:], [*ratios, None]):
        if rr is None:
            lines.append(line)
        else:
            lines.append(line + f"{pct_cell(rr['Cal_ave']['published'], 8)} {pct_cell(rr['Cal_ave']['ours'], 8)}  "
                                f"{pct_cell(rr['f_ave']['published'], 8)} {pct_cell(rr['f_ave']['ours'], 8)}")
    return {"available": True, "source": "seed 001 Tables 1 and 2 (SPMSM)", "table1": table1, "table2": table2,
            "ratios": ratios, "_table": "\n".join(lines)}


def _int_pair(c: Any) -> str:
    p, o = c["published"], c["ours"]
    return f"{'n/a' if p is None else int(p):>7} {'n/a' if o is None else int(o):>7}"

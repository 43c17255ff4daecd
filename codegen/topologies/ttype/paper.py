"""Seed 000's published figures next to ours (``mpcgen simulate --paper``).

Table 5 (torque ripple, flux ripple, i_a THD of 27- and 63-MPDTC at 300,
1800 and 3000 r/min, T* = 1.27 N*m) against the steady window of each
lengthened Table-5 run (``scenario.set = "mpdtc-table5"``), the reductions
the seed prints, and the figures of its text: u_ab THD (Fig. 11), the
largest line-voltage jump (Fig. 12) and the execution time (Fig. 9, which
simulate does not measure: ours is the candidate count).  The seed does not
say which ripple statistic Table 5 gives; ours is the RMSE (std and the
1st-99th percentile span are in the JSON).  The published numbers are the
data of :mod:`codegen.topologies.ttype.published`.
"""
from __future__ import annotations

import math
from typing import Any

from codegen.model import Model
from codegen.paper import no_figures, pair_cell, pair_head, pct_cell, percent, side
from codegen.results import clean_json
from codegen.topologies.ttype import published as pub

__all__ = ["paper_table"]

STRATS = ("mpdtc27", "mpdtc63")
#: (our key, Table 5 field, heading, format)
COLUMNS = (("T_rip_RMSE_nm", "dte_nm", "dTe/N*m (RMSE)", "6.4f"),
           ("psi_rip_RMSE_wb", "dpsi_wb", "dpsi/Wb (RMSE)", "7.5f"),
           ("THD_ia_percent", "thd_ia_percent", "i_a THD/%", "6.2f"))
#: the names of the reductions, in COLUMNS order
REDUCED = ("torque ripple", "flux ripple", "i_a THD")


def _motor_differs(model: Model) -> str | None:
    """The first motor or inverter field in which the config is not the paper's setup (Table 4, section 3.1)."""
    m, s = model.motor, pub.TABLE4_MOTOR
    for f in ("rs_ohm", "ld_h", "lq_h", "psi_f_wb", "pole_pairs", "rated_speed_rpm", "rated_torque_nm"):
        if not math.isclose(float(getattr(m, f)), float(getattr(s, f)), rel_tol=1e-9):
            return f
    for name, ours, paper in (("inverter.udc_v", model.inverter.udc_v, pub.UDC_V),
                              ("controller.dt_s", model.controller.dt_s, pub.TS_S)):
        if not math.isclose(ours, paper, rel_tol=1e-9):
            return name
    return None


def _reduction(a: Any, b: Any) -> float | None:
    r = percent(b, a)
    return None if r is None else 100.0 - r


def paper_table(model: Model, data: dict[str, Any]) -> dict[str, Any]:
    """Published vs ours for a ``simulate`` result ``data``; JSON-ready with a printable ``_table``."""
    field = _motor_differs(model)
    if field is not None:
        return no_figures(f"{model.name} differs from seed 000's setup (Table 4 motor, Udc and Ts of "
                          f"section 3.1) in {field}; Table 5 belongs to that setup")
    if data.get("scenario_set") != "mpdtc-table5":
        return no_figures(f"seed 000 publishes Table 5 for its steady runs (scenario.set = \"mpdtc-table5\"); "
                          f"{model.name} runs scenario.set = \"{data.get('scenario_set')}\"")
    res = data["strategies"]
    rows: list[dict[str, Any]] = []
    ratios: list[dict[str, Any]] = []
    for speed in sorted({r.speed_rpm for r in pub.TABLE5_STEADY}):
        ours_by = {s: res.get(s, {}).get(f"{speed:g}rpm_steady", {}) for s in STRATS}
        for p in (p for p in pub.TABLE5_STEADY if p.speed_rpm == speed):
            o = ours_by[p.strategy]
            win = o.get("window", {}).get("T_rip_RMSE_nm", {})
            rows.append({"speed_rpm": speed, "strategy": p.strategy,
                         **{k: side(getattr(p, f), o.get(k)) for k, f, _h, _s in COLUMNS},
                         "THD_ia_nominal_percent": side(p.thd_ia_percent, o.get("THD_ia_nominal_percent")),
                         "T_rip_std_nm": o.get("T_rip_std_nm"), "T_rip_p1_p99_nm": o.get("T_rip_p1_p99_nm"),
                         "window_s": [win.get("t0_s"), win.get("t1_s")], "steady": not o.get("not_steady")})
        printed = pub.TABLE5_REDUCTIONS_PERCENT[speed]
        for i, (k, _f, _h, _s) in enumerate(COLUMNS):
            ratios.append({"name": f"{REDUCED[i]} reduction 63 vs 27 / %", "speed_rpm": speed,
                           "published": printed[i],
                           "ours": _reduction(ours_by["mpdtc27"].get(k), ours_by["mpdtc63"].get(k))})
    rated = f"{pub.TABLE4_MOTOR.rated_speed_rpm:g}rpm_steady"
    o27, o63 = (res.get(s, {}).get(rated, {}) for s in STRATS)
    text_figs: list[dict[str, Any]] = [
        {"name": "u_ab THD at rated speed and load / % (Fig. 11)", "mpdtc27": side(pub.FIG11_UAB_THD_PERCENT["mpdtc27"], o27.get("THD_uab_percent")),
         "mpdtc63": side(pub.FIG11_UAB_THD_PERCENT["mpdtc63"], o63.get("THD_uab_percent")),
         "reduction": side(pub.FIG11_UAB_THD_REDUCTION_PERCENT, _reduction(o27.get("THD_uab_percent"), o63.get("THD_uab_percent")))},
        {"name": "largest line-voltage jump / (Udc/2) (Fig. 12)", "mpdtc27": side(pub.FIG12_MAX_JUMP_UDC2["mpdtc27"], o27.get("max_line_jump_udc2")),
         "mpdtc63": side(pub.FIG12_MAX_JUMP_UDC2["mpdtc63"], o63.get("max_line_jump_udc2")), "reduction": side(None, None)},
        {"name": "execution time / us (Fig. 9; ours: not measured)", "mpdtc27": side(pub.FIG9_EXEC_TIME_US["mpdtc27"], None),
         "mpdtc63": side(pub.FIG9_EXEC_TIME_US["mpdtc63"], None),
         "reduction": side(pub.FIG9_EXEC_TIME_REDUCTION_PERCENT, None)},
        {"name": "candidates per period (ours: Cal_ave)", "mpdtc27": side(pub.CANDIDATES_27, o27.get("Cal_ave")),
         "mpdtc63": side(None, o63.get("Cal_ave")),
         "reduction": side(None, _reduction(o27.get("Cal_ave"), o63.get("Cal_ave")))},
    ]
    ratios.append({"name": "execution time 63 / 27 / % (Fig. 9)", "speed_rpm": None,
                   "published": percent(pub.FIG9_EXEC_TIME_US["mpdtc63"], pub.FIG9_EXEC_TIME_US["mpdtc27"]),
                   "ours": None})
    ratios.append({"name": "Cal_ave 63 / 27 / % (ours, not time)", "speed_rpm": None, "published": None,
                   "ours": percent(o63.get("Cal_ave"), o27.get("Cal_ave"))})

    win = rows[0]["window_s"] if rows else [None, None]
    head = "".join(f" {pair_head(h, spec)}  " for _k, _f, h, spec in COLUMNS)
    lines = [f"paper: seed 000 Table 5 (steady state, T* = {pub.TABLE4_MOTOR.rated_torque_nm:g} N*m), published | "
             f"ours over the steady window [{_g(win[0])}, {_g(win[1])}) s of each run "
             "(Table 5 does not define its ripple statistic; ours is the RMSE)",
             f"  {'r/min':>5s} {'strategy':9s}{head}",
             f"  {'':5s} {'':9s}" + "".join(f" {pair_head('paper    ours', spec)}  " for *_a, spec in COLUMNS)]
    for r in rows:
        mark = "" if r["steady"] else "  (window not steady)"
        lines.append(f"  {r['speed_rpm']:5.0f} {r['strategy']:9s}"
                     + "".join(f" {pair_cell(r[k], spec)}  " for k, _f, _h, spec in COLUMNS) + mark)
    lines.append("reductions 63- vs 27-MPDTC the paper prints (%):")
    lines.append(f"  {'':40s} {'r/min':>5s} {'paper':>8s} {'ours':>8s}")
    for r in ratios:
        sp = "" if r["speed_rpm"] is None else f"{r['speed_rpm']:.0f}"
        lines.append(f"  {r['name']:40s} {sp:>5s} {pct_cell(r['published'], 8)} {pct_cell(r['ours'], 8)}")
    lines.append(f"figures of the paper's text (at {pub.TABLE4_MOTOR.rated_speed_rpm:g} r/min, rated load), "
                 "published | ours:")
    lines.append(f"  {'':48s} {pair_head('27-MPDTC', '7.2f')}  {pair_head('63-MPDTC', '7.2f')}  "
                 f"{pair_head('reduction %', '7.2f')}")
    for f in text_figs:
        lines.append(f"  {f['name']:48s} {pair_cell(f['mpdtc27'], '7.2f')}  {pair_cell(f['mpdtc63'], '7.2f')}  "
                     f"{pair_cell(f['reduction'], '7.2f')}")
    return clean_json({"available": True, "source": "seed 000 Table 5 and section 3 text", "rows": rows,
                       "ratios": ratios, "text_figures": text_figs, "_table": "\n".join(lines)})


def _g(v: Any) -> str:
    return "n/a" if v is None else f"{v:g}"

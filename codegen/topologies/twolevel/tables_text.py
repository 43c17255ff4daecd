"""``mpcgen tables`` for the two-level topology: the vector set and the switch tables.

``--utilisation published`` derives the s2/s3 tables from the
seed's published utilisation Tables 3-8 and compares them with the seed's
published tables; ``--utilisation training`` derives them from a closed-loop
training run of the conventional controller and prints the utilisation
tables in the seed's layout.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from codegen.model import Model
from codegen.topologies.twolevel import published as pub
from codegen.topologies.twolevel import utilisation as ut
from codegen.topologies.twolevel.vectors import VEC_TO_SW, unit_vectors

_S2_TITLES = ("Table 3 layout: utilisation, dT > eps_T", "Table 4 layout: utilisation, dT < -eps_T")
_S3_TITLES = (
    "Table 5 layout: dT > eps_T, dpsi > 0", "Table 6 layout: dT > eps_T, dpsi <= 0",
    "Table 7 layout: dT < -eps_T, dpsi > 0", "Table 8 layout: dT < -eps_T, dpsi <= 0",
)


def vector_set_text() -> str:
    """The two-level vector set, derived from the switching states."""
    ux, uy = unit_vectors()
    lines = ["Two-level vector set (u = 2/3 Udc (Sa + a Sb + a^2 Sc), shown / (2/3 Udc)):"]
    for v, sw in enumerate(VEC_TO_SW):
        ang = np.degrees(np.arctan2(uy[v], ux[v])) % 360 if v else 0.0
        name = "000/111" if v == 0 else f"{sw:03b}"
        lines.append(f"  V{v} {name:7s} alpha {ux[v]:+.4f} beta {uy[v]:+.4f} angle {ang:5.1f} deg")
    return "\n".join(lines)


def _utilisation_block(percent: np.ndarray, titles: tuple[str, ...]) -> list[str]:
    out = []
    for c, title in enumerate(titles):
        out += [ut.format_utilisation(percent[c].T, title), ""]
    return out


def two_level_tables_text(model: Model, source: str, log: Callable[[str], None]) -> str:
    """Text for a two-level config."""
    d = model.controller.derivation
    parts = [vector_set_text(), ""]
    if source == "published":
        parts += ["Seed's published utilisation (eta_V, %):", ""]
        parts += _utilisation_block(ut.published_utilisation("s2"), _S2_TITLES)
        parts += _utilisation_block(ut.published_utilisation("s3"), _S3_TITLES)
        parts.append(ut.published_derivation_report(d.coverage, d.max_active)[0])
        return "\n".join(parts)
    from codegen.topologies.twolevel.switch_tables import derived_tables

    log(f"training run: conventional controller over the {model.scenario.duration_s:g} s scenario of {model.name}")
    s2, s3, counts = derived_tables(model, progress=lambda f: log(f"  training {f:5.0%}"))
    n2 = int(counts["s2"].sum())
    parts += [f"Utilisation from the training run ({n2} samples with |dT| > eps_T = {model.controller.eps_t_nm} N*m):", ""]
    parts += _utilisation_block(ut.utilisation_percent(counts["s2"]), _S2_TITLES)
    parts += _utilisation_block(ut.utilisation_percent(counts["s3"]), _S3_TITLES)
    from codegen.topologies.twolevel.switch_tables import MIN_CELL_SAMPLES, thin_cells

    for k in ("s2", "s3"):
        thin = np.argwhere(thin_cells(counts[k]))
        if len(thin):
            cells = ", ".join(f"condition {c + 1} sector {s + 1}" for c, s in thin)
            parts += [f"{k}: {len(thin)} cells have < {MIN_CELL_SAMPLES} active choices and take the set derived from the paper's own data: {cells}", ""]
    parts += [f"s2 derived (coverage {d.coverage:.2f}, max_active {d.max_active}):", ut.format_switch_table(s2, "s2"), ""]
    parts += ["s2 vs the paper's published table:", ut.format_comparison(ut.compare_tables(s2, pub.PUBLISHED_S2), "s2"), ""]
    parts += ["s3 derived:", ut.format_switch_table(s3, "s3"), ""]
    parts += ["s3 row dT>0,dpsi>0 vs the paper's published row:",
              ut.format_comparison(ut.compare_tables((s3[0],), (pub.PUBLISHED_S3_ROW,)), "s3")]
    return "\n".join(parts)


def two_level_tables_rows(model: Model, source: str, log: Callable[[str], None]) -> list[dict[str, object]]:
    """The same tables as rows (``tables --json/--csv``): the vector set, the s2/s3 switch tables
    (from the published utilisation or the training run) and the utilisation they come from."""
    from codegen.topologies.twolevel.switch_tables import derived_tables

    ux, uy = unit_vectors()
    rows: list[dict[str, object]] = [
        {"table": "vector_set", "vector": f"V{v}", "switching_state": "000/111" if v == 0 else f"{sw:03b}",
         "alpha_pu": float(ux[v]), "beta_pu": float(uy[v])} for v, sw in enumerate(VEC_TO_SW)]
    d = model.controller.derivation
    if source == "published":
        percent = {"s2": ut.published_utilisation("s2"), "s3": ut.published_utilisation("s3")}
        s2, s3 = ut.published_tables(d.coverage, d.max_active)
    else:
        log(f"training run: conventional controller over the {model.scenario.duration_s:g} s scenario")
        s2, s3, counts = derived_tables(model, progress=lambda f: log(f"  training {f:5.0%}"))
        percent = {k: ut.utilisation_percent(v) for k, v in counts.items()}
    for kind, table in (("s2", s2), ("s3", s3)):
        for c, row in enumerate(table):
            for sec, cell in enumerate(row):
                rows.append({"table": f"{kind}_switch_table", "source": source, "condition": c + 1,
                             "sector": sec + 1, "candidates": " ".join(f"V{v}" for v in cell)})
                for v in range(7):
                    rows.append({"table": f"{kind}_utilisation", "source": source, "condition": c + 1,
                                 "sector": sec + 1, "vector": f"V{v}", "percent": float(percent[kind][c, sec, v])})
    return rows

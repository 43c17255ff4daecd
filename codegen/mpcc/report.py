"""Markdown report of a generated long-horizon step (part of ``mpcgen generate``): constants, the
lattice matrices' sizes, the search's stack and node budget, the guard and the assumptions."""
from __future__ import annotations

from codegen import reporting as rp
from codegen.model import Model
from codegen.mpcc.render import stack_bytes
from codegen.mpcc.tables import MpccTables

__all__ = ["report_text"]


def report_text(model: Model, t: MpccTables, target: str, topology: str) -> str:
    """Markdown report of the generated long-horizon step of ``topology`` (its title)."""
    c = model.controller
    n, b = t.n_vars, t.n_levels
    budget = f"{t.node_budget}" + ("" if c.node_budget is not None else " (estimate, docs/mpcc.md \"Node budget\")")
    rows = ["", "## Lattice problem", "",
            f"- horizon N = {t.horizon}, L = 3N = {n} positions, alphabet {list(t.adapter.levels)}"
            + (f", jump rule: a phase's position moves by at most {t.max_step} per period" if t.max_step else ""),
            f"- node budget {budget}; search stack {stack_bytes(t)} bytes of locals"]
    table_bytes = {"H (real, L x L)": 4 * n * n, "W1 (real, L x 2N)": 4 * n * 2 * t.horizon,
                   "W2 (real, L x 3)": 4 * n * 3, "positions, place values": 4 * b + 4 * n,
                   "sincos_tab (real)": 4 * len(t.sincos_tab)}
    return rp.document(
        model, target, f"{topology} long-horizon current control (sphere decoder)",
        f"strategy `{c.strategy}`, horizon {c.horizon}, lambda_u {c.lambda_u:g} A^2, delay compensation "
        f"{c.delay_compensation}", t.consts, rows, table_bytes, t.adapter.fault_bits, "the safe switching state", [
            "surface PMSM (Ld = Lq) in the stationary frame, exact zero-order-hold discretisation (docs/mpcc.md eq. (1)).",
            "back-EMF and the current reference rotate by omega_e Ts per period (speed constant over the horizon).",
            f"switching weight defined at the nominal DC link inverter.udc_v = {model.inverter.udc_v:g} V: at a "
            "measured Udc the effective weight is lambda_u (Udc/udc_v)^2.",
            "initial radius: the applied positions held over the horizon (the step keeps no state).",
        ] + ([f"neutral point: penalty lambda_vo V_o(k+2)^2 on the first state only, lambda_vo = "
              f"{c.lambda_vo_a2_per_v2:g} A^2/V^2, the sampled and predicted currents held over their periods "
              "(docs/mpcc.md eq. (14)); V_o is not in the current model."] if t.neutral_point else []))

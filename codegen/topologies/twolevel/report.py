"""Markdown report of a generated two-level controller (part of ``mpcgen generate``).

Lists what the C contains: constants with their float32 bits, the candidate
rows, the memory the tables take, the input guard and the assumptions the
step makes.  Deterministic: no dates, no paths.
"""
from __future__ import annotations

from codegen import reporting as rp
from codegen.model import Model
from codegen.topologies.twolevel import mtpa
from codegen.topologies.twolevel.derive import T_FLOOR_OF_RATED, TwoLevelTables, guard_limits
from codegen.topologies.twolevel.records import FAULT_BITS, N_VECTORS


def table_bytes(t: TwoLevelTables) -> dict[str, int]:
    """Bytes of read-only data the step's tables take (uint16 = 2, float = 4)."""
    out = {
        "ux, uy (float)": 2 * N_VECTORS * 4,
        "vec_to_sw, zero_sw (uint16)": (N_VECTORS + 8) * 2,
        "sw_to_vec (uint16)": 8 * 2 if t.delay_compensation else 0,
        "candidate rows (uint16)": len(t.rows) * (N_VECTORS + 1) * 2,
        "sincos_tab (real)": len(t.sincos_tab) * 4,
    }
    if t.psi_tab:
        out["psi_tab, psi_slope (MTPA psi*, real)"] = (len(t.psi_tab) + len(t.psi_slope)) * 4
    return out


def report_text(model: Model, t: TwoLevelTables, target: str) -> str:
    """Markdown report of the generated controller."""
    c = model.controller
    rows = ["", "## Candidate rows", ""] + [f"- row {i}: " + " ".join(f"V{v}" for v in r)
                                           for i, r in enumerate(t.rows)]
    return rp.document(
        model, target, "two-level MPTC",
        f"strategy `{c.strategy}`, predictor `{c.predictor}`, delay compensation {c.delay_compensation}, "
        f"tables `{c.tables}`, flux reference `{c.psi_ref}`, cost `{c.cost}`",
        t.consts, rows, table_bytes(t), FAULT_BITS, "zero vector 000", [
            "flux-geometry: Rs neglected and rotor frozen over dt (eq. (1)-(3) of the MPTC paper); dq-euler: "
            "forward Euler,\n  candidate voltages rotated with theta_e(k).",
            "delay compensation (when on): k+1 predicted under the vector applied now, candidates for k+2.",
            "sin/cos: generated polynomial, |error| < 2e-7 for |theta_e| <= 256 rad.",
            _flux_reference_text(model, t),
            _cost_text(t),
        ])


def _flux_reference_text(model: Model, t: TwoLevelTables) -> str:
    """The psi* assumption line: constant, or the MTPA table with its interpolation error."""
    if t.psi_ref == "constant":
        return f"flux reference psi* = controller.psi_ref_wb = {model.controller.psi_ref_wb:g} Wb (constant)."
    t_max = guard_limits(model)["TORQUE_REF_GUARD_NM"]
    err = mtpa.interpolation_error(model.motor, t_max, len(t.psi_tab))
    return (f"flux reference psi* by MTPA of |T*| (eq. (M1)-(M3)): table of {len(t.psi_tab)} segments over "
            f"[0, {t_max:g}] N*m,\n  linear interpolation (largest error {err:.2g} Wb in float64), "
            "1/psi* by one division per step.")


def _cost_text(t: TwoLevelTables) -> str:
    """The cost assumption line (eq. (C1) or (C2))."""
    lam = " lambda_psi" if t.flux_weighted else ""
    if t.cost == "rated":
        return f"cost (C1): g = ((Te - T*)/T_N)^2 +{lam} ((|psi| - psi*)/psi*)^2."
    return (f"cost (C2): g = ((Te - T*)/T_N)^2 +{lam} (w (|psi| - psi*)/psi*)^2, w = max(|T*|, T_floor)/T_N,\n"
            f"  T_floor = {T_FLOOR_OF_RATED:g} T_N: w^2 times seed eq. (5) (squared) with T* -> max(|T*|, T_floor).")

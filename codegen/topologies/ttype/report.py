"""Markdown report of a generated T-type MPDTC controller (part of ``mpcgen generate``)."""
from __future__ import annotations

from codegen import reporting as rp
from codegen.model import Model
from codegen.topologies.ttype.derive import ThreeLevelTables
from codegen.topologies.ttype.records import FAULT_BITS


def table_bytes(t: ThreeLevelTables) -> dict[str, int]:
    """Bytes of read-only data the step's tables take (uint16 = 2, float = 4)."""
    n_vec = len(t.ux)
    out = {
        "seq_pat (uint16)": len(t.seq_pat) * 4 * 2,
        "ux, uy (float)": 2 * n_vec * 4,
        "seq (uint16)": n_vec * 7 * 2,
        "sincos_tab (real)": len(t.sincos_tab) * 4,
    }
    # groups are resolved by generated code: no group tables; 27-MPDTC's one row is unrolled too,
    # only its group count remains
    if t.n_sectors > 1:
        out["row_n, rows (uint16)"] = len(t.row_groups) * (1 + t.max_groups) * 2
        out["end_state (uint16)"] = n_vec * 2
    else:
        out["row_n (uint16)"] = len(t.row_groups) * 2
    return out


def report_text(model: Model, t: ThreeLevelTables, target: str) -> str:
    """Markdown report of the generated controller."""
    c = model.controller
    tables = ["", "## Candidate groups", ""]
    tables += [f"- group {i}: {label}" for i, label in enumerate(t.group_labels)]
    tables += ["", f"## Candidate rows ({len(t.row_groups)})", ""]
    tables += [f"- row {i}: {label}: " + " ".join(t.group_labels[g] for g in r)
               for i, (r, label) in enumerate(zip(t.row_groups, t.row_labels))]
    settings = (f"strategy `{c.strategy}`, lambda_psi {c.lambda_psi_nm_per_wb:g} N*m/Wb, "
                f"lambda_vo {c.lambda_vo_nm_per_v:g} N*m/V, one-step delay compensation")
    assumptions = [
        "Ld = Lq = Ls (surface PMSM); forward-Euler dq prediction k -> k+1 under the applied vector "
        "(delay compensation), candidates evaluated at k+2.",
        "flux reference psi* by MTPA from T*; deadbeat reference voltage u* picks the 63-MPDTC row.",
        "a group's members are resolved by the smallest predicted |V_o(k+2)|; a virtual member's T_N "
        "is the neutral-point deadbeat, clamped to [T_N_min, Ts/3].",
        "sin/cos: generated polynomial, |error| < 2e-7 for |theta_e| <= 256 rad.",
    ]
    return rp.document(model, target, "T-type three-level MPDTC", settings, t.consts, tables, table_bytes(t),
                       FAULT_BITS, "OOO for the whole period", assumptions)

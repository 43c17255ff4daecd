"""Markdown report of a generated two-level controller (part of ``mpcgen generate``).

Lists what the C contains: constants with their float32 bits, the candidate
rows, the memory the tables take, the input guard and the assumptions the
step makes.  Deterministic: no dates, no paths.
"""
from __future__ import annotations

from codegen import reporting as rp
from codegen.model import Model
from codegen.topologies.twolevel.derive import TwoLevelTables
from codegen.topologies.twolevel.records import FAULT_BITS, N_VECTORS


def table_bytes(t: TwoLevelTables) -> dict[str, int]:
    """Bytes of read-only data the step's tables take (uint16 = 2, float = 4)."""
    return {
        "ux, uy (float)": 2 * N_VECTORS * 4,
        "vec_to_sw, zero_sw (uint16)": (N_VECTORS + 8) * 2,
        "sw_to_vec (uint16)": 8 * 2 if t.delay_compensation else 0,
        "candidate rows (uint16)": len(t.rows) * (N_VECTORS + 1) * 2,
    }


def report_text(model: Model, t: TwoLevelTables, target: str) -> str:
    """Markdown report of the generated controller."""
    c = model.controller
    rows = ["", "## Candidate rows", ""] + [f"- row {i}: " + " ".join(f"V{v}" for v in r)
                                           for i, r in enumerate(t.rows)]
    return rp.document(
        model, target, "two-level MPTC",
        f"strategy `{c.strategy}`, predictor `{c.predictor}`, delay compensation {c.delay_compensation}, "
        f"tables `{c.tables}`",
        t.consts, rows, table_bytes(t), FAULT_BITS, "zero vector 000", [
            "flux-geometry: Rs neglected and rotor frozen over dt (eq. (1)-(3) of the MPTC paper); dq-euler: "
            "forward Euler,\n  candidate voltages rotated with theta_e(k).",
            "delay compensation (when on): k+1 predicted under the vector applied now, candidates for k+2.",
            "sin/cos: generated polynomial, |error| < 2e-7 for |theta_e| <= 256 rad.",
        ])

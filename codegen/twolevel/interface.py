"""The two-level controller step's input and output records: one list, every layer.

The generated C structs (templates), the numpy structured dtypes that carry
batches through cffi and the Python reference, and the firmware runtime all
use these names.  Field order here is the struct member order in C.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Number of basic voltage vectors V0..V6 (the most candidates a step can evaluate).
N_VECTORS = 7


@dataclass(frozen=True)
class Field:
    """One struct member: name, C type, array length (1 = scalar), meaning."""

    name: str
    ctype: str  # "float" | "uint16_t"
    length: int
    doc: str


#: Motor measurements every controller step takes first (both topologies).
MOTOR_INPUT_FIELDS: tuple[Field, ...] = (
    Field("ia_a", "float", 1, "sampled phase-a current, A"),
    Field("ib_a", "float", 1, "sampled phase-b current, A"),
    Field("theta_e_rad", "float", 1, "electrical rotor angle, rad (|x| <= angle guard)"),
    Field("omega_e_rad_s", "float", 1, "electrical rotor speed, rad/s"),
)

INPUT_FIELDS: tuple[Field, ...] = MOTOR_INPUT_FIELDS + (
    Field("udc_v", "float", 1, "measured DC-link voltage, V"),
    Field("torque_ref_nm", "float", 1, "torque reference T*, N*m (speed-loop output)"),
    Field("sw_prev", "uint16_t", 1, "switching state applied in the current period, Sa*4+Sb*2+Sc"),
)

OUTPUT_FIELDS: tuple[Field, ...] = (
    Field("te_nm", "float", 1, "estimated torque at k (k+1 with delay compensation), N*m"),
    Field("psi_wb", "float", 1, "estimated stator-flux magnitude at k (k+1), Wb"),
    Field("psi_alpha_wb", "float", 1, "stator flux alpha, Wb"),
    Field("psi_beta_wb", "float", 1, "stator flux beta, Wb"),
    Field("sin_theta", "float", 1, "sin(theta_e) from the generated polynomial"),
    Field("cos_theta", "float", 1, "cos(theta_e) from the generated polynomial"),
    Field("cost_best", "float", 1, "cost of the chosen candidate (0 if none evaluated)"),
    Field("costs", "float", N_VECTORS, "cost of candidate j, in evaluation order; 0 beyond n_eval"),
    Field("sw", "uint16_t", 1, "chosen switching state Sa*4+Sb*2+Sc"),
    Field("vector", "uint16_t", 1, "chosen vector index 0..6 (V0 realised as 000 or 111)"),
    Field("n_eval", "uint16_t", 1, "costs evaluated in this step (Cal)"),
    Field("fault", "uint16_t", 1, "fault bits (FAULT_* below); nonzero => safe decision"),
    Field("sector", "uint16_t", 1, "flux sector used, 1-based (0: none used)"),
    Field("condition", "uint16_t", 1, "table condition row used, 1-based (0: none)"),
    Field("cand", "uint16_t", N_VECTORS, "candidate vector j in evaluation order; 0 beyond n_eval"),
)

#: Fault bits of the input guard (numerics.md "Inputs are guarded").
FAULT_BITS: tuple[tuple[str, int, str], ...] = (
    ("CURRENT", 1, "|i_a|, |i_b| or |i_c| above i_trip_a, or not finite"),
    ("UDC_LOW", 2, "DC link below udc_min_v, or not finite"),
    ("UDC_HIGH", 4, "DC link above udc_max_v, or not finite"),
    ("ANGLE", 8, "|theta_e| above the angle guard, or not finite"),
    ("SPEED", 16, "|omega_e| above the speed guard, or not finite"),
    ("TORQUE_REF", 32, "|T*| above the torque-reference guard, or not finite"),
    ("STATE", 64, "sw_prev is not a switching state 0..7"),
)
FAULT = {name: bit for name, bit, _ in FAULT_BITS}

_NP = {"float": np.float32, "uint16_t": np.uint16}


def record_dtype(fields: tuple[Field, ...]) -> np.dtype:
    """numpy structured dtype laid out like the C struct of ``fields`` (natural alignment)."""
    spec = [(f.name, _NP[f.ctype], (f.length,)) if f.length > 1 else (f.name, _NP[f.ctype]) for f in fields]
    return np.dtype(spec, align=True)


#: numpy records laid out exactly like the C structs (checked against cffi at build time).
INPUT_DTYPE: np.dtype = record_dtype(INPUT_FIELDS)
OUTPUT_DTYPE: np.dtype = record_dtype(OUTPUT_FIELDS)

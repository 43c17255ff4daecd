"""The two-level controller step's input and output records: one list, every layer.

The generated C structs (templates), the numpy structured dtypes that carry
batches through cffi and the Python reference, and the firmware runtime all
use these names.  Field order here is the struct member order in C.
"""
from __future__ import annotations

import numpy as np

from ...kernels.guard import AllAtLeast, AllAtMost, Check, IndexAtMost, fault_bits, motor_checks
from ...numfmt.float32 import FLOAT32
from ...records import MOTOR_INPUT_FIELDS, Field, Record, fields

#: Number of basic voltage vectors V0..V6 (the most candidates a step can evaluate).
N_VECTORS = 7


INPUT_FIELDS: tuple[Field, ...] = MOTOR_INPUT_FIELDS + fields("""
    udc_v          real  1  measured DC-link voltage, V
    torque_ref_nm  real  1  torque reference T*, N*m (speed-loop output)
    prev_sw        u16   1  switching state applied in the current period, Sa*4+Sb*2+Sc
""")

OUTPUT_FIELDS: tuple[Field, ...] = fields("""
    te_est_nm     real  1          estimated torque at k (k+1 with delay compensation), N*m
    psi_est_wb    real  1          estimated stator-flux magnitude at k (k+1), Wb
    psi_alpha_wb  real  1          stator flux alpha, Wb
    psi_beta_wb   real  1          stator flux beta, Wb
    sin_theta     real  1          sin(theta_e) from the generated polynomial
    cos_theta     real  1          cos(theta_e) from the generated polynomial
    cost_best     real  1          cost of the chosen candidate (0 if none evaluated)
    costs         real  N_VECTORS  cost of candidate j, in evaluation order; 0 beyond n_eval
    sw            u16   1          chosen switching state Sa*4+Sb*2+Sc
    vector        u16   1          chosen vector index 0..6 (V0 realised as 000 or 111)
    n_eval        u16   1          costs evaluated in this step (Cal)
    fault         u16   1          fault bits (FAULT_* below); nonzero => safe decision
    gates_off     u16   1          1: disable the PWM outputs this period (fault, controller.fault_action); 0: apply sw
    sector        u16   1          flux sector used, 1-based (0: none used)
    condition     u16   1          table condition row used, 1-based (0: none)
    cand          u16   N_VECTORS  candidate vector j in evaluation order; 0 beyond n_eval
""", N_VECTORS=N_VECTORS)

#: The input guard as data (numerics.md "Input guard and safe decision"), evaluated by codegen.kernels.guard.
GUARD: tuple[Check, ...] = motor_checks() + (
    AllAtLeast("UDC_LOW", ("udc_v",), "UDC_MIN_V"),
    AllAtMost("UDC_HIGH", ("udc_v",), "UDC_MAX_V"),
    IndexAtMost("STATE", "prev_sw", 7),
)
#: Fault bits of the input guard: (name, bit, meaning).
FAULT_BITS: tuple[tuple[str, int, str], ...] = fault_bits({
    "UDC_LOW": "DC link below udc_min_v, or not finite",
    "UDC_HIGH": "DC link above udc_max_v, or not finite",
    "STATE": "prev_sw is not a switching state 0..7",
})
FAULT = {name: bit for name, bit, _ in FAULT_BITS}

#: The step's records (one definition; every layout derives from these).
INPUT = Record("twolevel_input", INPUT_FIELDS)
OUTPUT = Record("twolevel_output", OUTPUT_FIELDS)
#: numpy records of the float32 reference, laid out exactly like the C structs
#: (checked against cffi at build time).
INPUT_DTYPE: np.dtype = INPUT.bind(FLOAT32).dtype

"""The three-level MPDTC step's input and output records: one list, every layer.

The generated C structs (templates/ttype), the numpy structured dtypes
that carry batches through cffi and the Python reference
(``codegen.topologies.ttype.reference``), and the plant simulator use these names.
Field order here is the struct member order in C.

Vector ids (``virtual.py``): 0..26 the switching states (index
9*(Sa+1) + 3*(Sb+1) + (Sc+1): NNN = 0, OOO = 13, PPP = 26), 27..62 the 36
virtual vectors.

Segment convention of the decision (``states``/``seg_s``): the period is 7
segments applied in order; the plant skips zero-length segments.
- basic state s: states = [s, s, s, s, s, s, s], seg_s = [Ts, 0, 0, 0, 0, 0, 0]
- virtual vector: states = its sequence [N, b, c, P, c, b, N],
  seg_s = [T_N/2, Ts/6, Ts/6, Ts/3 - T_N, Ts/6, Ts/6, T_N/2]
  (float32, so the sum equals Ts to within a few ulp, not exactly).
"""
from __future__ import annotations

from functools import cache

import numpy as np

from ...kernels.guard import AllAtLeast, AllAtMost, Check, IndexAtMost, RealInRangeWhen, fault_bits, motor_checks
from ...numfmt.float32 import FLOAT32
from ...records import MOTOR_INPUT_FIELDS, Field, Record, fields
from .vectors import N_STATES, OOO

#: segments per period (a virtual vector's 7-segment sequence)
N_SEGMENTS = 7

INPUT_FIELDS: tuple[Field, ...] = MOTOR_INPUT_FIELDS + fields("""
    uc1_v          real  1  upper DC-link capacitor voltage, V
    uc2_v          real  1  lower DC-link capacitor voltage, V (Udc = uc1 + uc2, V_o = (uc1 - uc2)/2)
    torque_ref_nm  real  1  torque reference T*, N*m (speed-loop output)
    prev_vector    u16   1  vector id 0..62 applied in the current period
    t_n_prev_s     real  1  T_N of the current period, s (used if prev_vector is virtual)
""")

_OUTPUT_FIELDS = """
    te_est_nm      real  1           predicted torque at k+1, N*m
    psi_est_wb     real  1           predicted stator-flux magnitude at k+1, Wb
    psi_ref_wb     real  1           flux reference psi* (MTPA), Wb
    vo_v           real  1           measured neutral-point voltage V_o(k) = (uc1 - uc2)/2, V
    vo_pred_v      real  1           predicted V_o(k+1) under the applied vector, V
    u_ref_alpha_v  real  1           deadbeat reference voltage u*, alpha, V
    u_ref_beta_v   real  1           deadbeat reference voltage u*, beta, V
    t_n_s          real  1           T_N of the chosen vector, s (0 for a basic state)
    cost_best      real  1           cost of the chosen candidate, N*m (eq. (7))
    costs          real  N_MAX_EVAL  cost of group j, evaluation order; 0 beyond n_eval
    seg_s          real  N_SEGMENTS  segment times, s (sum Ts; see module doc)
    states         u16   N_SEGMENTS  switching state 0..26 of each segment
    vector         u16   1           chosen vector id 0..62
    n_eval         u16   1           costs evaluated (= voltage groups of the row)
    n_groups       u16   1           voltage groups in the candidate row
    n_members      u16   1           candidate vectors whose V_o(k+2) was predicted
    sector         u16   1           12-sector of u*, 1-based (0: fault)
    fault          u16   1           fault bits (FAULT_* below); nonzero => safe decision
    gates_off      u16   1           1: disable the PWM outputs this period (fault, controller.fault_action); 0: apply
    cand           u16   N_MAX_EVAL  resolved member (vector id) of group j; 0 beyond n_eval
"""


@cache
def output_record(n_max_eval: int) -> Record:
    """The output record of a strategy whose rows hold at most ``n_max_eval`` voltage groups (the
    costs a step can evaluate: 19 for 27-MPDTC's one row, 7 for 63-MPDTC's Table 3; the derived
    tables' ``max_groups``), so that no slot is always zero."""
    return Record("ttype_output", fields(_OUTPUT_FIELDS, units={"cost_best": "N*m", "costs": "N*m"},
                                         N_MAX_EVAL=n_max_eval, N_SEGMENTS=N_SEGMENTS))

#: first virtual vector id (after the 27 switching states); ids above N_IDS - 1 are not vectors
FIRST_VIRTUAL = N_STATES
N_IDS = 63

#: The input guard as data (numerics.md "Input guard and safe decision"), evaluated by codegen.kernels.guard.
GUARD: tuple[Check, ...] = motor_checks() + (
    AllAtLeast("UDC_LOW", ("uc1_v", "uc2_v"), "UC_MIN_V"),
    AllAtMost("UDC_HIGH", ("uc1_v", "uc2_v"), "UC_MAX_V"),
    IndexAtMost("STATE", "prev_vector", N_IDS - 1),
    RealInRangeWhen("TN_PREV", "t_n_prev_s", None, "TS3_S", "prev_vector", FIRST_VIRTUAL, N_IDS - 1),
)
#: Fault bits of the input guard: (name, bit, meaning).
FAULT_BITS: tuple[tuple[str, int, str], ...] = fault_bits({
    "UDC_LOW": "uc1 or uc2 below udc_min_v/2, or not finite",
    "UDC_HIGH": "uc1 or uc2 above udc_max_v/2, or not finite",
    "STATE": "prev_vector is not a vector id 0..62",
    "TN_PREV": "prev_vector virtual and t_n_prev_s outside [0, Ts/3] or not finite",
}, extra=("TN_PREV",))
FAULT = {name: bit for name, bit, _ in FAULT_BITS}

#: safe decision on a tripped guard: OOO for the whole period
SAFE_STATE = OOO

#: numpy records laid out exactly like the C structs (checked against cffi at build time).
INPUT = Record("ttype_input", INPUT_FIELDS)
INPUT_DTYPE: np.dtype = INPUT.bind(FLOAT32).dtype

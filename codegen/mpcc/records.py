"""The long-horizon step's output record: the family's fields around the topology's decision fields.

The decision keeps the field names the topology's simulator, modulator and firmware read (the
two-level's ``sw``/``vector``, the T-type's ``states``/``seg_s``/``vector``/``t_n_s``), given by the
topology; the family adds the sequence, the lattice problem's U_bar and the decoder's counters.
"""
from __future__ import annotations

from codegen.records import Field, fields

__all__ = ["output_fields"]

_REALS = """
    te_est_nm      real  1       estimated torque at k+d, 1.5 p psi_f i_q, N*m
    psi_est_wb     real  1       estimated stator-flux magnitude at k+d, |L i + psi_f (cos, sin)|, Wb
    i_alpha_a      real  1       current alpha at k+d (the horizon's start), A
    i_beta_a       real  1       current beta at k+d, A
    sin_theta      real  1       sin(theta_e) from the generated polynomial
    cos_theta      real  1       cos(theta_e) from the generated polynomial
    cost_best      real  1       ||H U - U_bar||^2 of the chosen sequence (eq. (11); 0 on a fault)
    ubar           real  N_VARS  U_bar = H U_unc (eq. (4)), the lattice point the search is centred on
"""

_COUNTS = """
    seq            u16   N       switching state of each period of the chosen sequence (the first is applied)
    n_nodes        u16   1       search-tree nodes the sphere decoder entered
    n_eval         u16   1       sequences whose full distance was evaluated (the initial guess and each leaf)
    budget_hit     u16   1       1: the node budget stopped the search, the best sequence so far is applied
    fault          u16   1       fault bits (FAULT_* below); nonzero => safe decision
    gates_off      u16   1       1: disable the PWM outputs this period (fault, controller.fault_action); 0: apply
"""


def output_fields(horizon: int, reals: tuple[Field, ...], decision: tuple[Field, ...]) -> tuple[Field, ...]:
    """The family's reals, the topology's ``reals``, the sequence, the topology's ``decision`` (u16
    fields) and the counters, in that (C struct) order."""
    counts = fields(_COUNTS, N=horizon)
    return fields(_REALS, units={"cost_best": "", "ubar": ""}, N_VARS=3 * horizon) + reals + counts[:1] \
        + decision + counts[1:]

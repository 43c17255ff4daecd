"""The long-horizon family's part of a topology's configuration (docs/mpcc.md "Configuration").

Each topology's ``section`` module adds :func:`fields` under its own family name and calls
:func:`check` when the config's strategy is of that family; this module names no strategy.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import NoReturn

from codegen.config import INT, REAL, Spec, closed, open_closed

__all__ = ["MAX_HORIZON", "MAX_NODE_BUDGET", "MAX_LAMBDA_VO", "fields", "neutral_point_fields", "check"]

#: the longest horizon: the decoder's tie-break index of a sequence, |alphabet|^(3N), fits 32 bits for
#: three levels up to N = 6
MAX_HORIZON = 6
#: ``n_nodes`` is a 16-bit output
MAX_NODE_BUDGET = 65535
#: the largest neutral-point weight, A^2/V^2 (beyond it the term alone decides the first state)
MAX_LAMBDA_VO = 1e6


def fields(family: str) -> dict[str, Spec]:
    """The family's own config fields, read only by its strategies (``Spec.families``)."""
    return {
        "controller.horizon": Spec(INT, closed(1, MAX_HORIZON), required=True, families=(family,)),
        "controller.lambda_u": Spec(REAL, open_closed(0, 1e9), required=True, families=(family,),
                                    hint_low="the switching weight must be positive (it makes H^T H positive "
                                             "definite: the common mode has no current cost)"),
        "controller.node_budget": Spec(INT, closed(1, MAX_NODE_BUDGET), families=(family,)),
    }


def neutral_point_fields(family: str) -> dict[str, Spec]:
    """The field of a topology with a DC-link midpoint (docs/mpcc.md eq. (14)): the weight of the
    neutral-point penalty lambda_vo V_o(k+d+1)^2 on the first period's positions.  Left out: the
    model's default (``codegen.model.Controller.lambda_vo_a2_per_v2``); 0 switches the term off."""
    return {"controller.lambda_vo_a2_per_v2": Spec(REAL, closed(0, MAX_LAMBDA_VO), families=(family,))}


def check(values: Mapping[str, object], fail: Callable[[str, object, str], NoReturn]) -> None:
    """What the family needs of the rest of the config: a surface PMSM (the alpha-beta model is LTI
    only for Ld == Lq, docs/mpcc.md eq. (1)) and float32 (no fixed-point sphere decoder)."""
    ld, lq = values["motor.ld_h"], values["motor.lq_h"]
    strategy = values["controller.strategy"]
    if ld != lq:
        fail("motor.lq_h", lq, f"controller.strategy = '{strategy}' needs a surface PMSM, motor.lq_h == "
             f"motor.ld_h = {ld:g} (its alpha-beta model is time invariant only then; docs/mpcc.md)")
    if values["controller.number_format"] != "float32":
        fail("controller.number_format", values["controller.number_format"],
             f"controller.strategy = '{strategy}' runs in float32 only (no fixed-point sphere decoder); "
             "allowed: float32")

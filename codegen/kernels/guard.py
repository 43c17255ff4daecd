"""The input guard as data (numerics.md "Input guard and safe decision").

A topology describes its guard as a tuple of checks; :func:`evaluate` is the
Python evaluation, ``templates/common/kernels.j2`` ``guard_fn`` the C one.
Every check is written so that a NaN fails it (comparisons are false on NaN)
and sets the check's fault bit.  Limits are constant names of the step
(``Const``), a lower bound of ``None`` is zero.

Fault bits: :data:`COMMON_FAULTS` are the bits every topology has, in bit
order (1, 2, 4, ...); a topology appends its own after them.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from codegen.kernels.consts import Constants
from codegen.kernels.frames import third_phase
from codegen.numfmt import Ops

__all__ = ["guard_ops", "COMMON_FAULTS", "COMMON_FAULT_DOCS", "PhaseCurrents", "AllAtLeast", "AllAtMost", "AbsAtMost",
           "IndexAtMost", "RealInRangeWhen", "Check", "fault_bits", "motor_checks", "evaluate", "gates_off"]


#: fault bits every topology's guard has, in bit order
COMMON_FAULTS: tuple[str, ...] = ("CURRENT", "UDC_LOW", "UDC_HIGH", "ANGLE", "SPEED", "TORQUE_REF", "STATE")

#: meaning of the common bits whose checks are the same in every topology
COMMON_FAULT_DOCS: dict[str, str] = {
    "CURRENT": "|i_a|, |i_b| or |i_c| above i_trip_a, or not finite",
    "ANGLE": "|theta_e| above the angle guard, or not finite",
    "SPEED": "|omega_e| above the speed guard, or not finite",
    "TORQUE_REF": "|T*| above the torque-reference guard, or not finite",
}


#: each check kind as a formula (generated comments); fields: {fields}, {field}, {limit}, {lo}, ...
_TEXT: dict[str, str] = {
    "phase_currents": "|{ia}|, |{ib}|, |i_c| <= {limit}, i_c = -({ia} + {ib})",
    "all_at_least": "{joined} >= {limit}",
    "all_at_most": "{joined} <= {limit}",
    "abs_at_most": "|{field}| <= {limit}",
    "index_at_most": "{field} <= {max}",
    "real_in_range_when": "{field} in [{lo_text}, {limit}] when {index} in [{first}, {last}]",
}


@dataclass(frozen=True)
class Check:
    """One guard check: fault bit name, kind (a key of the formula table), checked fields, bounds.

    ``limit`` is the constant name of the (upper) bound, ``lo`` that of the lower bound of
    ``real_in_range_when`` (None: zero), ``max`` the largest valid value of an index field,
    ``index``/``first``/``last`` the index field and range under which a range check applies.
    """

    fault: str
    kind: str
    fields: tuple[str, ...]
    limit: str = ""
    lo: str | None = None
    max: int = 0
    index: str = ""
    first: int = 0
    last: int = 0

    @property
    def field(self) -> str:
        """The (first) checked field."""
        return self.fields[0]

    @property
    def ia(self) -> str:
        return self.fields[0]

    @property
    def ib(self) -> str:
        return self.fields[-1]

    @property
    def hi(self) -> str:
        return self.limit

    @property
    def text(self) -> str:
        """The check as a formula (generated comments)."""
        return _TEXT[self.kind].format(ia=self.ia, ib=self.ib, field=self.field, joined=", ".join(self.fields),
                                       limit=self.limit, max=self.max, lo_text=self.lo or 0, index=self.index,
                                       first=self.first, last=self.last)


def PhaseCurrents(fault: str, ia: str, ib: str, limit: str) -> Check:  # noqa: N802 (a check constructor)
    """|i_a|, |i_b|, |i_c| <= limit with i_c = -(i_a + i_b)."""
    return Check(fault, "phase_currents", (ia, ib), limit)


def AllAtLeast(fault: str, fields: tuple[str, ...], limit: str) -> Check:  # noqa: N802
    """Every field >= limit."""
    return Check(fault, "all_at_least", fields, limit)


def AllAtMost(fault: str, fields: tuple[str, ...], limit: str) -> Check:  # noqa: N802
    """Every field <= limit."""
    return Check(fault, "all_at_most", fields, limit)


def AbsAtMost(fault: str, field: str, limit: str) -> Check:  # noqa: N802
    """|field| <= limit."""
    return Check(fault, "abs_at_most", (field,), limit)


def IndexAtMost(fault: str, field: str, max_value: int) -> Check:  # noqa: N802
    """Integer field <= max_value."""
    return Check(fault, "index_at_most", (field,), max=max_value)


def RealInRangeWhen(fault: str, field: str, lo: str | None, hi: str, index: str, first: int,  # noqa: N802
                    last: int) -> Check:
    """Real field in [lo, hi] whenever integer field ``index`` is in [first, last] (lo None: zero)."""
    return Check(fault, "real_in_range_when", (field,), hi, lo, index=index, first=first, last=last)


def fault_bits(docs: Mapping[str, str], extra: tuple[str, ...] = ()) -> tuple[tuple[str, int, str], ...]:
    """(name, bit, meaning) of the common bits then ``extra``; ``docs`` adds or overrides meanings."""
    names = COMMON_FAULTS + extra
    meaning = {**COMMON_FAULT_DOCS, **docs}
    return tuple((n, 1 << i, meaning[n]) for i, n in enumerate(names))


def motor_checks() -> tuple[Check, ...]:
    """The checks of the motor measurements every step takes (``records.MOTOR_INPUT_FIELDS``)
    and of the torque reference: CURRENT, ANGLE, SPEED, TORQUE_REF."""
    return (
        PhaseCurrents("CURRENT", "ia_a", "ib_a", "I_TRIP_A"),
        AbsAtMost("ANGLE", "theta_e_rad", "ANGLE_GUARD_RAD"),
        AbsAtMost("SPEED", "omega_e_rad_s", "OMEGA_GUARD_RAD_S"),
        AbsAtMost("TORQUE_REF", "torque_ref_nm", "TORQUE_REF_GUARD_NM"),
    )


def guard_ops(checks: tuple[Check, ...]) -> dict[str, int]:
    """Essential operations of a guard, for the cycle bounds (``Topology.essential_ops``), counted from
    its checks: ``cmp``, one compare per checked field (the absolute values are sign masks inside the
    compares: float32 compares bit patterns); a phase-current check three (|i_a|, |i_b|, |i_c|) and,
    as ``add``, the sum i_a + i_b that gives i_c; a range check applied under an index range one
    compare per bound, zero included in the sign test when it has no lower bound, and one for the
    index range; then the one branch on their union (counted with the compares: neither writes a
    register).  Two-level: 9 compares (|i_a|, |i_b|, |i_c|, |theta|, |omega|, |T*|, the DC-link's low
    and high limits, the state index) and the branch, ``cmp`` 10; the sum, ``add`` 1."""
    ops = {"add": 0, "cmp": 1}  # the branch on the union
    for c in checks:
        if c.kind == "phase_currents":
            ops["cmp"] += 3
            ops["add"] += 1
        elif c.kind == "real_in_range_when":
            ops["cmp"] += (1 if c.lo is None else 2) + 1
        else:  # all_at_least, all_at_most, abs_at_most, index_at_most: a compare a field
            ops["cmp"] += len(c.fields)
    return ops


def _ok(ops: Ops, c: Check, k: Constants, x: np.ndarray) -> np.ndarray:
    """Per record: does check ``c`` pass."""
    if c.kind == "phase_currents":
        ia, ib, lim = x[c.ia], x[c.ib], k[c.limit]
        ic = third_phase(ops, ia, ib)
        return ops.le(ops.abs(ia), lim) & ops.le(ops.abs(ib), lim) & ops.le(ops.abs(ic), lim)
    if c.kind in ("all_at_least", "all_at_most"):
        cmp = ops.ge if c.kind == "all_at_least" else ops.le
        ok = np.ones(len(x), bool)
        for f in c.fields:
            ok &= cmp(x[f], k[c.limit])
        return ok
    if c.kind == "abs_at_most":
        return ops.le(ops.abs(x[c.field]), k[c.limit])
    if c.kind == "index_at_most":
        return x[c.field] <= c.max
    idx, v = x[c.index], x[c.field]
    lo = ops.const(0.0) if c.lo is None else k[c.lo]
    applies = (idx >= c.first) & (idx <= c.last)
    return ~applies | (ops.ge(v, lo) & ops.le(v, k[c.hi]))


def evaluate(ops: Ops, checks: tuple[Check, ...], bits: Mapping[str, int], k: Constants,
             x: np.ndarray) -> np.ndarray:
    """Fault bits (uint16) per input record: the OR of the bits of the failed checks."""
    fault = np.zeros(len(x), np.uint16)
    for c in checks:
        fault |= np.where(_ok(ops, c, k, x), 0, bits[c.fault]).astype(np.uint16)
    return fault


def gates_off(ops: Ops, fault: np.ndarray, omega_e: np.ndarray, fault_action: str, k: Constants) -> np.ndarray:
    """The ``gates_off`` output (uint16) per record: 0 without a fault; on a fault 1 for
    ``fault_action`` "gates-off", and for "active-short-circuit" 0 (the safe decision, the zero
    vector, is applied) when |omega_e| >= ASC_OMEGA_MIN_RAD_S, else 1.  ``omega_e`` is the raw input
    (not the zeroed faulted lane): a NaN speed fails the comparison and gives gates off.
    C: ``kernels.j2`` ``gates_off``."""
    if fault_action == "gates-off":
        on_fault = np.ones(len(fault), bool)
    else:
        on_fault = ~ops.ge(ops.abs(omega_e), k.ASC_OMEGA_MIN_RAD_S)
    return np.where((fault != 0) & on_fault, 1, 0).astype(np.uint16)

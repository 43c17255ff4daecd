"""Batch plumbing every Python reference shares: input check, error state, faulted lanes.

A reference runs vectorised over a batch of input records; lanes whose guard
tripped compute on zeros (their outputs are replaced by the safe decision),
so no lane's garbage can raise or leak into another.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from codegen.kernels.consts import Const, Constants
from codegen.numfmt import NumberFormat, Ops
from codegen.records import REAL, Record

__all__ = ["run_batch", "zero_faulted", "StepFrame", "begin_step"]


def run_batch(x: Any, dtype: np.dtype, step: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """``step(x)`` with floating-point warnings off, after checking ``x`` is a batch of ``dtype``."""
    x = np.asarray(x)
    if x.dtype != dtype:
        raise TypeError(f"input dtype must be {dtype}")
    with np.errstate(all="ignore"):
        return step(x)


def zero_faulted(ops: Ops, ok: np.ndarray, x: np.ndarray, fields: Any) -> dict[str, np.ndarray]:
    """Each input field with the faulted lanes (``~ok``) zeroed: real fields in the format,
    the others (indices) as ``np.intp``.  ``fields``: the record's fields (name, kind)."""
    zero = ops.const(0.0)
    return {f.name: ops.where(ok, x[f.name], zero) if f.kind == REAL
            else np.where(ok, x[f.name], 0).astype(np.intp) for f in fields}


@dataclass(frozen=True)
class StepFrame:
    """What every reference step starts from: format, its ops, constants, zeroed outputs, guard result,
    the inputs with the faulted lanes zeroed (``inp``) and the format's zero (``zero``)."""

    nf: NumberFormat
    o: Ops
    k: Constants
    n: int
    out: np.ndarray
    fault: np.ndarray
    ok: np.ndarray
    zero: Any
    inp: dict[str, np.ndarray]


def begin_step(nf: NumberFormat, consts: Iterable[Const], x: np.ndarray, fault: np.ndarray,
               inputs: Record, outputs: Record) -> StepFrame:
    """The common start of a reference step in format ``nf`` over the batch ``x`` whose guard gave ``fault``."""
    ok = fault == 0
    return StepFrame(nf, nf.ops, Constants(consts), len(x), outputs.bind(nf).zeros(len(x)), fault, ok,
                     nf.ops.const(0.0), zero_faulted(nf.ops, ok, x, inputs.fields))

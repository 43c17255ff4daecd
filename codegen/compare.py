"""Bit-for-bit comparison of step outputs (numerics.md "Bit-for-bit").

Floats are compared as their IEEE-754 bit patterns (uint32), integers as
integers: equal bits, never a tolerance.  On a mismatch the report shows the
input state and every output field from both sides, side by side.
"""
from __future__ import annotations

import numpy as np


def _bits(a: np.ndarray) -> np.ndarray:
    if a.dtype == np.float32:
        return a.view(np.uint32)
    if a.dtype == np.float64:
        return a.view(np.uint64)
    return a


def mismatch_mask(ref: np.ndarray, got: np.ndarray) -> tuple[np.ndarray, dict[str, int]]:
    """Per-record mismatch mask over every field, and the count per field."""
    if ref.dtype != got.dtype or ref.shape != got.shape:
        raise ValueError(f"cannot compare {ref.dtype}{ref.shape} with {got.dtype}{got.shape}")
    bad = np.zeros(len(ref), bool)
    per_field: dict[str, int] = {}
    for name in ref.dtype.names or ():
        ne = _bits(ref[name]) != _bits(got[name])
        if ne.ndim > 1:
            ne = ne.reshape(len(ref), -1).any(axis=1)
        if ne.any():
            per_field[name] = int(ne.sum())
        bad |= ne
    return bad, per_field


def _fmt(v: object) -> str:
    a = np.asarray(v)
    if a.dtype == np.float32:
        if a.ndim == 0:
            return f"{float(a)!r} (0x{int(a.view(np.uint32)):08x})"
        return "[" + ", ".join(f"{float(e)!r}" for e in a) + "]"
    if a.ndim:
        return "[" + ", ".join(str(int(e)) for e in a) + "]"
    return str(a.item())


def describe_mismatch(state: np.void, ref: np.void, got: np.void, ref_name: str = "python", got_name: str = "C") -> str:
    """Multi-line text: the state, then each output field from both sides."""
    lines = ["input state:"]
    for name in state.dtype.names or ():
        lines.append(f"  {name:16s} = {_fmt(state[name])}")
    lines.append(f"outputs ({ref_name} | {got_name}):")
    for name in ref.dtype.names or ():
        a, b = ref[name], got[name]
        same = np.array_equal(_bits(np.asarray(a)), _bits(np.asarray(b)))
        mark = "  " if same else "!!"
        lines.append(f"{mark}{name:16s} {_fmt(a)} | {_fmt(b)}")
    return "\n".join(lines)

"""Which config field sets a fixed-point range, and what to change: the message of a config the fixed-point
format cannot hold (``codegen.kernels.stepformat``).

A range signal (a worst case such as the cost bound) is computed from many config fields, and the field
a signal is labelled with is where it is usually set, not necessarily what made it too wide.  The cause
is found by sensitivity: every numeric field of ``[motor]``, ``[inverter]``, ``[controller]`` and
``[speed_loop]`` is raised by :data:`STEP` in turn, the range signals recomputed, and the field the
offending range grows fastest with (the largest exponent k of ``range ~ field^k``) is named.  The
advice is the largest value of that field at which the format holds the whole step (a search that
derives the format again), or, where the step cannot be derived again, the value at which the range
itself would fit (a few Newton steps on ``log range`` over ``log field``; "about": the format's bases
move with the ranges).
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable

from codegen.model import Model
from codegen.numfmt.scaling import RepresentationError, Signal

__all__ = ["STEP", "RangeCause", "numeric_fields", "with_field", "sensitivities", "range_cause", "value_for_limit", "largest_fitting",
           "advice"]

#: relative step of the sensitivity (range ~ field^k: k = log(range ratio) / log(STEP))
STEP = 1.125
#: exponents below this are "does not depend on the field"
MIN_EXPONENT = 0.05
#: sections whose numeric fields may set a range
SECTIONS = ("motor", "inverter", "controller", "speed_loop")
#: numeric fields that choose the format rather than a range
NOT_RANGES = frozenset({"controller.fixed_q"})

RangesOf = Callable[[Model], Iterable[Signal]]


@dataclasses.dataclass(frozen=True)
class RangeCause:
    """The field a range grows fastest with: ``range ~ field^exponent`` near its value."""

    field: str
    value: float
    exponent: float


def numeric_fields(model: Model) -> list[tuple[str, float]]:
    """(dotted name, value) of every int or float field of :data:`SECTIONS` (booleans and unset fields left out)."""
    out = []
    for section in SECTIONS:
        obj = getattr(model, section)
        for f in dataclasses.fields(obj):
            v = getattr(obj, f.name)
            name = f"{section}.{f.name}"
            if isinstance(v, (int, float)) and not isinstance(v, bool) and name not in NOT_RANGES and v != 0:
                out.append((name, float(v)))
    return out


def with_field(model: Model, field: str, value: float) -> Model:
    """``model`` with the field ``section.name`` set to ``value`` (an int field keeps its type, rounded)."""
    section, name = field.split(".")
    obj = getattr(model, section)
    v: float = round(value) if isinstance(getattr(obj, name), int) else value
    return model.replace(**{section: dataclasses.replace(obj, **{name: v})})


def _range(model: Model, name: str, ranges_of: RangesOf) -> float | None:
    """``max_abs`` of the range signal ``name`` of ``model`` (None: absent or not computable there)."""
    try:
        found = [s.max_abs for s in ranges_of(model) if s.name == name]
    except (ArithmeticError, ValueError):
        return None
    return found[0] if found and found[0] > 0 and math.isfinite(found[0]) else None


def _exponent(model: Model, field: str, value: float, name: str, ranges_of: RangesOf,
              at: float | None = None) -> float | None:
    """k of ``range ~ field^k`` at ``value`` (int fields: from value to value + 1)."""
    base = _range(with_field(model, field, value), name, ranges_of) if at is None else at
    is_int = isinstance(getattr(getattr(model, field.split(".")[0]), field.split(".")[1]), int)
    up = value + 1 if is_int else value * STEP
    moved = _range(with_field(model, field, up), name, ranges_of)
    if base is None or moved is None or value <= 0:
        return None
    return math.log(moved / base) / math.log(up / value)


def sensitivities(model: Model, name: str, ranges_of: RangesOf) -> list[RangeCause]:
    """Every positive numeric field the range ``name`` depends on (|exponent| > MIN_EXPONENT), the
    fastest-growing first."""
    here = _range(model, name, ranges_of)
    if here is None:
        return []
    out = []
    for field, value in numeric_fields(model):
        k = _exponent(model, field, value, name, ranges_of, here) if value > 0 else None
        if k is not None and abs(k) > MIN_EXPONENT:
            out.append(RangeCause(field, value, k))
    return sorted(out, key=lambda c: -c.exponent)


def range_cause(model: Model, name: str, ranges_of: RangesOf) -> RangeCause | None:
    """The positive numeric field the range ``name`` grows fastest with, or None when it grows with none."""
    found = sensitivities(model, name, ranges_of)
    return found[0] if found and found[0].exponent > 0 else None


def value_for_limit(model: Model, cause: RangeCause, name: str, limit_abs: float, ranges_of: RangesOf,
                    steps: int = 6) -> float | None:
    """About the largest value of ``cause.field`` at which the range ``name`` is at most ``limit_abs``
    (Newton on log range over log field; None when it does not converge to a positive value)."""
    v = cause.value
    for _ in range(steps):
        r = _range(with_field(model, cause.field, v), name, ranges_of)
        k = _exponent(model, cause.field, v, name, ranges_of, r)
        if r is None or k is None or k <= MIN_EXPONENT:
            return None
        if r <= limit_abs:
            return v
        v *= (limit_abs / r) ** (1.0 / k) * 0.999
    r = _range(with_field(model, cause.field, v), name, ranges_of)
    return v if r is not None and r <= limit_abs * 1.01 else None


def largest_fitting(model: Model, cause: RangeCause, fits: Callable[[Model], bool], guess: float | None = None,
                    halvings: int = 40, precision: float = 1.01) -> float | None:
    """The largest value of ``cause.field`` below its value (within ``precision``) at which ``fits`` holds,
    rounded down to 3 significant digits: from ``guess`` (or half the value) down by halvings, then
    bisection on a log scale.  None when it fits nowhere down to 2^-halvings of the value."""
    hi, v, lo = cause.value, guess if guess is not None and 0 < guess < cause.value else cause.value / 2, None
    for _ in range(halvings):
        if fits(with_field(model, cause.field, v)):
            lo = v
            break
        hi, v = v, v / 2
    if lo is None:
        return None
    while hi / lo > precision:
        mid = math.sqrt(lo * hi)
        if fits(with_field(model, cause.field, mid)):
            lo = mid
        else:
            hi = mid
    step = 10.0 ** (math.floor(math.log10(lo)) - 2)
    shown = math.floor(lo / step) * step
    return shown if fits(with_field(model, cause.field, shown)) else lo


def _num(v: float) -> str:
    return f"{v:.3g}"


def _lower(model: Model, exc: RepresentationError, culprit: Signal, cause: RangeCause, shrink: RangeCause | None,
           ranges_of: RangesOf, fits: Callable[[Model], bool] | None) -> str:
    """The advice to lower ``cause.field``: to the largest value the format holds (``fits``), else to
    the value at which the culprit range meets ``exc.limit_abs`` (an estimate); ``shrink``: the field
    the range shrinks fastest with, named beside it."""
    guess = value_for_limit(model, cause, culprit.name, exc.limit_abs, ranges_of) if exc.limit_abs else None
    is_int = isinstance(getattr(getattr(model, cause.field.split(".")[0]), cause.field.split(".")[1]), int)
    best = largest_fitting(model, cause, fits, guess) if fits is not None and not is_int else None
    now = f"{cause.field} (now {_num(cause.value)})"
    if best is not None:
        change = f"lower {now} to at most {_num(best)} (the largest value the format holds, everything else unchanged)"
    elif fits is not None and not is_int:
        change = f"lowering {now} alone does not make the format hold the step"
    else:
        change = f"lower {now} " + (f"to about {_num(guess)} or less" if guess is not None else "well below its value")
    grows = f"grows as {cause.field}^{cause.exponent:.2g}"
    if shrink is not None:
        grows += f" (and as {shrink.field}^{shrink.exponent:.2g})"
    if culprit.name == exc.signal:
        return f"{culprit.name} {grows}: {change}"
    return (f"the widest range, {culprit.name} (|x| up to {culprit.max_abs:.6g}), sets the resolution and "
            f"{grows}: {change}")


#: the global Q values a config may choose (codegen.config: controller.fixed_q)
GLOBAL_Q = range(8, 31)


def _global_q_hint(model: Model, exc: RepresentationError, fits: Callable[[Model], bool] | None) -> str:
    """Which ``controller.fixed_q`` to take instead: the nearest that holds the step (``fits``), else the
    bound the offending value alone sets."""
    q = model.controller.fixed_q
    assert q is not None
    if fits is not None:
        order = [v for v in GLOBAL_Q if v > q] if exc.bits_short else [v for v in reversed(GLOBAL_Q) if v < q]
        for v in order:
            if fits(model.with_controller(fixed_q=v)):
                return f"{'raise' if v > q else 'lower'} controller.fixed_q to {v} (the nearest global Q that holds the step)"
        return "no global Q holds the step (without controller.fixed_q each signal gets its own format)"
    if exc.bits_short:
        return f"raise controller.fixed_q to at least {q + exc.bits_short}"
    q_max = math.floor(math.log2((2**31 - 1) / (2.0 * exc.max_abs))) if exc.max_abs > 0 else 0
    return f"lower controller.fixed_q to at most {q_max}" if q_max >= 1 else "no global Q holds it"


def advice(model: Model, exc: RepresentationError, ranges_of: RangesOf,
           fits: Callable[[Model], bool] | None = None) -> tuple[str | None, str]:
    """(the field to name, the advice) for ``exc`` under ``model`` (``ranges_of``: the step's range
    signals of a model; ``fits``: whether the format holds a model's step).  The field is the one that
    sets the offending range (or, for a constant left with too few bits, the range that set the
    resolution); None keeps the field ``exc`` names."""
    culprit = exc.culprit
    global_q = model.controller.fixed_q
    found = sensitivities(model, culprit.name, ranges_of) if culprit is not None else []
    cause = found[0] if found and found[0].exponent > 0 else None
    shrink = found[-1] if found and found[-1].exponent < 0 else None
    lower = _lower(model, exc, culprit, cause, shrink, ranges_of, fits) \
        if culprit is not None and cause is not None else ""
    if global_q is not None:
        return None, f"{_global_q_hint(model, exc, fits)}{'; or ' + lower if lower else ''}"
    if lower and cause is not None:
        return cause.field, lower
    if exc.bits_short:
        return None, f"{exc.field} sets this constant, too small for the format's resolution: raise it"
    return None, f"{exc.field} sets this value: lower it"

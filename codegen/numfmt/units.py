"""SI units as exponents of volt, ampere and second (the fixed-point format's base units).

The fixed-point format scales every signal by a power-of-two base per base
unit (``codegen.numfmt.scaling``); a signal's base is the product of the
bases of its unit's factors, so every equation of the step stays
dimensionally consistent in the scaled integers.  The units used by the
step's constants and records reduce to V, A and s (rad is dimensionless):

    Wb = V s,  H = V s / A,  ohm = V / A,  F = A s / V,  C = A s,  N*m = W s = V A s.

A unit is written as in the constants' tables: products ``*``, quotients
``/``, integer powers ``^n``, parentheses, ``1`` (e.g. ``A/(N*m)``,
``N*m*s/rad``, ``Wb^2``).
"""
from __future__ import annotations

import re
from functools import cache

__all__ = ["Dim", "parse_unit"]


#: exponents (V, A, s) of every named unit
Dim = tuple[int, int, int]
_NAMED: dict[str, Dim] = {
    "1": (0, 0, 0), "rad": (0, 0, 0),
    "V": (1, 0, 0), "A": (0, 1, 0), "s": (0, 0, 1),
    "Wb": (1, 0, 1), "H": (1, -1, 1), "ohm": (1, -1, 0), "F": (-1, 1, 1), "C": (0, 1, 1),
    "N*m": (1, 1, 1), "Nm": (1, 1, 1), "W": (1, 1, 0), "J": (1, 1, 1),
}
_TOKEN = re.compile(r"\s*(N\*m|[A-Za-z]+|\d+|[*/^()])")


def _tokens(text: str) -> list[str]:
    out, pos = [], 0
    text = text.strip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None:
            raise ValueError(f"unit {text!r}: cannot read {text[pos:]!r}")
        out.append(m.group(1))
        pos = m.end()
    return out


@cache
def parse_unit(text: str) -> Dim:
    """Exponents (V, A, s) of ``text``; ``""`` is dimensionless.  ValueError for an unknown unit."""
    if not text.strip():
        return (0, 0, 0)
    toks = _tokens(text)
    pos = 0

    def atom() -> Dim:
        nonlocal pos
        t = toks[pos]
        pos += 1
        if t == "(":
            d = expr()
            if pos >= len(toks) or toks[pos] != ")":
                raise ValueError(f"unit {text!r}: unbalanced parentheses")
            pos += 1
        elif t in _NAMED:
            d = _NAMED[t]
        else:
            raise ValueError(f"unit {text!r}: unknown unit {t!r} (known: {', '.join(_NAMED)})")
        if pos < len(toks) and toks[pos] == "^":
            n = int(toks[pos + 1])
            pos += 2
            d = (d[0] * n, d[1] * n, d[2] * n)
        return d

    def term() -> Dim:
        nonlocal pos
        d = atom()
        while pos < len(toks) and toks[pos] == "*":
            pos += 1
            e = atom()
            d = (d[0] + e[0], d[1] + e[1], d[2] + e[2])
        return d

    def expr() -> Dim:
        nonlocal pos
        d = term()
        while pos < len(toks) and toks[pos] == "/":
            pos += 1
            e = term()
            d = (d[0] - e[0], d[1] - e[1], d[2] - e[2])
        return d

    d = expr()
    if pos != len(toks):
        raise ValueError(f"unit {text!r}: unexpected {toks[pos]!r}")
    return d

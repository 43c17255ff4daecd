"""The fixed-point helpers' 32-bit forms (templates/numfmt/fixed.j2) and the CLZ-seeded Newton square
root: the C helpers bit for bit equal to the reference's operations (codegen.numfmt.fixed.FixedOps)
over random operands and the Q-range boundaries, for both parities of G and the extremes of G, with
the compiler builtins and in plain C99 (``<PREFIX>_Q_PORTABLE``), under UBSan; the multiply against
exact fractions at its saturation and rounding boundaries; the square root against the exact integer
square root (hypothesis, every perfect-square boundary, and exhaustively over its whole domain in the
slow tests); no 64-bit runtime helper (__aeabi_lmul, __aeabi_ldivmod, ...) in the Cortex-M3 code."""
from __future__ import annotations

import ctypes
import math
import subprocess
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from codegen.numfmt.fixed import FixedOps, clz32, isqrt32_newton, isqrt_q
from codegen.numfmt.scaling import INT32_MAX, INT32_MIN, Scaling
from codegen.render import environment

from conftest import STRICT_WARN, require_tool

#: the fractional bits tested: both ends of the allowed range (controller.fixed_q: 8..30), both parities
GS = (8, 13, 19, 20, 29, 30)
RNG = np.random.default_rng(30)

HEADERS = '{% import "numfmt/fixed.j2" as nf with context %}{{ nf.headers() }}'
WRAPPER = r"""
#define T_BIN(op) \
void w_##op(const int32_t *a, const int32_t *b, int32_t *o, int32_t n) \
{ \
    int32_t i; \
    for (i = 0; i < n; ++i) { \
        o[i] = t_q_##op(a[i], b[i]); \
    } \
}
#define T_UN(op) \
void w_##op(const int32_t *a, const int32_t *b, int32_t *o, int32_t n) \
{ \
    int32_t i; \
    (void)b; \
    for (i = 0; i < n; ++i) { \
        o[i] = t_q_##op(a[i]); \
    } \
}
T_BIN(add)
T_BIN(sub)
T_BIN(mul)
T_BIN(div)
T_UN(neg)
T_UN(abs)
T_UN(sqrt)
T_UN(trunc_int)
T_UN(from_int)
"""
OPS = ("add", "sub", "mul", "div", "neg", "abs", "sqrt", "trunc_int", "from_int")


def helpers_c(g: int) -> str:
    """The generated fixed-point helpers for G = g (prefix ``t``), as the step's headers print them."""
    return environment().from_string(HEADERS).render(prefix="t", PREFIX="T", q_frac_bits=g, q_lits={})


def _build(tmp, g: int, *defines: str, cc: str = "gcc"):
    src = tmp / f"w{g}{''.join(defines)}.c"
    src.write_text("".join(f"#define {d} 1\n" for d in defines) + helpers_c(g) + WRAPPER)
    so = src.with_suffix(".so")
    r = subprocess.run([cc, *STRICT_WARN, "-shared", "-fPIC", "-fsanitize=undefined", "-fno-sanitize-recover=all",
                        str(src), "-o", str(so)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return ctypes.CDLL(str(so))


@pytest.fixture(scope="module")
def libs(tmp_path_factory):
    """Per G: the helpers built with the compiler builtins (gcc and clang) and in plain C99."""
    tmp = tmp_path_factory.mktemp("fixedfast")
    clang = require_tool("clang", "clang")
    return {g: {"builtins": _build(tmp, g), "portable": _build(tmp, g, "T_Q_PORTABLE"),
                "clang": _build(tmp, g, cc=clang)} for g in GS}


def _c(lib, op: str, a: np.ndarray, b: np.ndarray | None = None) -> np.ndarray:
    a = np.ascontiguousarray(a, np.int32)
    b = np.ascontiguousarray(a if b is None else b, np.int32)
    o = np.zeros(len(a), np.int32)
    getattr(lib, f"w_{op}")(*(x.ctypes.data_as(ctypes.c_void_p) for x in (a, b, o)), ctypes.c_int32(len(a)))
    return o


def _sat(v: int) -> int:
    return max(INT32_MIN, min(INT32_MAX, v))


def _edges(g: int) -> np.ndarray:
    """Operands at the format's boundaries: 0, +-1, the extremes, powers of two around 2^G and 2^(G/2),
    sqrt(2^(31+G)) (a square at the saturation limit of the product) and their neighbours."""
    base = [0, 1, 2, 3, INT32_MAX, INT32_MAX - 1, 1 << (g - 1), 1 << g, (1 << g) + 1, (1 << g) - 1,
            1 << (g // 2), math.isqrt(1 << (31 + g)), math.isqrt(1 << (31 + g)) + 1, 46341, 46340, 65535, 65536]
    vals = set()
    for v in base:
        for w in (v - 1, v, v + 1):
            for s in (w, -w):
                vals.add(_sat(s))
    vals.add(INT32_MIN)
    return np.array(sorted(vals), np.int64)


def _operands(g: int, n: int = 40_000) -> tuple[np.ndarray, np.ndarray]:
    """Random operands of every magnitude (log-uniform), the edges crossed with each other, and
    products at the saturation limit: b = round(2^(31+G) / a) and its neighbours."""
    e = _edges(g)
    mag = np.exp2(RNG.uniform(0, 31, n)).astype(np.int64)
    a = np.clip(mag * RNG.choice([-1, 1], n), INT32_MIN, INT32_MAX)
    b = np.clip(np.exp2(RNG.uniform(0, 31, n)).astype(np.int64) * RNG.choice([-1, 1], n), INT32_MIN, INT32_MAX)
    lim = RNG.integers(1 << 8, INT32_MAX, 4000)
    blim = np.clip((np.int64(1) << (31 + g)) // lim, INT32_MIN, INT32_MAX)
    a = np.concatenate([a, np.repeat(e, len(e)), np.repeat(lim, 3), np.repeat(-lim, 3)])
    b = np.concatenate([b, np.tile(e, len(e)), np.concatenate([blim - 1, blim, blim + 1]),
                        np.concatenate([blim - 1, blim, blim + 1])])
    return a.astype(np.int32), np.clip(b, INT32_MIN, INT32_MAX).astype(np.int32)


@pytest.mark.parametrize("g", GS)
def test_c_helpers_equal_the_reference_operations(libs, g):
    """Every helper, in every build, bit for bit the reference's operation (which the oracle tests of
    test_fixed_ops.py check against Python integers)."""
    ops = FixedOps(Scaling(g, (0, 0, 0), "global"))
    a, b = _operands(g)
    expect = {"add": ops.add(a, b), "sub": ops.sub(a, b), "mul": ops.mul(a, b), "div": ops.div(a, b),
              "neg": ops.neg(a), "abs": ops.abs(a), "sqrt": ops.sqrt(a), "trunc_int": ops.trunc_int(a),
              "from_int": ops.from_int(a)}
    for build, lib in libs[g].items():
        for op in OPS:
            got = _c(lib, op, a, b)
            bad = np.flatnonzero(got != expect[op])
            assert bad.size == 0, (build, op, g, a[bad[:5]], b[bad[:5]], got[bad[:5]], expect[op][bad[:5]])


def _mul_exact(a: int, b: int, g: int) -> int:
    """a * b of counts with G fractional bits, round half up, saturated: exact rational arithmetic."""
    return _sat(math.floor(Fraction(a * b, 1 << g) + Fraction(1, 2)))


@pytest.mark.parametrize("g", GS)
def test_mul_is_exact_at_the_saturation_and_rounding_boundaries(libs, g):
    """Products a b / 2^G around the int32 limits (the last value kept, the first saturated), at exact
    ties (a b = (k + 1/2) 2^G: rounded up) and one count either side, every sign."""
    cases = []
    for k in (INT32_MAX, INT32_MAX - 1, INT32_MIN, INT32_MIN + 1, 0, 1, -1, 12345, -12345):
        # a b / 2^G = k + 1/2 + d / 2^G with a = 2^j: b = ((2k + 1) 2^(G-1) + d) / 2^j, d small
        for j in (0, 1, g // 2, g - 1, g, min(g + 5, 30)):
            for d in (-2, -1, 0, 1, 2):
                num = (2 * k + 1) * (1 << (g - 1)) + d
                if num % (1 << j) == 0 and INT32_MIN <= num >> j <= INT32_MAX:
                    cases += [(1 << j, num >> j), (-(1 << j), -(num >> j)), (num >> j, 1 << j)]
    lim = 1 << (31 + g)
    for a in (3, 7, 1 << (g // 2), 46341, 65537, INT32_MAX, INT32_MIN + 1, 1 << 30, (1 << 30) + 1):
        for target in (lim, -lim, lim - (1 << g), -lim - (1 << g)):
            for b in (target // a - 1, target // a, target // a + 1):
                if INT32_MIN <= b <= INT32_MAX:
                    cases += [(a, b), (-a, b), (b, a)]
    cases += [(INT32_MIN, INT32_MIN), (INT32_MIN, INT32_MAX), (INT32_MAX, INT32_MAX), (INT32_MIN, 1), (INT32_MIN, -1)]
    a = np.array([c[0] for c in cases], np.int32)
    b = np.array([c[1] for c in cases], np.int32)
    expect = [_mul_exact(x, y, g) for x, y in zip(a.tolist(), b.tolist())]
    assert FixedOps(Scaling(g, (0, 0, 0), "global")).mul(a, b).tolist() == expect
    for lib in libs[g].values():
        assert _c(lib, "mul", a, b).tolist() == expect
    # the boundary cases reach both saturations, exact ties and values kept next to them
    assert INT32_MAX in expect and INT32_MIN in expect and len(set(expect)) > 8


@pytest.mark.parametrize("g", GS)
def test_div_is_exact_near_its_saturation_and_ties(libs, g):
    """Quotients a 2^G / b at exact ties (rounded up, either sign), next to the int32 limits (the last
    one kept, the first saturated), b = 0 and the int32 extremes."""
    cases = [(0, 0), (5, 0), (INT32_MIN, 0), (INT32_MIN, INT32_MIN), (INT32_MIN, 1), (INT32_MIN, -1),
             (INT32_MAX, INT32_MIN), (INT32_MIN, INT32_MAX), (1, INT32_MIN), (-1, INT32_MIN), (1, INT32_MAX)]
    for b in (1, 2, 3, 7, 1 << g, (1 << g) + 1, 1 << 30, INT32_MAX, 65535, 65536, 65537):
        for q in (INT32_MAX, INT32_MAX - 1, 1 << 30, 3):
            # a 2^G / b = q + 1/2 exactly: a = (2q + 1) b / 2^(G+1) when that is an integer
            for a in ((2 * q + 1) * b >> (g + 1), ((2 * q + 1) * b >> (g + 1)) + 1,
                      ((2 * q + 1) * b >> (g + 1)) - 1, q * b >> g):
                for sa, sb in ((1, 1), (-1, 1), (1, -1), (-1, -1)):
                    if INT32_MIN <= sa * a <= INT32_MAX:
                        cases.append((sa * a, sb * b))
        for k in (1, 2, 3):  # exact ties: a 2^G = (k + 1/2) b
            if (2 * k + 1) * b % (1 << (g + 1)) == 0:
                a = (2 * k + 1) * b >> (g + 1)
                cases += [(a, b), (-a, b), (a, -b), (-a, -b)]
    a = np.array([c[0] for c in cases], np.int32)
    b = np.array([c[1] for c in cases], np.int32)
    expect = []
    for x, y in zip(a.tolist(), b.tolist()):
        expect.append(0 if y == 0 else _sat(math.floor(Fraction(x * (1 << g), y) + Fraction(1, 2))))
    assert FixedOps(Scaling(g, (0, 0, 0), "global")).div(a, b).tolist() == expect
    for lib in libs[g].values():
        assert _c(lib, "div", a, b).tolist() == expect
    assert INT32_MAX in expect and INT32_MIN in expect


def test_clz_is_the_leading_zero_count():
    x = np.concatenate([np.int64(1) << np.arange(32), (np.int64(1) << np.arange(1, 33)) - 1,
                        RNG.integers(1, 1 << 32, 10_000)])
    assert clz32(x).tolist() == [32 - int(v).bit_length() for v in x.tolist()]


def test_isqrt32_newton_at_every_square_boundary():
    """floor(sqrt(an)) for 2^30 <= an < 2^32 at s^2 - 1, s^2, s^2 + 1 of every s (where Newton's last
    step would land one above) and a million random values."""
    s = np.arange(1 << 15, 1 << 16, dtype=np.int64)
    an = np.concatenate([s * s - 1, s * s, s * s + 1, (s + 1) * (s + 1) - 1, RNG.integers(1 << 30, 1 << 32, 10**6),
                         np.array([1 << 30, (1 << 32) - 1], np.int64)])
    an = an[(an >= 1 << 30) & (an < 1 << 32)]
    r = isqrt32_newton(an)
    assert np.all(r * r <= an) and np.all((r + 1) * (r + 1) > an)


@settings(max_examples=3000, deadline=None)
@given(st.integers(INT32_MIN, INT32_MAX), st.integers(8, 30))
def test_sqrt_is_the_exact_floor_hypothesis(a, g):
    assert int(isqrt_q(np.array([a]), g)[0]) == (math.isqrt(a << g) if a > 0 else 0)


@pytest.mark.parametrize("g", range(8, 31))
def test_sqrt_is_the_exact_floor_at_square_boundaries(g):
    """a 2^G next to a perfect square (r^2 - 1 <= a 2^G <= r^2 + 2^G), for r spread over the whole
    result range, the first and last counts and a random sample: every G allowed."""
    r = np.unique(np.concatenate([np.arange(1, 5000), np.exp2(RNG.uniform(0, 30.5, 20_000)).astype(np.int64)]))
    sq = r * r
    a = np.concatenate([sq >> g, (sq >> g) + 1, (sq - 1) >> g, np.arange(-3, 5000), INT32_MAX - np.arange(5000),
                        RNG.integers(INT32_MIN, INT32_MAX, 20_000, endpoint=True)])
    a = a[(a >= INT32_MIN) & (a <= INT32_MAX)]
    got = isqrt_q(a, g)
    assert got.tolist() == [math.isqrt(int(x) << g) if x > 0 else 0 for x in a.tolist()]


def _exhaustive_program(g: int) -> str:
    return helpers_c(g) + r"""
#include <stdio.h>
int main(void)
{
    uint64_t bad = 0u;
    uint32_t a;
    for (a = 1u; a <= 0x7FFFFFFFu; ++a) {
        uint64_t x = (uint64_t)a << T_Q_G, r = (uint64_t)t_q_sqrt((int32_t)a);
        if ((r * r > x) || ((r + 1u) * (r + 1u) <= x)) {
            ++bad;
        }
    }
    printf("%llu\n", (unsigned long long)bad);
    return bad != 0u;
}
"""


@pytest.mark.slow
def test_sqrt_c_is_exact_for_every_positive_int32(tmp_path):
    """The generated q_sqrt over every a in [1, 2^31) for an even and an odd G: between them they
    reach every value the 16-bit square root q_isqrt32 is called with (a 2^m, 2^30 <= a 2^m < 2^32),
    and every result is floor(sqrt(a 2^G)) exactly (about 15 s each)."""
    procs = []
    for g in (19, 20):
        src = tmp_path / f"ex{g}.c"
        src.write_text(_exhaustive_program(g))
        exe = tmp_path / f"ex{g}"
        subprocess.run(["gcc", *STRICT_WARN, str(src), "-o", str(exe)], check=True)
        procs.append(subprocess.Popen([str(exe)], stdout=subprocess.PIPE, text=True))
    for p in procs:
        out, _ = p.communicate(timeout=600)
        assert p.returncode == 0 and out.strip() == "0"


@pytest.mark.slow
def test_isqrt32_newton_is_exact_over_its_whole_domain():
    """The reference's model of q_isqrt32 over every 2^30 <= an < 2^32 (about 100 s)."""
    step = 1 << 26
    for lo in range(1 << 30, 1 << 32, step):
        an = np.arange(lo, lo + step, dtype=np.int64)
        r = isqrt32_newton(an)
        assert np.all(r * r <= an) and np.all((r + 1) * (r + 1) > an), lo


#: the 64-bit helpers of the Arm run-time ABI (multiply, divide, shifts)
AEABI_64 = ("__aeabi_lmul", "__aeabi_ldivmod", "__aeabi_uldivmod", "__aeabi_llsl", "__aeabi_llsr", "__aeabi_lasr")


@pytest.mark.parametrize("cpu", ["cortex-m3", "cortex-m7"])
def test_no_64_bit_runtime_helper_on_the_cortex_m(tmp_path, cpu):
    """Every helper compiles to 32-bit instructions (SMLAL/UMULL, UDIV, CLZ): no call of a 64-bit
    multiply, divide or shift routine, whatever G."""
    arm = require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    flags = ["-mcpu=" + cpu, "-mthumb"] + (["-mfloat-abi=soft"] if cpu == "cortex-m3" else
                                           ["-mfpu=fpv5-d16", "-mfloat-abi=hard"])
    for g in GS:
        src = tmp_path / f"m{g}.c"
        src.write_text(helpers_c(g) + WRAPPER)
        obj = src.with_suffix(".o")
        r = subprocess.run([arm, *STRICT_WARN, *flags, "-c", str(src), "-o", str(obj)], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        syms = subprocess.run(["arm-none-eabi-nm", "-u", str(obj)], capture_output=True, text=True).stdout
        assert not [s for s in AEABI_64 if s in syms], (g, syms)
        dis = subprocess.run(["arm-none-eabi-objdump", "-d", str(obj)], capture_output=True, text=True).stdout
        assert "\tclz" in dis and "\tudiv" in dis and ("\tsmlal" in dis or "\tsmull" in dis), g


@pytest.mark.parametrize("portable", [False, True], ids=["builtins", "portable"])
def test_helpers_are_strict_clean_under_the_16_bit_int_model(tmp_path, portable):
    """The helpers, builtins or plain C99, under the C28x's type model (clang's MSP430 target: 16-bit
    int, 32-bit long) with the strict warnings, and free of the spellings the C28x profile forbids."""
    from conftest import assert_c28x_clean

    clang = require_tool("clang", "clang")
    for g in (8, 19, 30):
        text = ("#define T_Q_PORTABLE 1\n" if portable else "") + helpers_c(g) + WRAPPER
        assert_c28x_clean(f"helpers G={g}", text)
        src = tmp_path / f"h{g}.c"
        src.write_text(text)
        r = subprocess.run([clang, "--target=msp430", "-ffreestanding", "-fsyntax-only", *STRICT_WARN, str(src)],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr

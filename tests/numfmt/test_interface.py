"""The fixed-point interface: the header states each field's Q format, and mpc_binding.h's integer
conversions (no double) are bit for bit their Python models (codegen.numfmt.interface), which are
checked against exact rational arithmetic (fractions)."""
from __future__ import annotations

import ctypes
import math
import subprocess
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from codegen.manifest import sources
from codegen.numfmt.interface import adc_gain, f32_from_bits, q_from_f32, q_scale
from codegen.numfmt.scaling import INT32_MAX, INT32_MIN
from codegen.topology import topology_of

from conftest import SPMSM, STRICT_WARN, TTYPE, model_for

QS = (-12, -1, 0, 6, 14, 19, 23, 30, 44, 61)

WRAPPER = r"""
#include <stdint.h>
#include "mpc_binding.h"
void t_from_f32(const float *x, int32_t *out, int32_t n, int q)
{
    for (int32_t i = 0; i < n; ++i) {
        out[i] = %(p)s_q_from_f32(x[i], q);
    }
}
void t_scale(const int32_t *x, const int32_t *k, const int32_t *s, int32_t *out, int32_t n, uint32_t *sat)
{
    for (int32_t i = 0; i < n; ++i) {
        out[i] = %(p)s_q_scale(x[i], k[i], (int)s[i], sat);
    }
}
void t_ia_from_adc(const int32_t *c, int32_t offset, int32_t gk, int gs, int32_t *out, int32_t n, uint32_t *sat)
{
    for (int32_t i = 0; i < n; ++i) {
        out[i] = %(p)s_ia_a_from_adc(c[i], offset, gk, gs, sat);
    }
}
"""


@pytest.fixture(scope="module")
def fixed_files():
    m = model_for(SPMSM, number_format="fixed", tables="published")
    t = topology_of(m).derive(m)
    return m, t, sources(m, "host", t)


@pytest.fixture(scope="module")
def lib(fixed_files, tmp_path_factory):
    """The generated binding's helpers in a shared library (strict flags, UBSan)."""
    m, _, files = fixed_files
    d = tmp_path_factory.mktemp("binding")
    for name, text in files.items():
        (d / name).write_text(text)
    (d / "w.c").write_text(WRAPPER % {"p": m.prefix})
    so = d / "w.so"
    r = subprocess.run(["gcc", *STRICT_WARN, "-shared", "-fPIC", "-fsanitize=undefined", "-fno-sanitize-recover=all",
                        f"-I{d}", str(d / "w.c"), "-o", str(so)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    arm = subprocess.run(["arm-none-eabi-gcc", *STRICT_WARN, "-mcpu=cortex-m3", "-mthumb", "-mfloat-abi=soft",
                          f"-I{d}", "-c", str(d / "w.c"), "-o", str(d / "w_m3.o")], capture_output=True, text=True)
    assert arm.returncode == 0, arm.stderr
    return ctypes.CDLL(str(so))


def _ptr(a: np.ndarray):
    return a.ctypes.data_as(ctypes.c_void_p)


def _c_from_f32(lib, x: np.ndarray, q: int) -> np.ndarray:
    x = np.ascontiguousarray(x, np.float32)
    out = np.zeros(len(x), np.int32)
    lib.t_from_f32(_ptr(x), _ptr(out), ctypes.c_int32(len(x)), ctypes.c_int(q))
    return out


def _np_from_f32(x: np.ndarray, q: int) -> np.ndarray:
    """floor(x 2^q + 1/2) in float64 (exact: x 2^q is a float32 value scaled by a power of two, and
    v + 1/2 is exact below 2^52, where int32 saturates anyway), saturated, NaN -> 0."""
    v = np.ldexp(x.astype(np.float64), q)
    v = np.floor(np.where(np.isnan(v), 0.0, v) + 0.5)
    return np.clip(v, INT32_MIN, INT32_MAX).astype(np.int64)


def _f32_cases(n: int = 200_000) -> np.ndarray:
    rng = np.random.default_rng(3)
    bits = rng.integers(0, 2**32, n, dtype=np.uint64).astype(np.uint32)
    special = np.array([0, 0x80000000, 1, 0x80000001, 0x007FFFFF, 0x00800000, 0x7F7FFFFF, 0xFF7FFFFF,
                        0x7F800000, 0xFF800000, 0x7FC00000, 0xFFC00001, 0x3F000000, 0xBF000000, 0x3F800000],
                       np.uint32)
    x = np.concatenate([bits, special]).view(np.float32)
    # halfway cases and their neighbours around counts of every Q tried
    halves = np.concatenate([(np.arange(-3000, 3000) + 0.5) * 2.0**-q for q in QS]).astype(np.float32)
    near = np.concatenate([np.nextafter(halves, np.float32(np.inf)), np.nextafter(halves, np.float32(-np.inf))])
    return np.concatenate([x, halves, near, np.float32(2.0**31) * np.array([1, -1], np.float32)])


def test_q_from_f32_model_is_exact():
    """The Python model against exact rationals, on edge cases (the C is checked against the model)."""
    for bits in (0, 1, 0x3F000000, 0xBF000000, 0x7F7FFFFF, 0x4EFFFFFF, 0xCF000000, 0x7FC00000, 0xFF800000):
        x = f32_from_bits(bits)
        for q in QS:
            want = 0 if math.isnan(x) else max(INT32_MIN, min(INT32_MAX, math.floor(
                Fraction(x) * Fraction(2) ** q + Fraction(1, 2)))) if math.isfinite(x) else \
                (INT32_MAX if x > 0 else INT32_MIN)
            assert q_from_f32(x, q) == want


def test_q_from_f32_is_bit_exact(lib):
    x = _f32_cases()
    for q in QS:
        got = _c_from_f32(lib, x, q)
        want = _np_from_f32(x, q)
        bad = np.flatnonzero(got != want)
        assert bad.size == 0, (q, x[bad[:5]], got[bad[:5]], want[bad[:5]])
    # a sample against the Fraction model too
    for v in x[:: len(x) // 500]:
        for q in (0, 14, 44):
            assert int(_c_from_f32(lib, np.array([v]), q)[0]) == q_from_f32(float(v), q)


def test_q_from_f32_matches_the_encoding_of_the_states(fixed_files):
    """q_from_f32 of a float32 value is Scaling.encode of it (the rule the verified states use)."""
    _, t, _ = fixed_files
    x = _f32_cases(20_000)
    x = x[np.isfinite(x)]
    for unit in ("A", "V", "rad", "rad/s", "N*m"):
        q = t.scaling.q(unit)
        assert np.array_equal(_np_from_f32(x, q), t.scaling.encode(unit, x.astype(np.float64)).astype(np.int64))


@settings(max_examples=3000, deadline=None)
@given(st.integers(INT32_MIN, INT32_MAX), st.integers(INT32_MIN, INT32_MAX), st.integers(-62, 62))
def test_q_scale_is_exact(lib, x, k, s):
    out = np.zeros(1, np.int32)
    sat = ctypes.c_uint32(0)
    xs, ks, ss = (np.array([v], np.int32) for v in (x, k, s))
    lib.t_scale(_ptr(xs), _ptr(ks), _ptr(ss), _ptr(out), ctypes.c_int32(1), ctypes.byref(sat))
    want, saturated = q_scale(x, k, s)
    assert want == math.floor(Fraction(x * k) / Fraction(2) ** s + Fraction(1, 2)) or saturated
    assert (int(out[0]), sat.value) == (want, int(saturated))


@pytest.mark.parametrize("gain", [3.3 / 4096 / 0.05, 1e-3, 0.25, 7.0, 1e-6])
def test_adc_helper_exhaustive_over_a_12_bit_converter(lib, fixed_files, gain):
    """Every 12-bit ADC code: (code - offset) x gain into the ia_a counts, half up, saturations counted."""
    _, t, _ = fixed_files
    k, s = adc_gain(gain)
    assert 2**29 <= k < 2**30 and abs(k * 2.0**-s - gain) <= gain * 2.0**-29
    codes = np.arange(-5000, 9096, dtype=np.int32)
    offset = 2048
    out = np.zeros(len(codes), np.int32)
    sat = ctypes.c_uint32(0)
    lib.t_ia_from_adc(_ptr(codes), ctypes.c_int32(offset), ctypes.c_int32(k), ctypes.c_int(s), _ptr(out),
                      ctypes.c_int32(len(codes)), ctypes.byref(sat))
    q = t.scaling.q("A")
    want = [q_scale(int(c) - offset, k, s - q) for c in codes.tolist()]
    assert out.tolist() == [w for w, _ in want]
    assert sat.value == sum(v for _, v in want)
    exact = [math.floor(Fraction(int(c) - offset) * Fraction(k) * Fraction(2) ** (q - s) + Fraction(1, 2))
             for c in codes[:: 97].tolist()]
    assert out[:: 97].tolist() == [max(INT32_MIN, min(INT32_MAX, e)) for e in exact]


@pytest.mark.parametrize("path", [SPMSM, TTYPE], ids=["spmsm", "tlevel"])
def test_header_states_each_fields_q_format(path):
    """A fixed header says counts (not SI) and gives each real field's Q format, LSB and range, and a
    define of its fractional bits; the float32 header says SI units and has no Q format."""
    over = {"tables": "published"} if path == SPMSM else {}
    m = model_for(path, number_format="fixed", **over)
    t = topology_of(m).derive(m)
    h = sources(m, "host", t)[f"{m.prefix}_mpc.h"]
    assert "with int32 counts, not SI units" in h and "(SI units, names carry the unit)" not in h
    topo = topology_of(m)
    for rec in (topo.input_record, topo.output_record(m)):
        for f in rec.fields:
            if f.kind != "real":
                continue
            q = t.scaling.q(f.unit)
            assert f"#define {m.prefix.upper()}_Q_{f.name.upper()} {q} /* {t.scaling.describe(f.unit)}" in h
            assert f"int32 count of {t.scaling.describe(f.unit)}: 1 LSB = 2^{-q}" in h
    b = sources(m, "host", t)["mpc_binding.h"]
    assert f"{m.prefix}_q_from_f32" in b and f"{m.prefix}_q_scale" in b
    m32 = model_for(path, **over)
    h32 = sources(m32, "host")[f"{m32.prefix}_mpc.h"]
    assert "(SI units, names carry the unit)" in h32 and "_Q_" not in h32 and "int32 count" not in h32

"""The portable float32 speed PI (``<prefix>_speed_pi.c``): strict on gcc and arm-none-eabi-gcc,
bit for bit equal to a float32 numpy model of the same operations, and within a stated tolerance
of the float64 PI the host simulator runs (codegen/simulator/csrc/speed_pi.c)."""
from __future__ import annotations

import re
import subprocess

import numpy as np

from codegen.render import render_speed_pi, speed_pi_constants

from conftest import M7_FLAGS, SPMSM, STRICT_WARN, compile_strict, model_for, require_tool

F = np.float32
#: |float32 PI - float64 PI| over the sequence, relative to limit_nm
TOLERANCE = 1e-4


def _errors(limit_rad_s: float, n: int = 4000) -> tuple[np.ndarray, np.ndarray]:
    """(w_ref, w_m) in rad/s: steps, ramps, saturation both ways, random noise."""
    rng = np.random.default_rng(7)
    t = np.arange(n)
    w_ref = np.where(t < n // 4, limit_rad_s, np.where(t < n // 2, -limit_rad_s, 0.3 * limit_rad_s))
    w_m = 0.5 * limit_rad_s * np.sin(t / 300.0) + rng.normal(0, 0.01 * limit_rad_s, n)
    return w_ref.astype(F), w_m.astype(F)


def _model_f32(kp: F, ki_dt: F, lim: F, w_ref: np.ndarray, w_m: np.ndarray) -> np.ndarray:
    """The C's operations in numpy float32, in its order."""
    integral, out = F(0), np.zeros(len(w_ref), F)
    for j, (r, w) in enumerate(zip(w_ref, w_m)):
        e = F(r - w)
        u = F(F(kp * e) + integral)
        out[j] = lim if u > lim else (-lim if u < -lim else u)
        if not ((u > lim and e > 0) or (u < -lim and e < 0)):
            i_new = F(integral + F(ki_dt * e))
            integral = lim if i_new > lim else (-lim if i_new < -lim else i_new)
    return out


def _pi_f64(kp: float, ki: float, dt: float, lim: float, w_ref: np.ndarray, w_m: np.ndarray) -> np.ndarray:
    """The host simulator's float64 PI (speed_pi.c), in Python."""
    integral, out = 0.0, np.zeros(len(w_ref))
    for j, (r, w) in enumerate(zip(w_ref.astype(float), w_m.astype(float))):
        e = r - w
        u = kp * e + integral
        out[j] = min(max(u, -lim), lim)
        if not ((u > lim and e > 0.0) or (u < -lim and e < 0.0)):
            integral = min(max(integral + ki * e * dt, -lim), lim)
    return out


DRIVER = r"""
#include <stdio.h>
#include <stdint.h>
#include <string.h>
#include "%(p)s_speed_pi.h"
int main(void)
{
    %(p)s_speed_pi_t pi;
    float r, w;
    %(p)s_speed_pi_reset(&pi);
    while (scanf("%%a %%a", &r, &w) == 2) {
        float t = %(p)s_speed_pi_step(&pi, r, w);
        uint32_t bits;
        memcpy(&bits, &t, sizeof bits);
        printf("%%08lx\n", (unsigned long)bits);
    }
    return 0;
}
"""


def test_speed_pi_strict_bit_exact_and_close_to_float64(tmp_path):
    m = model_for(SPMSM)
    files = render_speed_pi(m, "stm32h743")
    assert files == render_speed_pi(m, "stm32h743")  # deterministic
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    src = tmp_path / f"{m.prefix}_speed_pi.c"
    compile_strict(src, tmp_path / "pi.o")
    arm = require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    compile_strict(src, tmp_path / "pi_m7.o", (arm, *M7_FLAGS))
    # the host program: strict flags but no -ffp-contract=off and FMA available (the pragma holds)
    (tmp_path / "main.c").write_text(DRIVER % {"p": m.prefix})
    exe = tmp_path / "pi"
    flags = [f for f in STRICT_WARN if f != "-ffp-contract=off"]
    r = subprocess.run(["gcc", *flags, "-mfma", f"-I{tmp_path}", str(tmp_path / "main.c"), str(src), "-o", str(exe)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr

    sl, dt = m.speed_loop, m.controller.dt_s
    k = {c.name: c.value for c in speed_pi_constants(m)}
    assert k["SPI_KI_DT"] == F(sl.ki * dt) and k["SPI_KP"] == F(sl.kp) and k["SPI_LIMIT_NM"] == F(sl.limit_nm)
    # speed errors large enough to saturate both ways (kp e beyond the limit) and small ones
    w_ref, w_m = _errors(3.0 * sl.limit_nm / sl.kp)
    stdin = "".join(f"{float(a).hex()} {float(b).hex()}\n" for a, b in zip(w_ref, w_m))
    got = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=True).stdout.split()
    c_out = np.array([int(h, 16) for h in got], np.uint32).view(F)
    want = _model_f32(k["SPI_KP"], k["SPI_KI_DT"], k["SPI_LIMIT_NM"], w_ref, w_m)
    assert c_out.view(np.uint32).tobytes() == want.view(np.uint32).tobytes()
    assert (np.abs(c_out) == F(sl.limit_nm)).any() and (np.abs(c_out) < F(sl.limit_nm)).any()
    ref64 = _pi_f64(sl.kp, sl.ki, dt, sl.limit_nm, w_ref, w_m)
    assert np.max(np.abs(c_out.astype(float) - ref64)) <= TOLERANCE * sl.limit_nm


FIXED_DRIVER = r"""
#include <stdio.h>
#include <stdint.h>
#include "%(p)s_speed_pi.h"
int main(void)
{
    %(p)s_speed_pi_t pi;
    long r, w;
    %(p)s_speed_pi_reset(&pi);
    while (scanf("%%ld %%ld", &r, &w) == 2) {
        printf("%%ld\n", (long)%(p)s_speed_pi_step(&pi, (int32_t)r, (int32_t)w));
    }
    return 0;
}
"""


def _fixed_pi(m):
    """The fixed-point model's generated speed PI files and its Python reference (FixedSpeedPI)."""
    from codegen.manifest import sources
    from codegen.numfmt.speedpi import FixedSpeedPI
    from codegen.topology import topology_of

    t = topology_of(m).derive(m)
    files = {k: v for k, v in sources(m, "host", t).items() if "_speed_pi." in k}
    sl = m.speed_loop
    return files, FixedSpeedPI.of(sl.kp, sl.ki * m.controller.dt_s, sl.limit_nm, t.scaling)


def test_fixed_speed_pi_is_integer_and_bit_exact(tmp_path):
    """A fixed-point build's speed PI is integer C in the step's Q formats (no float anywhere), strict on
    gcc and arm-none-eabi-gcc for a core without FPU, and bit for bit the Python reference
    (codegen.numfmt.speedpi) over steps, ramps, saturation both ways, noise and the int32 extremes;
    within a few counts of the float64 PI."""
    m = model_for(SPMSM, number_format="fixed", tables="published")
    files, ref = _fixed_pi(m)
    for name, text in files.items():
        (tmp_path / name).write_text(text)
        code = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
        assert "float" not in code and "double" not in code, name
    src = tmp_path / f"{m.prefix}_speed_pi.c"
    compile_strict(src, tmp_path / "pi.o")
    arm = require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    compile_strict(src, tmp_path / "pi_m3.o", (arm, "-mcpu=cortex-m3", "-mthumb", "-mfloat-abi=soft"))
    (tmp_path / "main.c").write_text(FIXED_DRIVER % {"p": m.prefix})
    exe = tmp_path / "pi"
    r = subprocess.run(["gcc", *STRICT_WARN, "-fsanitize=undefined", "-fno-sanitize-recover=all", f"-I{tmp_path}",
                        str(tmp_path / "main.c"), str(src), "-o", str(exe)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr

    sl = m.speed_loop
    w_ref, w_m = _errors(3.0 * sl.limit_nm / sl.kp)
    q = ref.q_speed
    r_n = np.floor(w_ref.astype(float) * 2.0**q + 0.5).astype(np.int64)
    m_n = np.floor(w_m.astype(float) * 2.0**q + 0.5).astype(np.int64)
    ext = np.array([2**31 - 1, -2**31, 0, 2**31 - 1, -2**31, -2**31, 2**31 - 1, 5, -5], np.int64)
    r_n = np.concatenate([r_n, ext, np.zeros(50, np.int64)])
    m_n = np.concatenate([m_n, ext[::-1], np.zeros(50, np.int64)])
    stdin = "".join(f"{a} {b}\n" for a, b in zip(r_n.tolist(), m_n.tolist()))
    got = np.array(subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=True).stdout.split(),
                   np.int64)
    want = ref.run(r_n, m_n)
    assert np.array_equal(got, want)
    assert (np.abs(want) == ref.limit).any() and (np.abs(want) < ref.limit).any()
    # the same PI as the float64 one, to the formats' resolution (gains kept to 30 bits)
    n = len(w_ref)
    ref64 = _pi_f64(sl.kp, sl.ki, m.controller.dt_s, sl.limit_nm, r_n[:n] * 2.0**-q, m_n[:n] * 2.0**-q)
    assert np.max(np.abs(want[:n] * 2.0**-ref.q_torque - ref64)) <= TOLERANCE * sl.limit_nm


def test_fixed_speed_pi_refuses_a_gain_it_cannot_hold():
    """A gain beyond the formats is a one-line RepresentationError naming the config field."""
    import pytest

    from codegen.numfmt.scaling import RepresentationError, Scaling
    from codegen.numfmt.speedpi import FixedSpeedPI

    sc = Scaling(20, (0, 0, 0), "global")
    FixedSpeedPI.of(5.0, 5e-4, 30.0, sc)
    with pytest.raises(RepresentationError) as e:
        FixedSpeedPI.of(1e12, 5e-4, 30.0, sc)
    assert e.value.field == "speed_loop.kp" and "\n" not in str(e.value)
    with pytest.raises(RepresentationError) as e:
        FixedSpeedPI.of(5.0, 1e-20, 30.0, sc)
    assert e.value.field == "speed_loop.ki"

"""The plant core, written once on ``sim_real_t`` (codegen/simulator/csrc/sim_real.h), compiled twice.

The host simulator compiles it in float64, the firmware's on-board loop in
float32 (``SIM_REAL_F32``).  Compiled both ways with the strict flags here:
the float32 speed PI equals a numpy float32 model of its operations bit for
bit (every literal a float: no double promotion), the double one the host
simulator's ``speed_pi_step`` formula; and both topologies' right-hand
sides, integrated over the same switching sequence, agree between float32
and float64 to float32 accuracy.
"""
from __future__ import annotations

import subprocess

import numpy as np
import pytest

from codegen.simulator.api import CORE_HEADERS, firmware_files
from codegen.topologies.ttype import sim as ttype_sim
from codegen.topologies.twolevel import sim as twolevel_sim

from conftest import ROOT, STRICT_WARN

F = np.float32
KP, KI, DT, LIMIT = 5.0, 10.0, 50e-6, 30.0
#: periods of the switching sequences
PERIODS = 400

DRIVER = r"""
#include <stdio.h>

#include "sim_real.h"
#include "speed_pi.h"
#include "ttype_rhs.h"
#include "twolevel_rhs.h"

static void put(sim_real_t v)
{
    printf("%a\n", (double)v);
}

static void motor(pmsm_dq_rhs_t *m, sim_real_t load_nm)
{
    pmsm_dq_rhs_setup(m, SIM_R(0.2), SIM_R(8.5e-3), SIM_R(12.5e-3), SIM_R(0.175), 4, SIM_R(0.012), SIM_R(1e-3),
                      load_nm, 0);
}

int main(void)
{
    const sim_real_t dt = SIM_R(50e-6), h_max = SIM_R(5e-6);
    sim_real_t integral = SIM_R(0.0), x[5] = {SIM_R(0.0), SIM_R(0.0), SIM_R(20.0), SIM_R(0.0), SIM_R(0.0)};
    double w_ref, w_m;
    int k, i;
    /* the speed PI over the (w_ref, w_m) pairs on stdin */
    while (scanf("%la %la", &w_ref, &w_m) == 2) {
        put(speed_pi_update(SIM_R(5.0), SIM_R(10.0), dt, SIM_R(30.0), &integral, (sim_real_t)w_ref,
                            (sim_real_t)w_m));
        put(integral);
    }
    /* two-level: a switching state per period */
    for (k = 0; k < PERIODS; ++k) {
        twolevel_rhs_t c;
        int lv[3];
        twolevel_rhs_levels((k * 5 + k / 7) % 8, lv);
        twolevel_rhs_setup(&c, lv, SIM_R(312.0), SIM_R(0.0));
        motor(&c.m, SIM_R(2.0));
        twolevel_rhs_interval(&c, x, dt, sim_inverter_substeps(dt, h_max));
        for (i = 0; i < 4; ++i) {
            put(x[i]);
        }
    }
    /* T-type: seven segments per period, the neutral point moving */
    for (k = 0; k < PERIODS; ++k) {
        for (i = 0; i < 7; ++i) {
            ttype_rhs_t c;
            int lv[3];
            const sim_real_t len = (i == 3) ? SIM_R(20e-6) : SIM_R(5e-6);
            (void)ttype_rhs_levels((k * 11 + i * 5) % 27, lv);
            ttype_rhs_setup(&c, lv, SIM_R(220.0), SIM_R(1000e-6), SIM_R(0.0));
            motor(&c.m, SIM_R(1.0));
            ttype_rhs_interval(&c, x, len, sim_inverter_substeps(len, h_max));
        }
        x[3] = pmsm_dq_wrap(x[3]);
        for (i = 0; i < 5; ++i) {
            put(x[i]);
        }
    }
    return 0;
}
"""


def _speeds(n: int = 600) -> tuple[np.ndarray, np.ndarray]:
    """(w_ref, w_m) float32 pairs, rad/s: saturation both ways and small errors."""
    rng = np.random.default_rng(3)
    t = np.arange(n)
    w_ref = np.where(t < n // 3, 50.0, np.where(t < 2 * n // 3, -50.0, 10.0))
    w_m = 20.0 * np.sin(t / 40.0) + rng.normal(0.0, 0.5, n)
    return w_ref.astype(F), w_m.astype(F)


def _pi(real: type, w_ref: np.ndarray, w_m: np.ndarray) -> np.ndarray:
    """speed_pi_update's operations, one rounding each in ``real``: (T*, integral) per call."""
    kp, ki, dt, lim = real(KP), real(KI), real(DT), real(LIMIT)
    integral, out = real(0.0), []
    for r, w in zip(w_ref.astype(real), w_m.astype(real)):
        e = real(r - w)
        u = real(real(kp * e) + integral)
        out.append(lim if u > lim else (-lim if u < -lim else u))
        if not ((u > lim and e > 0) or (u < -lim and e < 0)):
            i_new = real(integral + real(real(ki * e) * dt))
            integral = lim if i_new > lim else (-lim if i_new < -lim else i_new)
        out.append(integral)
    return np.array(out, real)


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, np.ndarray]:
    """The driver's output compiled in float64 and in float32 (the firmware's -DSIM_REAL_F32)."""
    tmp = tmp_path_factory.mktemp("core")
    src = tmp / "core.c"
    src.write_text(DRIVER.replace("PERIODS", str(PERIODS)))
    dirs = sorted({p.parent for p in (*CORE_HEADERS, *twolevel_sim.SIM.core_headers, *ttype_sim.SIM.core_headers)})
    w_ref, w_m = _speeds()
    stdin = "".join(f"{float(a).hex()} {float(b).hex()}\n" for a, b in zip(w_ref, w_m))
    out = {}
    for name, defs in (("f64", []), ("f32", ["-DSIM_REAL_F32"])):
        exe = tmp / f"core_{name}"
        r = subprocess.run(["gcc", *STRICT_WARN, *defs, *[f"-I{d}" for d in dirs], str(src), "-o", str(exe), "-lm"],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        text = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=True).stdout
        out[name] = np.array([float.fromhex(v) for v in text.split()])
    return out


def test_the_float32_and_float64_speed_pi_are_its_operations_in_each_type(runs):
    w_ref, w_m = _speeds()
    n = 2 * len(w_ref)
    f32 = _pi(np.float32, w_ref, w_m)
    assert runs["f32"][:n].astype(F).tobytes() == f32.tobytes()  # every operation in float: no promotion
    assert runs["f64"][:n].tobytes() == _pi(np.float64, w_ref, w_m).tobytes()
    assert (np.abs(f32[::2]) == F(LIMIT)).any() and (np.abs(f32[::2]) < F(LIMIT)).any()


@pytest.mark.parametrize("part,width,start", [("two-level", 4, 0), ("T-type", 5, 4 * PERIODS)])
def test_the_float32_plant_tracks_the_float64_one(runs, part, width, start):
    n0 = 2 * len(_speeds()[0])
    lo, hi = n0 + start, n0 + start + width * PERIODS
    x64 = runs["f64"][lo:hi].reshape(PERIODS, width)
    x32 = runs["f32"][lo:hi].reshape(PERIODS, width)
    assert np.all(np.isfinite(x64)) and np.abs(x64[:, :2]).max() > 1.0  # currents flow
    scale = np.abs(x64).max(axis=0)
    err = np.abs(x32 - x64).max(axis=0) / scale
    assert np.all(err[[0, 1, 2]] < 1e-4), err
    angle = np.abs(np.angle(np.exp(1j * (x32[:, 3] - x64[:, 3]))))
    assert angle.max() < 1e-4
    assert not np.array_equal(x32, x64)  # really two types


@pytest.mark.parametrize("sim", [twolevel_sim, ttype_sim], ids=["two-level", "T-type"])
def test_the_firmware_gets_the_core_the_host_compiles(sim):
    """The on-board plant's files: the simulator's core headers, the topology's, its on-board C; the host
    build's headers include the same core."""
    files = firmware_files(sim.SIM)
    core = {p.name for p in (*CORE_HEADERS, *sim.SIM.core_headers)}
    assert core <= set(files) and any(n.endswith(".c") for n in files)
    for name in core:
        path = next(p for p in (*CORE_HEADERS, *sim.SIM.core_headers) if p.name == name)
        assert files[name] == path.read_text()
    assert not (set(files) & {p.name for p in (ROOT / "firmware" / "runtime").iterdir()})  # one copy each

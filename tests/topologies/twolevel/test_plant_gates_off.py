"""The two-level plant with the gates off (csrc/twolevel_plant.c, sim_inverter.h "The open inverter")
against its analytic decays, and the active short circuit (the safe vector 000 applied) against its own.

Set-up (every test at standstill, the speed imposed at 0: no back-EMF; amplitude-invariant
Clarke, i_alpha = i_a, i_beta = (i_a + 2 i_b)/sqrt(3); the phase equations of the dq model are
u_xn = Rs i_x + dpsi_x/dt):

* **Gates off, a winding pair.**  i_a = I0 > 0, i_b = -I0, i_c = 0.  Every switch off: a's current
  comes up the lower diode (v_a = 0), b's goes up the upper diode (v_b = Udc), c's diodes block
  (i_c stays 0, its leg floats).  Loop a -> b across the DC link, u_ab = v_a - v_b = -Udc:
  with i_ab = i (1, -1/sqrt(3)) = (2/sqrt(3)) i e, e the unit vector at -30 deg, the power
  u_ab i = (3/2) u_ab.i_ab = (3/2)(4/3)(Rs i^2 + (e^T L e) i di/dt), L = Rot(theta) diag(Ld, Lq)
  Rot(theta)^T, so the pair is R = 2 Rs and L = 2 (Ld cos^2(phi) + Lq sin^2(phi)) in series,
  phi = -pi/6 - theta the angle of e from the d axis (a surface PMSM: L = 2 Ls):

      L di/dt = -(Udc + R i)  =>  i(t) = (I0 + Udc/R) exp(-t R/L) - Udc/R,
      zero at t0 = (L/R) ln(1 + R I0/Udc),

  after which every diode blocks and i = 0 for good (no EMF to drive it).
* **Gates off, all three phases.**  i_a = I0, i_b = i_c = -I0/2 (surface PMSM, Ls): a on the lower
  diode (v_a = 0), b and c on the upper (Udc); u_alpha = (2/3)(v_a - (v_b + v_c)/2) = -2 Udc/3, so
  Ls di_a/dt = -2 Udc/3 - Rs i_a and all three reach zero together at
  t0 = (Ls/Rs) ln(1 + 3 Rs I0/(2 Udc)).
* **Active short circuit** (the safe vector 000 applied: every phase on the lower rail, u = 0):
  Ld di_d/dt = -Rs i_d, Lq di_q/dt = -Rs i_q, so i_d(t) = i_d0 exp(-t Rs/Ld), i_q(t) =
  i_q0 exp(-t Rs/Lq) (surface PMSM: every phase current i_x(t) = i_x0 exp(-t Rs/Ls)).

The zero crossing is compared with t0 at the RK4 sub-step resolution (the first 1 us sub-step
boundary with every current exactly 0 is the one after t0) and, inside one call, within 10 ns
(the crossing is located inside its sub-step); the decays before it and the short circuit to a
relative 1e-9 (RK4 at 1 us sub-steps against time constants of milliseconds: its truncation
error is far below that, the bound is rounding).

Beyond the analytic cases: with the back-EMF above the DC link the open inverter rectifies; the
plant matches an independent abc-frame model of the diode bridge (scipy, event-located mode
changes) within 10 uA, and with the back-EMF below the DC link the currents decay to exactly zero
and stay there while the rotor turns.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tests.fixtures.plantref import plant_params

H = 1e-6  # the sub-step (docs/simulation.md: at most 1 us)
SPMSM = dict(rs_ohm=0.2, ld_h=8.5e-3, lq_h=8.5e-3, psi_f_wb=0.175, pole_pairs=4, j_kgm2=0.01, b_nms=0.0,
             udc_v=312.0)
IPMSM = dict(rs_ohm=0.25, ld_h=3.3e-3, lq_h=7.3e-3, psi_f_wb=0.2264, pole_pairs=3, j_kgm2=0.01, b_nms=0.0,
             udc_v=312.0)
SPINDLE = dict(rs_ohm=0.05, ld_h=150e-6, lq_h=150e-6, psi_f_wb=0.03, pole_pairs=1, j_kgm2=1e-4, b_nms=0.0,
               udc_v=310.0)
PHI = (0.0, 2 * math.pi / 3, -2 * math.pi / 3)  # phase axes a, b, c


def _dq(i_abc: tuple[float, float, float], theta: float) -> tuple[float, float]:
    """(i_d, i_q) of phase currents at theta (Clarke, Park)."""
    ial, ibe = i_abc[0], (i_abc[0] + 2 * i_abc[1]) / math.sqrt(3)
    return ial * math.cos(theta) + ibe * math.sin(theta), -ial * math.sin(theta) + ibe * math.cos(theta)


def _abc(s) -> np.ndarray:
    """Phase currents (i_a, i_b, i_c) of a plant state."""
    ial = s.i_d_a * math.cos(s.theta_e_rad) - s.i_q_a * math.sin(s.theta_e_rad)
    ibe = s.i_d_a * math.sin(s.theta_e_rad) + s.i_q_a * math.cos(s.theta_e_rad)
    ia, ib = ial, -0.5 * ial + math.sqrt(3) / 2 * ibe
    return np.array([ia, ib, -ia - ib])


def _state(ffi, i_abc, theta=0.0, wm=0.0):
    i_d, i_q = _dq(i_abc, theta)
    return ffi.new("pmsm_state_t *", {"i_d_a": i_d, "i_q_a": i_q, "omega_m_rad_s": wm, "theta_e_rad": theta})


def _open_steps(ffi, lib, p, x0, n):
    """Phase currents after each of n calls of one 1 us sub-step with the gates off, (n, 3)."""
    s = _state(ffi, *x0)
    out = np.zeros((n, 3))
    for k in range(n):
        assert lib.twolevel_plant_advance_open(s, p, 0.0, H, 1) == 0
        out[k] = _abc(s)
    return out


def _open_once(ffi, lib, p, x0, t):
    """Phase currents after one call over t (sub-steps of at most 1 us) with the gates off."""
    s = _state(ffi, *x0)
    assert lib.twolevel_plant_advance_open(s, p, 0.0, t, math.ceil(t / H)) == 0
    return _abc(s)


def _check_zero_crossing(ffi, lib, p, x0, i0, r, ell, udc):
    """The pair/phase current decays as (i0 + udc/r) exp(-t r/l) - udc/r, reaches zero at t0 within the
    sub-step resolution (and within 10 ns inside a call) and stays exactly zero."""
    t0 = ell / r * math.log(1 + r * i0 / udc)
    n = int(t0 / H) + 200
    i = _open_steps(ffi, lib, p, x0, n)
    t = H * np.arange(1, n + 1)
    zero = np.all(i == 0.0, axis=1)
    kz = int(np.argmax(zero))
    assert zero[kz] and np.all(zero[kz:])  # zero for good: no chattering
    assert t[kz] - H < t0 <= t[kz] + 1e-15, (t0, t[kz])  # the first sub-step end after t0
    ana = (i0 + udc / r) * np.exp(-t[:kz] * r / ell) - udc / r
    lead = int(np.argmax(np.abs(x0[0])))  # the phase carrying +-i0
    assert np.max(np.abs(np.abs(i[:kz, lead]) - ana)) <= 1e-9 * (i0 + udc / r)
    before, after = _open_once(ffi, lib, p, x0, t0 - 1e-8), _open_once(ffi, lib, p, x0, t0 + 1e-8)
    assert np.all(np.abs(before[np.abs(np.asarray(x0[0])) > 0]) > 0) and np.all(after == 0.0)
    return i[:kz]


@pytest.mark.parametrize("motor,theta", [(SPMSM, 0.0), (SPMSM, 2.0), (SPINDLE, 0.4), (IPMSM, -math.pi / 6),
                                         (IPMSM, math.pi / 3), (IPMSM, 1.0)],
                         ids=["spmsm", "spmsm-2rad", "spindle", "ipmsm-d", "ipmsm-q", "ipmsm-1rad"])
def test_gates_off_winding_pair_reaches_zero_at_t0(stub, motor, theta):
    ffi, lib = stub
    p = plant_params(ffi, "sim_params_t", motor, imposed=1)
    i0 = 40.0
    phi = -math.pi / 6 - theta  # the pair current's direction from the d axis
    l_pair = 2 * (motor["ld_h"] * math.cos(phi) ** 2 + motor["lq_h"] * math.sin(phi) ** 2)
    i = _check_zero_crossing(ffi, lib, p, ((i0, -i0, 0.0), theta), i0, 2 * motor["rs_ohm"], l_pair,
                             motor["udc_v"])
    # the blocked phase stays at zero, the pair carries equal and opposite currents
    assert np.max(np.abs(i[:, 2])) <= 1e-9 * i0
    assert np.max(np.abs(i[:, 0] + i[:, 1])) <= 1e-9 * i0


def test_gates_off_three_phases_reach_zero_together(stub):
    ffi, lib = stub
    p = plant_params(ffi, "sim_params_t", SPMSM, imposed=1)
    i0 = 30.0
    i = _check_zero_crossing(ffi, lib, p, ((i0, -i0 / 2, -i0 / 2), 0.7), i0, SPMSM["rs_ohm"],
                             SPMSM["ld_h"], 2 * SPMSM["udc_v"] / 3)  # Ls di/dt = -(2/3)Udc - Rs i
    assert np.max(np.abs(i[:, 1] - i[:, 2])) <= 1e-9 * i0


@pytest.mark.parametrize("motor", [SPMSM, IPMSM, SPINDLE], ids=["spmsm", "ipmsm", "spindle"])
def test_active_short_circuit_decays_exponentially(stub, motor):
    ffi, lib = stub
    p = plant_params(ffi, "sim_params_t", motor, imposed=1)
    i_d0, i_q0 = -12.0, 25.0
    s = ffi.new("pmsm_state_t *", {"i_d_a": i_d0, "i_q_a": i_q0, "omega_m_rad_s": 0.0, "theta_e_rad": 0.9})
    tau_d, tau_q = motor["ld_h"] / motor["rs_ohm"], motor["lq_h"] / motor["rs_ohm"]
    t, dt = 0.0, 50e-6
    for t_check in (0.1 * tau_d, 0.5 * tau_d, tau_d, 3 * tau_q):
        n = round((t_check - t) / dt)
        for _ in range(n):
            assert lib.twolevel_plant_advance(s, p, 0, 0.0, dt, 50) == 0  # the safe vector 000
        t += n * dt
        assert s.i_d_a == pytest.approx(i_d0 * math.exp(-t / tau_d), rel=1e-9)
        assert s.i_q_a == pytest.approx(i_q0 * math.exp(-t / tau_q), rel=1e-9)
    assert t > 2 * tau_q


# ---- the diode bridge with the rotor turning: an independent abc-frame model -------------------------

def _bridge_reference(m: dict[str, float], we: float, i0: np.ndarray, t_out: np.ndarray, drop_v: float) -> np.ndarray:
    """Phase currents of a surface PMSM (Ls = ld_h) turning at we behind an open two-level bridge, at t_out.

    Phase x: v_x - v_n = Rs i_x + Ls di_x/dt + e_x, e_x = -we psi_f sin(we t - phi_x).  Each leg
    conducts its lower diode ("L": i_x > 0, v_x = -Vd) or its upper one ("U": i_x < 0, v_x = Udc +
    Vd), or floats ("F": i_x = 0).  All three conducting: v_n = mean(v).  One floating, f, between a
    pair p, q (i_p = i = -i_q): 2 Ls di/dt = v_p - v_q - 2 Rs i - (e_p - e_q), the floating leg at v_f =
    (v_p + v_q)/2 + (3/2) e_f (from i_f = di_f/dt = 0 and e_a + e_b + e_c = 0); it conducts once v_f
    leaves [-Vd, Udc + Vd].  All floating: until max e - min e exceeds Udc + 2 Vd, then the highest
    phase "U", the lowest "L".  The mode changes are events located by scipy (DOP853).
    """
    rs, ls, pf, udc = m["rs_ohm"], m["ld_h"], m["psi_f_wb"], m["udc_v"]
    lo, hi = -drop_v, udc + drop_v

    def emf(t: float) -> np.ndarray:
        return -we * pf * np.sin(we * t - np.array(PHI))

    def floating_v(t: float, mode: list[str]) -> float:
        f = mode.index("F")
        p, q = [k for k in range(3) if k != f]
        return 0.5 * (_pot(mode[p]) + _pot(mode[q])) + 1.5 * emf(t)[f]

    def _pot(md: str) -> float:
        return hi if md == "U" else lo

    def rhs(t: float, i: np.ndarray, mode: list[str]) -> np.ndarray:
        e = emf(t)
        out = np.zeros(3)
        if mode.count("F") == 1:
            f = mode.index("F")
            p, q = [k for k in range(3) if k != f]
            out[p] = (_pot(mode[p]) - _pot(mode[q]) - 2 * rs * i[p] - (e[p] - e[q])) / (2 * ls)
            out[q] = -out[p]
        elif "F" not in mode:
            v = np.array([_pot(md) for md in mode])
            out = (v - v.mean() - rs * i - e) / ls
        return out

    def at_rest(t: float) -> list[str]:
        e = emf(t)
        mode = ["F"] * 3
        if np.ptp(e) > hi - lo:
            mode[int(np.argmax(e))], mode[int(np.argmin(e))] = "U", "L"
        return mode

    def one_zero(t: float, mode: list[str], k: int) -> list[str]:
        mode = list(mode)
        mode[k] = "F"
        vf = floating_v(t, mode)
        if vf < lo:
            mode[k] = "L"
        elif vf > hi:
            mode[k] = "U"
        return mode

    out = np.zeros((len(t_out), 3))
    t, i = 0.0, np.array(i0, float)
    mode = ["L" if x > 0 else "U" for x in i]
    j = 0
    while j < len(t_out):
        events, kinds = [], []
        for k in range(3):
            if mode[k] != "F":
                ev = (lambda kk: lambda _t, y: y[kk])(k)
                ev.terminal, ev.direction = True, (-1 if mode[k] == "L" else 1)
                events.append(ev)
                kinds.append(("zero", k))
        if mode.count("F") == 1:
            for bound, direction, md in ((lo, -1, "L"), (hi, 1, "U")):
                ev = (lambda b, mo: lambda tt, _y: floating_v(tt, mo) - b)(bound, list(mode))
                ev.terminal, ev.direction = True, direction
                events.append(ev)
                kinds.append((md, mode.index("F")))
        if mode.count("F") == 3:
            ev = lambda tt, _y: float(np.ptp(emf(tt))) - (hi - lo)  # noqa: E731
            ev.terminal, ev.direction = True, 1
            events.append(ev)
            kinds.append(("rest", -1))
        sol = solve_ivp(lambda tt, y, mo=list(mode): rhs(tt, y, mo), (t, t_out[-1]), i, method="DOP853",
                        rtol=1e-12, atol=1e-12, events=events, dense_output=True)
        while j < len(t_out) and t_out[j] <= sol.t[-1]:
            out[j] = sol.sol(t_out[j])
            j += 1
        if sol.status != 1:
            break
        t, i = sol.t[-1], sol.y[:, -1].copy()
        kind, k = kinds[next(n for n, te in enumerate(sol.t_events) if len(te))]
        if kind == "zero" and "F" in mode:  # the pair reached zero: every current
            i[:] = 0.0
            mode = at_rest(t)
        elif kind == "zero":  # one leg at zero, the other two a pair
            i[k] = 0.0
            p, q = [x for x in range(3) if x != k]
            i[p] = 0.5 * (i[p] - i[q])
            i[q] = -i[p]
            mode = one_zero(t, mode, k)
        elif kind == "rest":
            e = emf(t)
            mode = ["F"] * 3
            mode[int(np.argmax(e))], mode[int(np.argmin(e))] = "U", "L"
        else:  # the floating leg reached a rail: its diode conducts
            mode[k] = kind
    return out


@pytest.mark.parametrize("drop_v", [0.0, 1.5])
def test_gates_off_rectifies_like_a_diode_bridge(stub, drop_v):
    """The back-EMF (line peak sqrt(3)*w_e*psi_f = 182 V) above a 100 V DC link: the open inverter is
    an uncontrolled rectifier, the currents of the abc-frame reference within 10 uA."""
    ffi, lib = stub
    m = dict(SPMSM, udc_v=100.0)
    p = plant_params(ffi, "sim_params_t", m, imposed=1)
    p.device_drop_v = drop_v
    wm = 150.0
    we = m["pole_pairs"] * wm
    i0 = np.array([6.0, -1.0, -5.0])
    s = _state(ffi, tuple(i0), 0.0, wm)
    dt, n = 50e-6, 400  # two electrical periods
    got = np.zeros((n, 3))
    for k in range(n):
        assert lib.twolevel_plant_advance_open(s, p, 0.0, dt, 50) == 0
        got[k] = _abc(s)
    ref = _bridge_reference(m, we, i0, dt * np.arange(1, n + 1), drop_v)
    assert np.max(np.abs(got - ref)) < 1e-5, np.max(np.abs(got - ref))
    # the bridge conducts (currents of amperes) and only against the DC link: braking torque
    assert np.max(np.abs(got)) > 1.0
    te = 1.5 * m["pole_pairs"] * m["psi_f_wb"] * np.array([_dq(tuple(r), we * dt * (k + 1))[1]
                                                           for k, r in enumerate(got)])
    assert np.mean(te) < 0


def test_gates_off_below_the_dc_link_decays_to_zero_while_turning(stub):
    """The spindle at 30 000 r/min (line EMF peak 163 V < 310 V): from 75 A the currents reach exactly
    zero within a period or two and stay there; the torque is then exactly zero."""
    ffi, lib = stub
    p = plant_params(ffi, "sim_params_t", SPINDLE, imposed=1)
    wm = 30000.0 * 2 * math.pi / 60
    s = _state(ffi, (75.0, -20.0, -55.0), 0.3, wm)
    zero_from = None
    for k in range(200):
        assert lib.twolevel_plant_advance_open(s, p, 0.0, 25e-6, 25) == 0
        if s.i_d_a == 0.0 and s.i_q_a == 0.0:
            zero_from = k if zero_from is None else zero_from
        else:
            assert zero_from is None, k  # once zero, zero for good
    assert zero_from is not None and zero_from < 4


def test_period_with_the_gates_off_and_on_again(stub):
    """twolevel_plant_advance_period_gates: an open period is the open inverter over the period; the
    period after it, with a dead time, spends that dead time open (every switch turning on closes one
    dead time late), then the decision -- bit for bit the pieces; without an open period it is
    twolevel_plant_advance_period."""
    ffi, lib = stub
    p = plant_params(ffi, "sim_params_t", SPMSM, imposed=1)
    dt, td = 50e-6, 2e-6
    p.dt_s = dt
    x0 = ((20.0, -5.0, -15.0), 0.4, 100.0)
    a, b = _state(ffi, *x0), _state(ffi, *x0)
    assert lib.twolevel_plant_advance_period_gates(a, p, 3, 0, 5, 1, 0.0, 50, -1.0, ffi.NULL) == 0
    assert lib.twolevel_plant_advance_open(b, p, 0.0, dt, 50) == 0
    assert (a.i_d_a, a.i_q_a, a.theta_e_rad) == (b.i_d_a, b.i_q_a, b.theta_e_rad)
    assert not np.allclose(_abc(a), _abc(_state(ffi, *x0)))
    p.dead_time_s = td
    a, b = _state(ffi, *x0), _state(ffi, *x0)
    assert lib.twolevel_plant_advance_period_gates(a, p, 0, 1, 6, 0, 0.0, 50, -1.0, ffi.NULL) == 0
    assert lib.twolevel_plant_advance_open(b, p, 0.0, td, 2) == 0
    assert lib.twolevel_plant_advance(b, p, 6, 0.0, dt - td, 48) == 0
    assert (a.i_d_a, a.i_q_a, a.theta_e_rad) == (b.i_d_a, b.i_q_a, b.theta_e_rad)
    a, b = _state(ffi, *x0), _state(ffi, *x0)
    assert lib.twolevel_plant_advance_period_gates(a, p, 0, 0, 6, 0, 0.0, 50, -1.0, ffi.NULL) == 0
    assert lib.twolevel_plant_advance_period(b, p, 0, 6, 0.0, 50, -1.0, ffi.NULL) == 0
    assert (a.i_d_a, a.i_q_a, a.theta_e_rad) == (b.i_d_a, b.i_q_a, b.theta_e_rad)
    assert lib.twolevel_plant_advance_open(b, p, 0.0, dt, 0) == -1
    assert lib.twolevel_plant_advance_open(b, p, 0.0, -dt, 1) == -1

"""``mpcgen bench``: execution cost per step, every strategy side by side.

Host: every strategy's compiled step runs over the same recorded trajectory
(the conventional controller's closed-loop run of the config's scenario,
80 000 samples for the SPMSM, as seed-001 section 7 does), in one process,
interleaved, best of ``repeats`` in the timing thread's CPU time (the median and the spread beside it:
``HOST_TIMING``); reported as ns per step and the ratio to
the first strategy (conventional / mpdtc27).  Absolute nanoseconds on a
shared machine are noise; the ratios are the figure to compare with the
seed's Table 11.  Also: closed-loop simulation throughput in periods/s, and the simulator's plant
integrators side by side (``plant.integrator`` "rk4" and "exact": periods/s in interleaved rounds and
each one's largest current error against scipy's DOP853 over a short window;
``codegen.simulator.integrators``).

Emulated (``--emulated``): instructions per step on the emulated Cortex-M7
(codegen.emulate), reported as instructions -- not cycles -- for the config's
number format (``m7_instructions_per_step``) and, side by side, every number
format (``m7_instructions_per_step_float32``, ``m7_instructions_per_step_fixed``:
the same config and strategy with ``controller.number_format`` replaced).

Without an FPU (``--emulated --board qemu-m3``): every strategy in fixed point and in float32 compiled for
soft float (``-mfloat-abi=soft``: libgcc's software float) on the emulated Cortex-M3 (QEMU mps2-an385),
instructions per step (min/median/max/mean over the bench states and over the self-test states) and the
ratio float32/fixed (``m3_float32_over_fixed``); beside it the emulated Cortex-M7's instructions in both
formats and their ratio fixed/float32 (``m7_fixed_over_float32``).  No cycle estimate in this mode (the
pipeline model is the Cortex-M7's).  Every image names the C it compiled by its C hash (``c_hash``, of the
board's target profile ``c_hash_target``; ``codegen.manifest``).

Cycles (``--emulated``, the config's number format): ``m7_cycles_est_min/median/max``, the
step's executed path in the real image (traced in unicorn) through llvm-mca's Cortex-M7 pipeline
model, and ``m7_cycles_bound``, the essential operations at that model's issue limits, with
``m7_cycles_est_over_bound``; ``m7_cycles_bound_overlap`` the same operations with every unit
overlapping perfectly (``codegen.stages.cycles``; docs/targets.md "Cycle estimate").

One state set for every M7 figure: the instruction counts and the cycle estimate (and its bounds)
are taken over the same ``N_BENCH`` bench states (every one run in QEMU and every one traced), so
their medians and ratios describe the same steps; ``m7_states`` in the JSON and the printed
footnote state the count.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from codegen import __version__
from codegen.errors import MpcgenError
from codegen.manifest import C_HASH_DEFINITION
from codegen.model import Model
from codegen.numfmt import CONFIG_FORMATS, FLOAT_CONTROLLER, QUANTISED
from codegen.simulator import integrators
from codegen.stages.cycles import METHOD_NOTE
from codegen.stages.firmware import EMULATED_BOARD, NOFPU_BOARD, board_spec
from codegen.stages.fwdata import N_BENCH
from codegen.topology import topology_of

#: the boards ``bench --emulated`` runs (``--board``)
BENCH_BOARDS = (EMULATED_BOARD, NOFPU_BOARD)
#: the self-test states each bench image also runs (bit-exact, else the bench fails)
BENCH_SELFTEST = 1000
#: how each board's core is named in progress lines
_CORE = {EMULATED_BOARD: "Cortex-M7", NOFPU_BOARD: "Cortex-M3 (no FPU, soft float)"}

#: how the host timing is taken (printed and in the JSON)
HOST_TIMING = ("CPU time of the timing thread (time.thread_time_ns: a step descheduled by other work on a "
               "shared machine is not counted), strategies interleaved in each round; ns/step and the ratios "
               "from each strategy's fastest round, the median beside it, spread = median/min - 1")


def host_timing(libs: dict[str, Any], states: np.ndarray, repeats: int) -> dict[str, dict[str, float]]:
    """Per strategy: ``min`` and ``median`` ns per step over ``repeats`` interleaved rounds (CPU time of this
    thread: ``HOST_TIMING``) and ``spread`` = median/min - 1."""
    rounds: dict[str, list[float]] = {s: [] for s in libs}
    for _ in range(max(1, repeats)):
        for s, lib in libs.items():
            t0 = time.thread_time_ns()
            lib.step_batch(states)
            rounds[s].append((time.thread_time_ns() - t0) / len(states))
    out = {}
    for s, r in rounds.items():
        lo, med = float(np.min(r)), float(np.median(r))
        out[s] = {"min": lo, "median": med, "spread": med / lo - 1.0 if lo > 0 else 0.0}
    return out


def host_ns_per_step(libs: dict[str, Any], states: np.ndarray, repeats: int) -> dict[str, float]:
    """Best-of-``repeats`` ns per step (``host_timing``'s minimum), strategies interleaved in each round."""
    return {s: t["min"] for s, t in host_timing(libs, states, repeats).items()}


def emulated_instructions(model: Model, strategies: list[str], log: Callable[[str], None], *,
                          board: str = EMULATED_BOARD, cycles: bool = True, dump_selftest: bool = False
                          ) -> dict[str, dict[str, Any]]:
    """Instructions per step on the emulated ``board`` (QEMU -icount; qemu-m7, or qemu-m3: no FPU,
    float32 in soft float) for each strategy, in every number format a config can choose
    (``codegen.numfmt.CONFIG_FORMATS``): strategy -> format name -> figures, or None where the config
    does not fit another format (its error message under ``"error"``).

    Each image, in every number format, replays the same ``N_BENCH`` states of the float32
    baseline's recorded trajectory (``fwdata.trajectory_states``; two-level: the conventional
    closed-loop run; three-level: the 27-MPDTC run at rated speed) and also runs the bit-exact self-test
    (``BENCH_SELFTEST`` states; its instructions under ``"selftest"``, with the median when
    ``dump_selftest``); a mismatch or a digest disagreement is an error, never a number.  Each entry
    names the C the image compiled (``c_hash`` of the board's target profile ``c_hash_target``).
    ``log`` gets a line per phase of each image (project, build, QEMU run, digests, trace, pipeline
    model) and a heartbeat every few seconds while one runs (``codegen.stages.progress``).  With
    ``cycles`` (qemu-m7 only), in the config's own number format, each strategy also gets its
    estimated Cortex-M7 cycles and their lower bound (``codegen.stages.cycles.strategy_cycles``, under
    ``"cycles"``), traced over every one of the ``N_BENCH`` bench states the instruction counts are
    taken over (the same set: an error otherwise).
    """
    import tempfile

    from codegen.manifest import c_hash_of, sources
    from codegen.stages.cycles import strategy_cycles
    from codegen.stages.emulate import EmulationError, run_and_check

    spec = board_spec(board)
    if spec.qemu is None:
        raise MpcgenError(f"board {board} is not emulated: bench --emulated runs {', '.join(BENCH_BOARDS)}")
    if cycles and board != EMULATED_BOARD:
        raise MpcgenError(f"the cycle estimate models the Cortex-M7 ({EMULATED_BOARD}), not {board}")
    core = _CORE.get(board, board)
    own = model.controller.number_format
    out: dict[str, dict[str, Any]] = {s: {} for s in strategies}
    with tempfile.TemporaryDirectory(prefix=f"mpcgen-{board}-") as tmp:
        for fmt in (own, *(f for f in CONFIG_FORMATS if f != own)):
            for s in strategies:
                variant = model.with_controller(strategy=s, number_format=fmt)
                log(f"emulated {core}: building and running {s} ({fmt}) in QEMU")
                try:
                    tables = topology_of(variant).derive(variant)
                except MpcgenError as e:
                    if fmt == own:
                        raise
                    log(f"  {s} in {fmt}: not measured ({e})")
                    out[s][fmt] = {"error": str(e)}
                    continue
                work = Path(tmp) / f"{s}-{fmt}"
                r = run_and_check(variant, tables, work, n_selftest=BENCH_SELFTEST, log=log, board=board,
                                  dump_selftest=dump_selftest)
                if r.mismatches or not r.digests_match:
                    raise EmulationError(f"{s} ({fmt}) on {board}: emulated results differ from the reference "
                                         f"({r.mismatches} mismatches)")
                out[s][fmt] = {"min": r.instr_min, "median": r.instr_median, "max": r.instr_max,
                               "mean": r.instr_mean, "states_checked": r.states, "bench_states": r.bench_states,
                               "selftest": {"states": r.selftest_states, "min": r.selftest_min,
                                            "median": r.selftest_median, "max": r.selftest_max,
                                            "mean": r.selftest_mean},
                               "c_hash": c_hash_of(sources(variant, spec.profile, tables)),
                               "c_hash_target": spec.profile}
                if cycles and fmt == own:
                    log(f"  {s} ({fmt}): tracing the step in unicorn, cycles from llvm-mca (Cortex-M7)")
                    cy = strategy_cycles(variant, tables, work / "build" / "fw.elf",
                                         n_bench=N_BENCH, max_states=N_BENCH, log=log)
                    if cy["states"] != r.bench_states:
                        raise EmulationError(f"{s} ({fmt}): cycles estimated over {cy['states']} states, "
                                             f"instructions counted over {r.bench_states}: not the same set")
                    out[s][fmt]["cycles"] = cy
    return out


def _ratio(num: dict[str, Any], den: dict[str, Any], key: str = "median") -> float | None:
    """num[key] / den[key] of two formats' figures (None where either was not measured)."""
    a, b = num.get(key), den.get(key)
    return float(a) / float(b) if a is not None and b else None


def _nofpu_entry(m3: dict[str, Any], m7: dict[str, Any]) -> dict[str, object]:
    """JSON entries of one strategy without FPU: the qemu-m3 figures per format, the ratio float32/fixed
    (median, mean, max over the bench states; medians over the self-test states) and the qemu-m7
    instructions per format with their ratio fixed/float32."""
    entry: dict[str, object] = {}
    for fmt, st in m3.items():
        entry.update({f"m3_instructions_per_step_{fmt}": st.get("median"), f"m3_instructions_min_{fmt}": st.get("min"),
                      f"m3_instructions_max_{fmt}": st.get("max"), f"m3_instructions_mean_{fmt}": st.get("mean")})
    fx, fl = m3.get(QUANTISED, {}), m3.get(FLOAT_CONTROLLER, {})
    fl_over_fx = f"{FLOAT_CONTROLLER}_over_{QUANTISED}"
    entry.update({
        f"m3_{fl_over_fx}": _ratio(fl, fx), f"m3_{fl_over_fx}_mean": _ratio(fl, fx, "mean"),
        f"m3_{fl_over_fx}_max": _ratio(fl, fx, "max"),
        f"m3_selftest_{fl_over_fx}": _ratio(fl.get("selftest", {}), fx.get("selftest", {})),
        "m3_by_number_format": m3,
    })
    for fmt, st in m7.items():
        entry[f"m7_instructions_per_step_{fmt}"] = st.get("median")
    entry.update({f"m7_{QUANTISED}_over_{FLOAT_CONTROLLER}": _ratio(m7.get(QUANTISED, {}),
                                                                    m7.get(FLOAT_CONTROLLER, {})),
                  "m7_by_number_format": m7})
    return entry


def _cell(x: float | None, fmt: str = "6.0f") -> str:
    return format(x, fmt) if x is not None else "n/a"


def _nofpu_line(m3: dict[str, Any], m7: dict[str, Any]) -> str:
    """The table cells of one strategy without FPU: per format min/median/max/mean, the ratios."""
    cells = []
    for fmt in (QUANTISED, FLOAT_CONTROLLER):
        st = m3.get(fmt, {})
        cells.append(" / ".join(_cell(st.get(k)) for k in ("min", "median", "max", "mean")).rjust(31))
    fx, fl = m3.get(QUANTISED, {}), m3.get(FLOAT_CONTROLLER, {})
    ratios = " / ".join(_cell(_ratio(fl, fx, k), "5.2f") for k in ("median", "mean", "max"))
    self_ratio = _cell(_ratio(fl.get("selftest", {}), fx.get("selftest", {})), "5.2f")
    m7fx, m7fl = m7.get(QUANTISED, {}), m7.get(FLOAT_CONTROLLER, {})
    return (f"  {cells[0]}  {cells[1]}  {ratios:>18s}  {self_ratio:>8s}"
            f"  {_cell(m7fx.get('median'), '7.0f')}  {_cell(m7fl.get('median'), '7.0f')}"
            f"  {_cell(_ratio(m7fx, m7fl), '6.2f'):>6s}")


def _format_columns(per_format: dict[str, dict[str, Any]]) -> tuple[dict[str, object], str]:
    """JSON entries ``m7_instructions_per_step_<format>`` (median, None if not measured) and the
    table's cells, one per number format."""
    entry: dict[str, object] = {}
    cells = []
    for fmt, st in per_format.items():
        median = st.get("median")
        entry[f"m7_instructions_per_step_{fmt}"] = median
        cells.append(f"{median:9.0f}" if median is not None else f"{'n/a':>9s}")
    return entry, " ".join(cells)


def bench(model: Model, strategies: list[str], emulated: bool = False, repeats: int = 5,
          log: Callable[[str], None] = print, board: str = EMULATED_BOARD) -> dict[str, Any]:
    """Run the benchmark; returns the JSON-able result with a printable ``_table``.  ``board``: the
    emulated board of ``emulated`` (``BENCH_BOARDS``; qemu-m3: fixed point against soft float)."""
    if board not in BENCH_BOARDS:
        raise MpcgenError(f"--board = {board!r}: bench --emulated runs {', '.join(BENCH_BOARDS)}")
    topo = topology_of(model)
    traj = topo.trajectory(model, progress=lambda f: log(f"  recording trajectory {f:5.0%}"))
    states, sim_wall, n_periods = traj.states, traj.wall_s, traj.periods
    libs = {}
    for s in strategies:
        variant = model.with_controller(strategy=s)
        libs[s] = topo.host_library(variant, topo.derive(variant))
    log(f"timing {len(strategies)} strategies over {len(states)} recorded states, best of {repeats}")
    timing = host_timing(libs, states, repeats)
    base = strategies[0]
    result: dict[str, Any] = {
        "config": model.name, "config_hash": model.config_hash(), "version": __version__,
        "trajectory_states": int(len(states)),
        "sim_periods_per_s": n_periods / sim_wall if sim_wall > 0 else 0.0,
        "baseline": base,
        "strategies": {},
    }
    own = model.controller.number_format
    m7 = {}
    header = f"{'strategy':12s} {'host ns/step':>13s} {'ratio':>7s}"
    if emulated and board == NOFPU_BOARD:
        return _bench_nofpu(model, strategies, result, timing, header, repeats, log)
    if emulated:
        result.update({"board": board, "c_hash_definition": C_HASH_DEFINITION})
        m7 = emulated_instructions(model, strategies, log=log)
        header += (f"  M7 instr/step {own} (min/median/max)   ratio  "
                   + " ".join(f"{f:>9s}" for f in m7[base])
                   + f"   M7 est. cycles (min/median/max)  ratio  {'bound':>11s}  est/bound"
                   + f"  {'overlap bound':>13s}  est/overlap")
    rows = [header]
    for s in strategies:
        # with --emulated, ratio_to_conventional is the M7 instruction ratio (the issue's figure)
        entry, line = _host_entry(timing, s, base)
        if emulated:
            st = m7[s][own]
            m7_ratio = st["median"] / m7[base][own]["median"]
            columns, cells = _format_columns(m7[s])
            entry.update({
                "m7_states": st["bench_states"],
                "m7_instructions_per_step": st["median"], "m7_instructions_min": st["min"],
                "m7_instructions_max": st["max"], "m7_ratio_to_conventional": m7_ratio,
                "ratio_to_conventional": m7_ratio, **columns, "m7_by_number_format": m7[s],
            })
            line += (f"  {' ' * (len(own) + 1)}{st['min']:6.0f} / {st['median']:6.0f} / {st['max']:6.0f}"
                     f"   {m7_ratio:6.3f}  {cells}")
            cy = st["cycles"]
            cy_ratio = cy["median"] / m7[base][own]["cycles"]["median"]
            bound, overlap = (f"{cy[k + '_median']:.0f}" if cy[k + "_min"] == cy[k + "_max"]
                              else f"{cy[k + '_min']:.0f}-{cy[k + '_max']:.0f}" for k in ("bound", "bound_overlap"))
            entry.update({
                "m7_cycles_est_median": cy["median"], "m7_cycles_est_min": cy["min"],
                "m7_cycles_est_max": cy["max"], "m7_cycles_est_mean": cy["mean"],
                "m7_cycles_est_ratio_to_conventional": cy_ratio,
                "m7_cycles_bound": cy["bound_median"], "m7_cycles_bound_min": cy["bound_min"],
                "m7_cycles_bound_max": cy["bound_max"], "m7_cycles_est_over_bound": cy["est_over_bound"],
                "m7_cycles_bound_overlap": cy["bound_overlap_median"],
                "m7_cycles_bound_overlap_min": cy["bound_overlap_min"],
                "m7_cycles_bound_overlap_max": cy["bound_overlap_max"],
                "m7_cycles_est_over_bound_overlap": cy["est_over_bound_overlap"],
                "m7_cycles_est_states": cy["states"], "m7_cycles_est_paths": cy["paths"],
                "m7_cycles_est_path_instructions_median": cy["path_instructions_median"],
            })
            line += (f"   {cy['min']:6.0f} / {cy['median']:6.0f} / {cy['max']:6.0f}       {cy_ratio:6.3f}"
                     f"  {bound:>11s}  {cy['est_over_bound']:9.2f}  {overlap:>13s}  {cy['est_over_bound_overlap']:11.2f}")
        result["strategies"][s] = entry
        rows.append(line)
    rows.append(f"closed-loop simulation ({model.name}, {base}): {result['sim_periods_per_s']:,.0f} periods/s")
    result["simulator"] = integrators.compare(topo, model, rounds=repeats, log=log)
    rows += integrators.summary(result["simulator"], model.name)
    if emulated:
        n_states = m7[base][own]["bench_states"]
        result["m7_states"] = n_states
        rows.append(f"M7 states: every M7 figure (instructions and est. cycles, min/median/max and ratios) is "
                    f"taken over the same {n_states} bench states (the recorded trajectory, evenly spaced), each "
                    "run in QEMU and traced once in unicorn.")
        rows.append("M7 figures are instruction counts on the emulated Cortex-M7 (QEMU -icount), not cycles; "
                    f"the min/median/max and ratio columns are the config's number format ({own}), the last "
                    "columns the median in every number format (JSON m7_instructions_per_step_<format>), "
                    "each image's self-test bit-exact.")
        rows.append(f"M7 est. cycles ({own}): " + METHOD_NOTE + " Bounds: median over the traced states (range if "
                    "it varies with the candidates evaluated); est/bound: median estimate over median bound.")
    _host_footer(result, rows, timing, strategies, repeats)
    return result


def _host_entry(timing: dict[str, dict[str, float]], s: str, base: str) -> tuple[dict[str, object], str]:
    """A strategy's host timing entries (JSON) and table cells."""
    ns = timing[s]["min"]
    host_ratio = ns / timing[base]["min"]
    entry: dict[str, object] = {"host_ns_per_step": ns, "host_ns_ratio": host_ratio,
                                "host_ns_median": timing[s]["median"], "host_ns_spread": timing[s]["spread"],
                                "host_ns_ratio_of_medians": timing[s]["median"] / timing[base]["median"],
                                "ratio_to_conventional": host_ratio}
    return entry, f"{s:12s} {ns:13.1f} {host_ratio:7.3f}"


def _host_footer(result: dict[str, Any], rows: list[str], timing: dict[str, dict[str, float]],
                 strategies: list[str], repeats: int) -> None:
    result["host_timing"] = f"{HOST_TIMING}; {repeats} rounds"
    rows.append(f"host timing: {HOST_TIMING}; {repeats} rounds: "
                + ", ".join(f"{s} {timing[s]['min']:.1f} / {timing[s]['median']:.1f} ns "
                            f"(spread {100 * timing[s]['spread']:.1f} %)" for s in strategies))
    result["_table"] = "\n".join(rows)


def _bench_nofpu(model: Model, strategies: list[str], result: dict[str, Any],
                 timing: dict[str, dict[str, float]], header: str, repeats: int,
                 log: Callable[[str], None]) -> dict[str, Any]:
    """``bench --emulated --board qemu-m3``: fixed point against float32 in soft float on the Cortex-M3
    (every strategy, both formats), the Cortex-M7's fixed/float32 beside it; ``result``: the host part."""
    from codegen.stages.firmware import M3_CPU_FLAGS

    base = strategies[0]
    m3 = emulated_instructions(model, strategies, log, board=NOFPU_BOARD, cycles=False, dump_selftest=True)
    m7 = emulated_instructions(model, strategies, log, board=EMULATED_BOARD, cycles=False)
    own = model.controller.number_format
    result.update({"board": NOFPU_BOARD, "c_hash_definition": C_HASH_DEFINITION,
                   "m3_cpu_flags": " ".join(M3_CPU_FLAGS), "m3_states": N_BENCH,
                   "m3_selftest_states": BENCH_SELFTEST, "m7_states": N_BENCH})
    rows = [header + f"  {'M3 ' + QUANTISED + ' instr/step':>31s}  {'M3 ' + FLOAT_CONTROLLER + ' soft-float':>31s}"
            f"  {FLOAT_CONTROLLER + '/' + QUANTISED:>18s}  {'self-test':>8s}  {'M7 fixed':>7s}  {'M7 fl32':>7s}"
            f"  {'M7 fx/fl':>6s}",
            f"{'':34s}  {'min / median / max / mean':>31s}  {'min / median / max / mean':>31s}"
            f"  {'median/mean/max':>18s}  {'median':>8s}  {'median':>7s}  {'median':>7s}  {'median':>6s}"]
    for s in strategies:
        entry, line = _host_entry(timing, s, base)
        own_m3 = m3[s].get(own, {})
        entry.update({"m3_states": own_m3.get("bench_states"), **_nofpu_entry(m3[s], m7[s])})
        if own_m3.get("median") is not None and m3[base][own].get("median"):
            entry["ratio_to_conventional"] = entry["m3_ratio_to_conventional"] = \
                own_m3["median"] / m3[base][own]["median"]
        result["strategies"][s] = entry
        rows.append(line + _nofpu_line(m3[s], m7[s]))
    rows.append(f"closed-loop simulation ({model.name}, {base}): {result['sim_periods_per_s']:,.0f} periods/s")
    result["simulator"] = integrators.compare(topology_of(model), model, rounds=repeats, log=log)
    rows += integrators.summary(result["simulator"], model.name)
    rows.append(f"M3 figures: instructions per step on the emulated Cortex-M3 ({NOFPU_BOARD}, QEMU mps2-an385 "
                f"-icount, no FPU), not cycles; float32 compiled {' '.join(M3_CPU_FLAGS)} (libgcc's software "
                f"float), fixed point in integer instructions only; min/median/max/mean over the same {N_BENCH} "
                f"bench states (the recorded trajectory), the self-test column the ratio of the medians over "
                f"{BENCH_SELFTEST} self-test states (guard and random states); every image's self-test bit-exact. "
                f"float32/fixed > 1: fixed point is that many times faster. M7: the same on the emulated "
                f"Cortex-M7 ({EMULATED_BOARD}, FPU), fixed/float32 > 1: float32 is that many times faster.")
    rows.append("C hashes of the measured images (c_hash of the board's target profile): "
                + "; ".join(f"{s} {fmt} {bd} {st['c_hash'][:12]}" for s in strategies
                            for bd, per in ((NOFPU_BOARD, m3[s]), (EMULATED_BOARD, m7[s]))
                            for fmt, st in per.items() if "c_hash" in st))
    _host_footer(result, rows, timing, strategies, repeats)
    return result

#!/usr/bin/env python3
"""Regenerate every figure of the README's "Measured here" section, on this machine, from this checkout.

    .venv/bin/python scripts/readme_figures.py            # run every command (about 20 min on 2 cores)
    .venv/bin/python scripts/readme_figures.py --only verify-spmsm --only bench-spmsm
    .venv/bin/python scripts/readme_figures.py --render   # rewrite the README from docs/figures.json only

Each figure is one command line, shown in the README exactly as run (``mpcgen`` is this checkout's
``python -m codegen.cli``); its JSON output (or printed summary) is reduced to the result text.
``docs/figures.json`` keeps every figure's command, result, raw values and the C hashes they are about,
with the machine (CPU model, cores, load) and the commit the code was at; the README's table between
the ``figures:begin``/``figures:end`` markers is rendered from that file and nothing else
(``tests/test_readme_figures.py`` checks that they agree).  A figure whose command fails is recorded as
failed and the README says so; nothing is carried over from an earlier run.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import resource
import shlex
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
STORE = ROOT / "docs" / "figures.json"
BEGIN, END = "<!-- figures:begin -->", "<!-- figures:end -->"
#: the commit the "before" column of the start-up figures runs (the last one before the start-up work)
BEFORE = "f7cf79c"


class Run:
    """Runs ``mpcgen`` commands of this checkout (or another tree) and keeps their CPU time."""

    def __init__(self, tmp: Path, tree: Path = ROOT) -> None:
        self.tmp, self.tree = tmp, tree

    def mpcgen(self, argv: list[str], json_out: bool = True) -> tuple[str, Any, float]:
        """(stdout, the ``--json`` file's value or None, CPU seconds of the process)."""
        path = self.tmp / f"out{time.monotonic_ns()}.json"
        args = argv + (["--json", str(path)] if json_out else [])
        env = {**os.environ, "PYTHONPATH": str(self.tree)}
        before = _children_cpu_s()
        proc = subprocess.Popen([sys.executable, "-m", "codegen.cli", *args], cwd=self.tree, env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        out, err = proc.communicate()
        cpu = _children_cpu_s() - before
        if proc.returncode != 0:
            raise RuntimeError(f"mpcgen {shlex.join(argv)} exited {proc.returncode}: {err.strip()[-400:]}")
        return out, (json.loads(path.read_text()) if json_out else None), cpu


def _children_cpu_s() -> float:
    """CPU seconds (user + system) of every child reaped so far (a difference around one child is its own)."""
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


@dataclass(frozen=True)
class Figure:
    """One README row: what, the command as shown, and how to measure it (returns result text, data)."""

    key: str
    what: str
    command: str
    measure: Callable[[Run], tuple[str, dict[str, Any]]]


def _argv(command: str) -> list[str]:
    words = shlex.split(command)
    assert words[0] == "mpcgen", command
    return words[1:]


def _k(x: float) -> str:
    """Thousands with spaces (README style): 1 234 567."""
    return f"{x:,.0f}".replace(",", " ")


def _m(x: float) -> str:
    return f"{x / 1e6:.2f} M"


def _rng(values: list[float], fmt: Callable[[float], str]) -> str:
    lo, hi = min(values), max(values)
    return fmt(lo) if fmt(lo) == fmt(hi) else f"{fmt(lo)}-{fmt(hi)}"


# ------------------------------------------------------------------ the figures
def verify(cfg: str, extra: str = "") -> Callable[[Run], tuple[str, dict[str, Any]]]:
    def measure(run: Run) -> tuple[str, dict[str, Any]]:
        _, d, _ = run.mpcgen(_argv(f"mpcgen verify examples/{cfg}.toml --states 1000000 {extra}") + ["-q"])
        ss = d["strategies"]
        bad = {s: v["mismatches"] for s, v in ss.items() if v["mismatches"]}
        rates = {s: v["states_per_s"] for s, v in ss.items()}
        text = (f"{'0 mismatches' if not bad else f'MISMATCHES {bad}'} in {_k(min(v['states'] for v in ss.values()))} "
                f"states per strategy ({len(ss)} strategies); " +
                " / ".join(f"{s} {_m(r)}" for s, r in rates.items()) + " states/s end to end")
        return text, {"states_per_s": rates, "mismatches": {s: v["mismatches"] for s, v in ss.items()},
                      "c_hash": {s: v["c_hash"] for s, v in ss.items()}}
    return measure


def bench_host(cfg: str) -> Callable[[Run], tuple[str, dict[str, Any]]]:
    def measure(run: Run) -> tuple[str, dict[str, Any]]:
        runs = [run.mpcgen(_argv(f"mpcgen bench examples/{cfg}.toml") + ["-q"])[1] for _ in range(2)]
        d = runs[0]
        base = d["baseline"]
        ratios = [{s: v["host_ns_ratio"] for s, v in r["strategies"].items()} for r in runs]
        drift = max(abs(ratios[1][s] / ratios[0][s] - 1) for s in ratios[0])
        sim = d["simulator"]["integrators"]
        text = ("host ns/step relative to " + base + ": " +
                ", ".join(f"{s} {r:.2f}x" for s, r in ratios[0].items() if s != base) +
                f" (a second run right after: largest ratio change {drift:.1%}); simulator alone, side by side: " +
                ", ".join(f"{i} {_k(v['periods_per_s'])} periods/s (current error against DOP853 "
                          f"{v['max_current_error_a']:.1e} A)" for i, v in sim.items()))
        return text, {"ratios": ratios, "ratio_drift": drift, "integrators": sim}
    return measure


def bench_emulated(cfg: str) -> Callable[[Run], tuple[str, dict[str, Any]]]:
    def measure(run: Run) -> tuple[str, dict[str, Any]]:
        _, d, _ = run.mpcgen(_argv(f"mpcgen bench examples/{cfg}.toml --emulated") + ["-q"])
        ss = d["strategies"]
        f32 = {s: v["m7_by_number_format"]["float32"] for s, v in ss.items()}
        fix = {s: v["m7_by_number_format"].get("fixed", {}).get("median") for s, v in ss.items()}
        text = ("float32 instructions (median): " + " / ".join(f"{s} {_k(v['median'])}" for s, v in f32.items()) +
                "; fixed point, the same states: " + " / ".join(f"{_k(v)}" if v else "n/a" for v in fix.values()) +
                "; estimated M7 cycles (float32, median / max): " +
                ", ".join(f"{s} {_k(v['cycles']['median'])} / {_k(v['cycles']['max'])}" for s, v in f32.items()) +
                "; estimate / bound: " + " / ".join(f"{v['cycles']['est_over_bound']:.2f}" for v in f32.values()))
        return text, {"float32": f32, "fixed_median": fix, "states": d.get("m7_states")}
    return measure


def bench_m3(cfg: str) -> Callable[[Run], tuple[str, dict[str, Any]]]:
    def measure(run: Run) -> tuple[str, dict[str, Any]]:
        _, d, _ = run.mpcgen(_argv(f"mpcgen bench examples/{cfg}.toml --emulated --board qemu-m3") + ["-q"])
        ss = d["strategies"]
        text = ("M3 instructions per step (median), fixed point vs float32 in soft float: " + "; ".join(
            f"{s} {_k(v['m3_instructions_per_step_fixed'])} vs {_k(v['m3_instructions_per_step_float32'])} "
            f"({v['m3_float32_over_fixed']:.2f}x)" for s, v in ss.items()) +
            "; the M7's fixed/float32: " + " / ".join(f"{v['m7_fixed_over_float32']:.2f}" for v in ss.values()))
        return text, {s: {k: v[k] for k in v if k.startswith(("m3_", "m7_fixed"))} for s, v in ss.items()}
    return measure


def verify_horizons(cfg: str, horizons: tuple[int, ...]) -> Callable[[Run], tuple[str, dict[str, Any]]]:
    def measure(run: Run) -> tuple[str, dict[str, Any]]:
        per: dict[str, Any] = {}
        for n in horizons:
            _, d, _ = run.mpcgen(_argv(f"mpcgen verify examples/{cfg}.toml --states 1000000 "
                                       f"--set controller.horizon={n}") + ["-q"])
            v = d["strategies"]["mpcc"]
            per[str(n)] = {k: v[k] for k in ("states", "mismatches", "states_per_s", "c_hash")}
        text = "; ".join(f"N = {n}: {_k(v['states'])} states, {v['mismatches']} mismatches, "
                         f"{_k(v['states_per_s'])} states/s" for n, v in per.items())
        return text, per
    return measure


def bench_horizons(cfg: str, horizons: tuple[int, ...]) -> Callable[[Run], tuple[str, dict[str, Any]]]:
    def measure(run: Run) -> tuple[str, dict[str, Any]]:
        per: dict[str, Any] = {}
        for n in horizons:
            _, d, _ = run.mpcgen(_argv(f"mpcgen bench examples/{cfg}.toml --emulated "
                                       f"--set controller.horizon={n}") + ["-q"])
            v = d["strategies"]["mpcc"]["m7_by_number_format"]["float32"]
            per[str(n)] = {"instructions_median": v["median"], "instructions_max": v["max"],
                           "cycles": v.get("cycles", {}), "c_hash": v.get("c_hash")}
        text = "estimated M7 cycles per step (median / max over the bench states): " + "; ".join(
            f"N = {n} {_k(v['cycles'].get('median', float('nan')))} / {_k(v['cycles'].get('max', float('nan')))}"
            for n, v in per.items()) + " (one 50 us period at 480 MHz: 24 000)"
        return text, per
    return measure


def hil(command: str) -> Callable[[Run], tuple[str, dict[str, Any]]]:
    def measure(run: Run) -> tuple[str, dict[str, Any]]:
        _, d, _ = run.mpcgen(_argv(command) + ["-q"])
        text = (f"{_k(d['answered'])} states, {d['mismatches']} mismatches, {d['lost']} lost, "
                f"{d['wire']['resent_states']} resent; {_k(d['states_per_s'])} states/s")
        return text, {k: d[k] for k in ("answered", "mismatches", "lost", "states_per_s", "c_hash", "outputs_sha256")}
    return measure


def monte_carlo(run: Run) -> tuple[str, dict[str, Any]]:
    _, d, _ = run.mpcgen(_argv(FIG_MC) + ["-q"])
    rip = [r["strategies"][s]["T_rip_RMSE_nm"] for r in d["runs"] for s in ("s1", "s2", "s3")]
    faults = sum(r["strategies"][s].get("faults", 0) or 0 for r in d["runs"] for s in r["strategies"])
    mean = sum(rip) / len(rip)
    sd = (sum((x - mean) ** 2 for x in rip) / (len(rip) - 1)) ** 0.5
    text = (f"{len(d['runs'])} runs x {len(d['strategies'])} strategies in {d['timing']['wall_s']:.0f} s on "
            f"{d['timing']['workers']} workers ({d['timing']['runner']}); torque ripple of s1-s3 {mean:.2f} +- "
            f"{sd:.2f} N*m (range {min(rip):.2f}-{max(rip):.2f}), {faults} faulted periods")
    return text, {"wall_s": d["timing"]["wall_s"], "ripple_mean": mean, "ripple_sd": sd, "faults": faults}


def paper(run: Run) -> tuple[str, dict[str, Any]]:
    _, d, _ = run.mpcgen(_argv(FIG_PAPER) + ["-q"])
    ours = {(r["strategy"], r["name"]): r for r in d["paper"]["ratios"]}
    conv = d["strategies"]["conventional"]
    t = [ours[(s, "T_rip vs conventional / %")] for s in ("s1", "s2", "s3")]
    c = [ours[(s, "Cal_ave vs conventional / %")] for s in ("s1", "s2", "s3")]
    text = (f"f_ave of conventional {conv['f_ave_hz'] / 1e3:.2f} kHz; T_rip of s1-s3 "
            f"{_rng([r['ours'] for r in t], lambda x: f'{x:.0f}')} % of conventional vs the paper's "
            f"{_rng([r['published'] for r in t], lambda x: f'{x:.0f}')} %; Cal_ave "
            + "/".join(f"{r['ours']:.0f}" for r in c) + " % vs " + "/".join(f"{r['published']:.0f}" for r in c) + " %")
    return text, {"ratios": d["paper"]["ratios"]}


def tune(run: Run) -> tuple[str, dict[str, Any]]:
    out = run.tmp / "tune"
    run.mpcgen(_argv(FIG_TUNE) + ["-o", str(out), "-q"], json_out=False)
    d = json.loads((out / "tune.json").read_text())
    rec = {s: v["recommended"] for s, v in d["strategies"].items()}
    n = sum(len(v["points"]) for v in d["strategies"].values())
    vals = {s: ("none admissible" if r is None else
                ", ".join(f"{k.rpartition('.')[2]} = {v:g}" for k, v in sorted(r["params"].items())))
            for s, r in rec.items()}
    text = (f"{n} points in {d['timing'].get('wall_s', float('nan')):.0f} s on {d['timing'].get('workers')} "
            "workers; recommended: " + "; ".join(f"{s} {v}" for s, v in vals.items()))
    return text, {"recommended": rec, "points": n, "timing": d["timing"]}


def startup(run: Run) -> tuple[str, dict[str, Any]]:
    """The same three commands in this checkout and in a worktree of BEFORE, CPU seconds each (warm cache)."""
    cmds = {"mpcgen --version": (["--version"], False),
            "verify --states 100000 (s1)": (["verify", "examples/seed001_spmsm.toml", "--strategies", "s1",
                                             "--states", "100000", "-q"], False),
            "simulate, 0.2 s scenario": (["simulate", "examples/seed001_spmsm.toml", "--strategies", "conventional",
                                          "--set", "scenario.duration_s=0.2", "--set", "scenario.speed_ref_rpm=[[0.0, 500.0]]",
                                          "--set", "scenario.load_nm=[[0.0, 10.0]]", "-q"], False)}
    wt = run.tmp / "before"
    subprocess.run(["git", "worktree", "add", "-q", "--detach", str(wt), BEFORE], cwd=ROOT, check=True)
    try:
        res: dict[str, dict[str, float]] = {}
        for name, (argv, js) in cmds.items():
            for label, tree in (("before", wt), ("after", ROOT)):
                r = Run(run.tmp, tree)
                r.mpcgen(argv, js)  # warm the build cache
                res.setdefault(name, {})[label] = min(r.mpcgen(argv, js)[2] for _ in range(3))
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(wt)], cwd=ROOT, check=False)
    text = f"CPU seconds, commit {BEFORE} -> this commit (best of 3, warm cache): " + "; ".join(
        f"`{n}` {v['before']:.2f} -> {v['after']:.2f}" for n, v in res.items())
    return text, {"cpu_s": res, "before_commit": BEFORE}


def mpdtc63_source(run: Run) -> tuple[str, dict[str, Any]]:
    res: dict[str, Any] = {}
    for nf in ("float32", "fixed"):
        out = run.tmp / f"g63{nf}"
        run.mpcgen(["generate", "examples/seed000_tlevel.toml", "--strategy", "mpdtc63", "--number-format", nf,
                    "--target", "stm32h743", "-o", str(out), "-q"], json_out=False)
        src = out / "tlevel_mpc.c"
        before = _children_cpu_s()
        p = subprocess.run(["arm-none-eabi-gcc", "-O2", "-mcpu=cortex-m7", "-mfpu=fpv5-d16", "-mfloat-abi=hard",
                            "-c", str(src), "-I", str(out), "-o", str(out / "x.o")], capture_output=True, text=True)
        cpu = _children_cpu_s() - before
        if p.returncode:
            raise RuntimeError(p.stderr[-300:])
        res[nf] = {"lines": len(src.read_text().splitlines()), "compile_cpu_s": cpu}
    text = (f"{_k(res['float32']['lines'])} lines, {res['float32']['compile_cpu_s']:.2f} s "
            f"(fixed point {_k(res['fixed']['lines'])} lines, {res['fixed']['compile_cpu_s']:.2f} s)")
    return text, res


def placement(run: Run) -> tuple[str, dict[str, Any]]:
    p = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "0", "-p", "no:cacheprovider", "-s",
                        "tests/firmware/test_placement.py"], cwd=ROOT, capture_output=True, text=True)
    passed = re.search(r"(\d+) passed", p.stdout)
    failed = re.search(r"(\d+) failed", p.stdout)
    sizes = [int(m.group(1)) for m in re.finditer(r"mpdtc63 float32 -O0: \.itcm_text (\d+) B", p.stdout)]
    text = (f"{passed.group(1) if passed else 0} links pass, {failed.group(1) if failed else 0} fail"
            + (f"; 63-MPDTC float32 at -O0: {sizes[0] / 1024:.1f} KB of ITCM" if sizes else ""))
    return text, {"passed": int(passed.group(1)) if passed else 0, "failed": int(failed.group(1)) if failed else 0}


FIG_MC = ("mpcgen sweep examples/seed001_ipmsm.toml --monte-carlo 100 --spread plant.rs_ohm=+-20 "
          "--spread plant.ld_h=+-10 --spread plant.lq_h=+-10 --spread plant.psi_f_wb=+-10")
FIG_PAPER = "mpcgen simulate examples/seed001_ipmsm.toml --paper"
FIG_TUNE = "mpcgen tune examples/seed000_tlevel.toml --weight controller.lambda_psi_nm_per_wb --workers 2"
HIL_VIRTUAL = "mpcgen hil examples/seed001_spmsm.toml --set controller.tables=published --states 20000"
HIL_FIXED = ("mpcgen hil examples/seed001_spmsm.toml --set controller.tables=published --number-format fixed "
             "--mode replay --states 20000")
HIL_QEMU = ("mpcgen hil examples/seed001_spmsm.toml --set controller.tables=published --board qemu-m7 "
            "--strategy s1 --states 500")
HIL_QEMU_MPCC = "mpcgen hil examples/mpcc_spmsm.toml --board qemu-m7 --states 500"

FIGURES: tuple[Figure, ...] = (
    Figure("verify-spmsm", "verification, SPMSM, 4 strategies",
           "mpcgen verify examples/seed001_spmsm.toml --states 1000000", verify("seed001_spmsm")),
    Figure("verify-ipmsm", "verification, IPMSM (dq-euler, MTPA), 4 strategies",
           "mpcgen verify examples/seed001_ipmsm.toml --states 1000000", verify("seed001_ipmsm")),
    Figure("verify-tlevel", "verification, T-type 27-/63-MPDTC",
           "mpcgen verify examples/seed000_tlevel.toml --states 1000000", verify("seed000_tlevel")),
    *(Figure(f"verify-fixed-{c}", f"fixed point, verification, {c}",
             f"mpcgen verify examples/{c}.toml --number-format fixed --states 1000000",
             verify(c, "--number-format fixed")) for c in ("seed001_spmsm", "seed001_ipmsm", "seed000_tlevel")),
    Figure("bench-spmsm", "host step cost and simulator, SPMSM (two runs in a row)",
           "mpcgen bench examples/seed001_spmsm.toml", bench_host("seed001_spmsm")),
    Figure("bench-tlevel", "host step cost and simulator, T-type (two runs in a row)",
           "mpcgen bench examples/seed000_tlevel.toml", bench_host("seed000_tlevel")),
    Figure("startup", "start-up, verify and a short simulation against an earlier commit",
           "mpcgen --version; mpcgen verify ... --states 100000; mpcgen simulate ... 0.2 s", startup),
    Figure("emulated-spmsm", "emulated Cortex-M7, SPMSM, per step over the 2 000 bench states",
           "mpcgen bench examples/seed001_spmsm.toml --emulated", bench_emulated("seed001_spmsm")),
    Figure("emulated-tlevel", "emulated Cortex-M7, T-type, per step over the 2 000 bench states",
           "mpcgen bench examples/seed000_tlevel.toml --emulated", bench_emulated("seed000_tlevel")),
    *(Figure(f"bench-m3-{c}", f"Cortex-M3 without FPU (QEMU mps2-an385), {c}",
             f"mpcgen bench examples/{c}.toml --emulated --board qemu-m3", bench_m3(c))
      for c in ("seed001_spmsm", "seed001_ipmsm", "seed000_tlevel")),
    *(Figure(f"verify-{c}", f"long horizon (sphere decoder), verification, {c}",
             f"mpcgen verify examples/{c}.toml --states 1000000 --set controller.horizon=N, N = 1, 2, 3, 5",
             verify_horizons(c, (1, 2, 3, 5))) for c in ("mpcc_spmsm", "mpcc_tlevel")),
    *(Figure(f"emulated-{c}", f"long horizon, emulated Cortex-M7 with the default node budget, {c}",
             f"mpcgen bench examples/{c}.toml --emulated --set controller.horizon=N, N = 1-5",
             bench_horizons(c, (1, 2, 3, 4, 5))) for c in ("mpcc_spmsm", "mpcc_tlevel")),
    Figure("hil-virtual", "serial HIL replay, virtual board", HIL_VIRTUAL, hil(HIL_VIRTUAL)),
    Figure("hil-fixed", "serial HIL replay, fixed point", HIL_FIXED, hil(HIL_FIXED)),
    Figure("hil-qemu", "serial HIL, emulated Cortex-M7 (QEMU's serial input is the limit)", HIL_QEMU, hil(HIL_QEMU)),
    Figure("hil-qemu-mpcc", "serial HIL, emulated Cortex-M7, long horizon N = 3", HIL_QEMU_MPCC, hil(HIL_QEMU_MPCC)),
    Figure("monte-carlo", "Monte Carlo mismatch study on Dask", FIG_MC, monte_carlo),
    Figure("placement", "placement in a CubeIDE project (every strategy, float32 and fixed, -O0 -g3 / -Os / -O2)",
           "pytest tests/firmware/test_placement.py -s", placement),
    Figure("mpdtc63-source", "63-MPDTC source and compile time",
           "wc -l and arm-none-eabi-gcc -O2 -c of the generated tlevel_mpc.c", mpdtc63_source),
    Figure("tune", "weight tuning on Dask", FIG_TUNE, tune),
    Figure("paper", "paper side by side (seed 001 Table 9)", FIG_PAPER, paper),
)


# ------------------------------------------------------------------ machine, store, README
def machine() -> dict[str, Any]:
    model = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cpu": model or platform.processor(), "cores": os.cpu_count(), "system": platform.platform(),
            "python": platform.python_version(), "load_average": list(os.getloadavg())}


def commit() -> dict[str, Any]:
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    changed = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                             capture_output=True, text=True).stdout.split("\n")
    dirty = sorted({ln[3:] for ln in changed if ln.strip()} - {"README.md", "docs/figures.json"})
    return {"head": head, "changed_files": dirty}


def render_block(store: dict[str, Any]) -> str:
    """The README block between the markers, from the store alone."""
    m = store["machine"]
    c = store["commit"]
    lines = [BEGIN,
             f"Measured by `python scripts/readme_figures.py` on {store['date']}: {m['cpu']}, {m['cores']} cores, "
             f"{m['system']}, Python {m['python']}, load average {m['load_average'][0]:.1f} at the start; code at "
             f"commit {c['head'][:12]}" + (f" with changes in {', '.join(c['changed_files'])}" if c["changed_files"]
                                           else "") + ". Raw values and C hashes: `docs/figures.json`.",
             "", "| what | command | result |", "|---|---|---|"]
    for f in store["figures"]:
        result = f["result"] if f["ok"] else f"FAILED: {f['error']}"
        lines.append(f"| {f['what']} | `{f['command']}` | {result.replace('|', '/')} |")
    lines += ["", *_cycle_shares(store), END]
    return "\n".join(lines)


def _cycle_shares(store: dict[str, Any]) -> list[str]:
    """The estimated cycles against the papers' published timings (seed 001 Table 11, 32.4 us per
    conventional step on an STM32H743; seed 000: 63-MPDTC 88.5 % of 27-MPDTC), from the emulated figures."""
    figs = {f["key"]: f for f in store["figures"] if f["ok"]}
    if "emulated-spmsm" not in figs or "emulated-tlevel" not in figs:
        return ["(the emulated figures failed: no comparison with the papers' timings)"]
    two = {s: v["cycles"]["median"] for s, v in figs["emulated-spmsm"]["data"]["float32"].items()}
    three = {s: v["cycles"]["median"] for s, v in figs["emulated-tlevel"]["data"]["float32"].items()}
    conv = two["conventional"]
    return [f"The MPTC paper reports 32.4 us per conventional step on an STM32H743; our estimate is {conv:.0f} "
            f"cycles, about {conv / 400:.2f} us at 400 MHz. Relative to conventional, s1-s3 take " +
            " / ".join(f"{100 * two[s] / conv:.0f}" for s in ("s1", "s2", "s3")) +
            " % of the estimated cycles (median) against the paper's 57.7 / 33.0 / 29.5 % (Table 11); 63-MPDTC "
            f"takes {100 * three['mpdtc63'] / three['mpdtc27']:.0f} % of 27-MPDTC's against the MPDTC paper's 88.5 %."]


def write_readme(store: dict[str, Any]) -> None:
    text = README.read_text()
    start, end = text.index(BEGIN), text.index(END) + len(END)
    README.write_text(text[:start] + render_block(store) + text[end:])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", action="append", metavar="KEY", help="measure only these figures (keeps the others)")
    ap.add_argument("--render", action="store_true", help="rewrite the README from docs/figures.json only")
    ap.add_argument("--list", action="store_true", help="list the figures' keys and commands")
    a = ap.parse_args(argv)
    if a.list:
        for f in FIGURES:
            print(f"{f.key:22s} {f.command}")
        return 0
    if a.render:
        write_readme(json.loads(STORE.read_text()))
        return 0
    unknown = set(a.only or ()) - {f.key for f in FIGURES}
    if unknown:
        print(f"readme_figures: unknown figure(s) {', '.join(sorted(unknown))}; see --list", file=sys.stderr)
        return 2
    old = {f["key"]: f for f in json.loads(STORE.read_text())["figures"]} if a.only and STORE.exists() else {}
    store: dict[str, Any] = {"date": time.strftime("%Y-%m-%d"), "machine": machine(), "commit": commit(), "figures": []}
    with tempfile.TemporaryDirectory(prefix="mpcgen-figures-") as tmp:
        for f in FIGURES:
            if a.only and f.key not in a.only:
                if f.key in old:
                    store["figures"].append(old[f.key])
                continue
            print(f"[{time.strftime('%H:%M:%S')}] {f.key}: {f.command}", file=sys.stderr, flush=True)
            t0 = time.perf_counter()
            entry: dict[str, Any] = {"key": f.key, "what": f.what, "command": f.command}
            try:
                result, data = f.measure(Run(Path(tmp)))
                entry.update(ok=True, result=result, data=data)
            except (RuntimeError, KeyError, OSError, subprocess.CalledProcessError) as exc:
                entry.update(ok=False, error=str(exc).splitlines()[0][:300] if str(exc) else type(exc).__name__)
            entry["wall_s"] = round(time.perf_counter() - t0, 1)
            print(f"    -> {entry.get('result', entry.get('error'))}", file=sys.stderr, flush=True)
            store["figures"].append(entry)
    STORE.write_text(json.dumps(store, indent=1, sort_keys=True) + "\n")
    write_readme(store)
    return 0 if all(f["ok"] for f in store["figures"]) else 1


if __name__ == "__main__":
    sys.exit(main())

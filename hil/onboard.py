"""Mode ``onboard``: the board runs the plant AND the controller at full rate; the host compares statistics.

The scenario is the model's (``mpcgen simulate``'s speed and load profile,
``scenario.duration_s``), sent as one SETPOINTS message: its piecewise-constant
steps as (period index, mechanical speed reference, load torque), at most
:data:`hil.schema.MAX_STEPS`, the number of periods and a decimation factor.
The board (firmware/runtime/onboard.[ch] and the files of the topology's
on-board plant, ``Topology.firmware_plant``, constants in the generated
``gen/plant_config.h``) runs the simulator's own plant core -- dq motor,
RK4 in sub-steps of at most dt_s/:data:`hil.codecgen.ONBOARD_SUBSTEPS`,
the topology's right-hand side, the speed PI -- compiled in float32, on the
ideal plant with the simulator's timing rule (:func:`hil.codecgen.board_model`),
and the controller every period, and streams TELEMETRY frames of decimated
sample-instant values (period index, then the simulator trace's
``omega_m_rad_s``, ``te_nm``, ``torque_ref_nm``, ``ia_a``, ``ib_a``, the
topology's decision field and ``fault``), then RUN_END (periods run, status,
decision changes at full rate, cycle min/max/sum and an 8-bin histogram).

The wire is checked as in the other modes (:func:`run_on_board`): TELEMETRY
frame i carries seq SETPOINTS seq + 1 + i and the samples i*16 ..., so a
frame received twice is dropped and counted (never counted twice) and a
missing one is known by its index.  The run is deterministic, so the
harness asks for missing frames again: the same SETPOINTS with a frame
window of the missing ones (the board runs the scenario again and sends
only those; its RUN_END must equal the first).  A SETPOINTS the board
refuses (ERROR CRC, COBS, LENGTH, ...: a corrupted frame) or never answers
is sent again; at most ``session.retries`` times in all, then the samples
still missing are reported as gaps (sample and period ranges) and the run
is INCOMPLETE.

The host runs ``simulate``'s float64 loop over the same scenario with the
board's plant and computes the same metrics from both (on the same
decimated sample instants): speed tracking RMS error (r/min), torque ripple
RMSE |T_e - T*| (N*m), mean torque (N*m), i_a RMS (A), the mechanical speed
at the end (r/min) and decision changes per second (full rate on both
sides).  A float32 plant integrates differently from the host's float64
one, and a finite-control-set controller amplifies any difference into
another decision sequence after a few periods: the traces are not compared
sample by sample, only these statistics, within :data:`TOLERANCE` (relative
to the host's value, plus an absolute floor).
"""
from __future__ import annotations

import time
from collections import Counter, deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from codegen.model import Model
from codegen.simulator.driver import RPM_TO_RAD_S, scenario_arrays
from codegen.topology import topology_of

from .codecgen import board_model
from .framing import Discarded, Frame, encode_frame
from .messages import (
    SEQ_UNKNOWN,
    ProtocolError,
    RunEnd,
    parse_error,
    parse_run_end,
    parse_telemetry,
    setpoints_payload,
    telemetry_frames,
)
from .progress import Progress
from .schema import MAX_STEPS, SAMPLE_TRACE_FIELDS, TELEMETRY_SAMPLES, Err, Msg
from .session import Session

__all__ = ["TOLERANCE", "profile_steps", "sample_metrics", "compare", "OnboardWire", "BoardRun", "run_on_board",
           "onboard", "summary_line", "wire_text", "gap_text"]

#: metric -> (relative, absolute) tolerance: |board - host| <= relative*|host| + absolute.  Measured over
#: 0.2 s (4 000 periods) of the two-level example (s2, published tables, speed reversal and load step) and
#: 0.1 s of the T-type one (mpdtc27, mpdtc63), float32 and fixed point: the float32 plant (the simulator's
#: plant core in float32) takes other decisions after some hundred periods, yet every statistic stays
#: within 0.4 % of the host's (1.1 %: the 63-MPDTC torque ripple), the final speed within 6.3 r/min of
#: 103 r/min in the middle of a reversal (hence its 5 r/min floor).
TOLERANCE: dict[str, tuple[float, float]] = {
    "speed_rmse_rpm": (0.05, 1.0),
    "speed_end_rpm": (0.05, 5.0),
    "torque_rip_rmse_nm": (0.05, 0.01),
    "te_mean_nm": (0.05, 0.05),
    "ia_rms_a": (0.05, 0.05),
    "changes_per_s": (0.05, 50.0),
}


def profile_steps(speed: np.ndarray, load: np.ndarray) -> list[tuple[int, float, float]]:
    """Piecewise-constant per-period arrays as (period index, speed, load) steps, the first at 0."""
    ks = [0] + [int(k) for k in np.flatnonzero((np.diff(speed) != 0) | (np.diff(load) != 0)) + 1]
    return [(k, float(speed[k]), float(load[k])) for k in ks]


#: the sample-instant arrays the metrics take, by the simulator trace's names (SI units)
METRIC_FIELDS = ("speed_ref_rad_s", "omega_m_rad_s", "te_nm", "torque_ref_nm", "ia_a")


def sample_metrics(t: dict[str, np.ndarray]) -> dict[str, float]:
    """The compared metrics of sample-instant arrays (:data:`METRIC_FIELDS`)."""
    err = (t["speed_ref_rad_s"] - t["omega_m_rad_s"]) / RPM_TO_RAD_S
    tail = max(1, len(err) // 10)
    return {"speed_rmse_rpm": float(np.sqrt(np.mean(err ** 2))),
            "speed_end_rpm": float(np.mean(t["omega_m_rad_s"][-tail:]) / RPM_TO_RAD_S),
            "torque_rip_rmse_nm": float(np.sqrt(np.mean((t["te_nm"] - t["torque_ref_nm"]) ** 2))),
            "te_mean_nm": float(np.mean(t["te_nm"])),
            "ia_rms_a": float(np.sqrt(np.mean(t["ia_a"] ** 2)))}


def compare(board: dict[str, float], host: dict[str, float]) -> dict[str, dict[str, Any]]:
    """Per metric: board, host, difference, allowed difference, within."""
    out = {}
    for name, (rel, ab) in TOLERANCE.items():
        b, h = board[name], host[name]
        allowed = rel * abs(h) + ab
        out[name] = {"board": b, "host": h, "diff": abs(b - h), "allowed": allowed, "ok": bool(abs(b - h) <= allowed)}
    return out


@dataclass
class OnboardWire:
    """What went wrong on the wire during an on-board run (all detected; nothing counted twice)."""

    setpoints_sent: int = 0
    #: harness side: cobs, short, crc, oversize (the frame decoder); layout (a payload not its type's layout);
    #: samples (a TELEMETRY frame whose period indices are not one frame's)
    discarded: Counter[str] = field(default_factory=Counter)
    duplicates: int = 0  # TELEMETRY frames received again from the same SETPOINTS (dropped)
    unexpected: int = 0  # frames answering no SETPOINTS sent (sequence number or frame index of none)
    resets: int = 0  # INFO during the run: the board restarted, the run is lost
    silent: int = 0  # SETPOINTS whose answer stopped for silence_s
    frames_asked_again: int = 0  # TELEMETRY frames asked for again (frame window of a later SETPOINTS)
    rerun_differs: int = 0  # frames or RUN_END of a later SETPOINTS that differ from the first's
    board_errors: Counter[str] = field(default_factory=Counter)  # ERROR messages by name

    def as_dict(self) -> dict[str, Any]:
        return {"setpoints_sent": self.setpoints_sent, "discarded": dict(self.discarded),
                "duplicates": self.duplicates, "unexpected": self.unexpected, "resets": self.resets,
                "silent": self.silent, "frames_asked_again": self.frames_asked_again,
                "rerun_differs": self.rerun_differs, "board_errors": dict(self.board_errors)}


def wire_text(wire: dict[str, Any]) -> str:
    """The wire counters that are not zero, one phrase ("" on a perfect link)."""
    parts = []
    if wire["setpoints_sent"] > 1:
        parts.append(f"SETPOINTS sent {wire['setpoints_sent']}x")
    for key, label in (("duplicates", "duplicate frames dropped"), ("frames_asked_again", "frames asked again"),
                       ("unexpected", "unexpected frames"), ("resets", "board resets"),
                       ("silent", "silences"), ("rerun_differs", "RE-RUN DIFFERS")):
        if wire[key]:
            parts.append(f"{label} {wire[key]}")
    for key, label in (("board_errors", "board errors"), ("discarded", "discarded")):
        if wire[key]:
            parts.append(f"{label} " + ", ".join(f"{k} {v}" for k, v in sorted(wire[key].items())))
    return "wire: " + ", ".join(parts) if parts else ""


@dataclass
class _Attempt:
    """One SETPOINTS sent: its seq, its frame window, what came back."""

    seq: int
    first: int
    count: int
    sent_s: float
    outcome: str = "no answer"
    heard: bool = False  # a TELEMETRY or the RUN_END of this SETPOINTS arrived
    seen: set[int] = field(default_factory=set)  # frame indices received

    def wants(self, idx: int, seq: int) -> bool:
        """Frame ``idx`` with sequence number ``seq`` answers this SETPOINTS."""
        return self.first <= idx < self.first + self.count and (seq - self.seq - 1 - idx) & 0xFFFF == 0

    def as_dict(self) -> dict[str, Any]:
        return {"seq": self.seq, "frame_first": self.first, "frame_count": self.count, "outcome": self.outcome}


@dataclass
class BoardRun:
    """What the board sent for one scenario (:func:`run_on_board`)."""

    samples: np.ndarray  # every sample received once, in period order
    end: RunEnd | None  # the first RUN_END (None: none arrived)
    wire: OnboardWire
    attempts: list[dict[str, Any]]  # each SETPOINTS sent: seq, frame window, outcome
    gaps: list[dict[str, list[int]]]  # samples never received: frames, samples, periods (first, last)
    failure: str | None  # why the run is not complete (None: every sample and the RUN_END received)
    run_s: float | None  # SETPOINTS to RUN_END of the SETPOINTS that gave the RUN_END


def _gaps(missing: list[int], samples: int, decimation: int) -> list[dict[str, list[int]]]:
    """Contiguous runs of missing frame indices as frames, samples and periods (first, last)."""
    out: list[dict[str, list[int]]] = []
    for idx in missing:
        if out and out[-1]["frames"][1] == idx - 1:
            out[-1]["frames"][1] = idx
        else:
            out.append({"frames": [idx, idx]})
    for g in out:
        s0, s1 = g["frames"][0] * TELEMETRY_SAMPLES, min((g["frames"][1] + 1) * TELEMETRY_SAMPLES, samples) - 1
        g["samples"], g["periods"] = [s0, s1], [s0 * decimation, s1 * decimation]
    return out


def gap_text(gaps: list[dict[str, list[int]]]) -> str:
    """The gaps of a run, one phrase."""
    head = ", ".join(f"{g['samples'][0]}-{g['samples'][1]} (periods {g['periods'][0]}-{g['periods'][1]})"
                     for g in gaps[:4])
    return f"gap{'s' if len(gaps) > 1 else ''}: samples {head}" + (f" and {len(gaps) - 4} more" if len(gaps) > 4 else "")


def run_on_board(session: Session, periods: int, decimation: int, steps: list[tuple[int, float, float]], *,
                 silence_s: float, prog: Progress | None = None,
                 log: Callable[[str], None] = lambda _: None) -> BoardRun:
    """Run ``steps`` for ``periods`` periods on the board (SETPOINTS) and gather its TELEMETRY and RUN_END.

    TELEMETRY frame i has seq SETPOINTS seq + 1 + i and holds the samples i*TELEMETRY_SAMPLES ...: a frame
    received again is dropped and counted, never taken twice.  A SETPOINTS the board refuses for a
    transport fault (ERROR CRC, COBS, SHORT, LENGTH, ... before any answer), one never answered (silence
    for ``silence_s``) and the frames missing after the RUN_END (a frame window of the missing ones; the
    run is deterministic) are asked for again, at most ``session.retries`` times; an ERROR SETPOINTS (the
    values invalid) is final.  What is still missing is reported as gaps."""
    schema = session.schema
    link = session.link
    n_samples = -(-periods // decimation)
    n_frames = telemetry_frames(n_samples)
    wire = OnboardWire()
    frames: dict[int, np.ndarray] = {}
    raw: dict[int, bytes] = {}
    attempts: list[_Attempt] = []
    end: RunEnd | None = None
    run_s: float | None = None
    refused: str | None = None
    pending: deque[Frame | Discarded] = deque()
    got = 0

    def expected_frames() -> int:
        return n_frames if end is None else min(n_frames, telemetry_frames(max(0, end.samples)))

    def missing() -> list[int]:
        return [i for i in range(expected_frames()) if i not in frames]

    def take_telemetry(item: Frame, cur: _Attempt) -> None:
        nonlocal got
        try:
            block = parse_telemetry(schema, item.payload)
        except ProtocolError:
            wire.discarded["layout"] += 1
            return
        ks = block["k"].astype(np.int64)
        idx = int(ks[0]) // (decimation * TELEMETRY_SAMPLES)
        if not np.array_equal(ks, (idx * TELEMETRY_SAMPLES + np.arange(len(ks))) * decimation):
            wire.discarded["samples"] += 1
            return
        a = next((a for a in reversed(attempts) if a.wants(idx, item.seq)), None)
        if a is None:
            wire.unexpected += 1
            return
        a.heard = True
        if idx in a.seen:
            wire.duplicates += 1
            return
        a.seen.add(idx)
        if idx in frames:  # asked again (or an earlier SETPOINTS answered late): the same run, the same frame
            if raw[idx] != item.payload:
                wire.rerun_differs += 1
            return
        frames[idx], raw[idx] = block, item.payload
        got += len(block)
        if prog is not None:
            prog.update(got, 0, [])

    def listen(cur: _Attempt) -> None:
        """Frames until ``cur`` is answered with RUN_END, refused or given up (``cur.outcome``)."""
        nonlocal end, run_s, refused
        last = time.perf_counter()
        suspect: float | None = None  # an ERROR of unknown seq came before any answer to cur
        while True:
            if not pending:  # frames decoded but not handled yet stay for the next SETPOINTS
                data = link.read_waiting()
                if not data:
                    link.wait(0.005)
                    data = link.read_waiting()
                pending.extend(session.decoder.feed(data))
            while pending:
                item = pending.popleft()
                if isinstance(item, Discarded):
                    wire.discarded[item.reason] += 1
                    continue
                now = last = time.perf_counter()
                if item.type == Msg.TELEMETRY:
                    take_telemetry(item, cur)
                elif item.type == Msg.RUN_END:
                    a = next((a for a in reversed(attempts) if a.seq == item.seq), None)
                    if a is None:
                        wire.unexpected += 1
                        continue
                    try:
                        r = parse_run_end(schema, item.payload)
                    except ProtocolError:
                        wire.discarded["layout"] += 1
                        continue
                    a.heard, a.outcome = True, "RUN_END"
                    if end is None:
                        end, run_s = r, now - a.sent_s
                    elif (r.periods, r.samples, r.status, r.changes) != (end.periods, end.samples, end.status,
                                                                        end.changes):
                        wire.rerun_differs += 1
                    if a is cur or not missing():
                        return
                elif item.type == Msg.ERROR:
                    try:
                        err = parse_error(schema, item.payload)
                    except ProtocolError:
                        wire.discarded["layout"] += 1
                        continue
                    wire.board_errors[err.name] += 1
                    if cur.heard:
                        continue  # about something else (garbage on the line): the run goes on
                    if err.seq == cur.seq:
                        cur.outcome = f"ERROR {err.name} (detail {err.detail})"
                        if err.code == Err.SETPOINTS:
                            refused = f"the board refused the setpoints: ERROR SETPOINTS, detail {err.detail}"
                        return
                    if err.seq == SEQ_UNKNOWN:
                        suspect, cur.outcome = now, f"ERROR {err.name} (detail {err.detail})"
                elif item.type == Msg.INFO:
                    wire.resets += 1
                    if not session.adopt_info(item.payload):
                        wire.discarded["layout"] += 1
                        continue
                    cur.outcome = "board reset"
                    return
                else:
                    wire.unexpected += 1
            now = time.perf_counter()
            if suspect is not None and not cur.heard and now - suspect > session.timeout_s:
                return  # the board refused this SETPOINTS (its frame failed the CRC, COBS or length check)
            if now - last > silence_s:
                wire.silent += 1
                cur.outcome = f"silent for {silence_s:g} s" + (" after its TELEMETRY" if cur.heard else "")
                return

    first, count = 0, n_frames
    while True:
        seq = session._next_seq(1 + first + count)  # the TELEMETRY frames take seq + 1 + frame index
        cur = _Attempt(seq, first, count, time.perf_counter())
        attempts.append(cur)
        link.write(encode_frame(Msg.SETPOINTS, seq,
                                setpoints_payload(schema, periods, decimation, steps, first, count)))
        wire.setpoints_sent += 1
        listen(cur)
        left = missing()
        if refused is not None or (end is not None and not left) or len(attempts) > max(0, session.retries):
            break
        if left:
            first, count = left[0], left[-1] - left[0] + 1
            if cur.heard:  # the board ran it: these frames were lost on the way
                wire.frames_asked_again += len(left)
        else:
            first, count = 0, 0  # only the RUN_END is missing
        log(f"SETPOINTS {cur.seq}: {cur.outcome}, {len(left)} TELEMETRY frames missing: sent again (frames "
            f"{first}..{first + count - 1})" if count else f"SETPOINTS {cur.seq}: {cur.outcome}: sent again for "
            f"its RUN_END")

    left = missing()
    total = n_samples if end is None else min(n_samples, max(0, end.samples))
    gaps = _gaps(left, total, decimation) if end is not None or frames else []  # no run: no gaps
    failure: str | None = refused
    if failure is None and end is None:
        outcomes = Counter(a.outcome for a in attempts)
        said = ", ".join(f"{o}{f' x{c}' if c > 1 else ''}" for o, c in outcomes.items())
        failure = (f"the board refused the SETPOINTS frame {len(attempts)}x ({said}: it arrived corrupted)"
                   if all(a.outcome.startswith("ERROR") for a in attempts)
                   else f"no RUN_END after {len(attempts)} SETPOINTS ({said})")
    elif failure is None and gaps:
        failure = gap_text(gaps)
    samples = (np.concatenate([frames[i] for i in sorted(frames)]) if frames else schema.sample.zeros(0))
    return BoardRun(samples, end, wire, [a.as_dict() for a in attempts], gaps, failure, run_s)


def onboard(session: Session, model: Model, tables: Any, *, decimation: int = 1, show_progress: bool = True,
            log: Callable[[str], None] = lambda _: None, silence_s: float | None = None) -> dict[str, Any]:
    """Run the model's scenario on the board (plant and controller there); the JSON-ready summary.
    ``silence_s``: seconds without a frame before a SETPOINTS counts as unanswered (default: the larger
    of 5 s and 4 times the session's timeout)."""
    schema = session.schema
    info = session.info if session.info is not None else session.handshake()
    if decimation < 1:
        raise ValueError(f"decimation {decimation}: must be >= 1")
    speed, load = scenario_arrays(model)
    n = len(speed)
    steps = profile_steps(speed, load)
    if len(steps) > MAX_STEPS:
        raise ValueError(f"the scenario has {len(steps)} speed/load steps, SETPOINTS takes at most {MAX_STEPS}")
    n_samples = (n + decimation - 1) // decimation
    prog = Progress(f"hil onboard {model.name}", n_samples, info.cycle_unit, enabled=show_progress)
    t0 = time.perf_counter()
    try:
        run = run_on_board(session, n, decimation, steps, prog=prog, log=log,
                           silence_s=silence_s if silence_s is not None else max(5.0, 4 * session.timeout_s))
    finally:
        prog.close()
    wall = time.perf_counter() - t0
    samples, end = run.samples, run.end
    ks = samples["k"].astype(np.int64)
    complete = (end is not None and end.status == 0 and end.periods == n and run.failure is None
                and run.wire.rerun_differs == 0 and np.array_equal(ks, np.arange(0, n, decimation)))

    # the host's float64 closed loop over the same scenario (mpcgen simulate), at the same sample instants,
    # on the board's model: the ideal plant, its actuation delay by the simulator's rule (a [plant] section
    # is not modelled on the board, so the comparison leaves it out and says so)
    host_model = board_model(model)
    topo = topology_of(host_model)
    ref = topo.closed_loop_trace(host_model, topo.host_library(host_model, tables, with_sim=True))
    idx = np.arange(0, n, decimation)
    host_t = {name: np.asarray(getattr(ref, name))[idx] for name in METRIC_FIELDS}
    dec = np.asarray(getattr(ref, topo.decision_field)).astype(np.int64)
    duration = n * float(model.controller.dt_s)
    host_m = {**sample_metrics(host_t), "changes_per_s": float(np.count_nonzero(np.diff(dec))) / duration}
    board_m: dict[str, float] | None = None
    verdict = None
    if complete and end is not None:
        board_t = {"speed_ref_rad_s": speed[ks],
                   **{f.name: samples[f.name].astype(np.float64) for f in SAMPLE_TRACE_FIELDS}}
        board_m = {**sample_metrics(board_t), "changes_per_s": end.changes / duration}
        verdict = compare(board_m, host_m)
    within = verdict is not None and all(v["ok"] for v in verdict.values())
    cycles: dict[str, Any] = {}
    if end is not None and end.periods > 0:
        cycles = {"cycles_min": end.cycles_min, "cycles_max": end.cycles_max,
                  "cycles_mean": round(end.cycles_sum / end.periods, 1),
                  "cycles_hist": end.hist, "cycles_hist_width": end.hist_width}
    # the rate of the board's run: its periods over the time from the SETPOINTS to its RUN_END (none without)
    rate = (round(end.periods / max(run.run_s, 1e-9), 1)
            if end is not None and run.run_s is not None and end.periods > 0 else None)
    return {
        "mode": "onboard", "config": model.name,
        "strategy": getattr(tables, "strategy", None) or model.controller.strategy,
        "config_hash": schema.config_hash, "schema_hash": schema.schema_hash, "board": info.as_dict(),
        "periods": n, "periods_done": end.periods if end is not None else None,
        "status": end.status if end is not None else None, "decimation": decimation,
        "profile_steps": [{"k": k, "speed_rad_s": w, "load_nm": ld} for k, w, ld in steps],
        "samples": int(len(samples)), "samples_expected": n_samples, "complete": bool(complete),
        "failure": run.failure, "gaps": run.gaps, "setpoints": run.attempts,
        "decision_field": topo.decision_field,
        "delay_periods": host_model.plant.delay_periods(model.controller.delay_compensation),
        "host_plant": ("ideal, the controller's timing (the board's plant); the config's [plant] section is "
                       "not modelled on the board" if model.plant != host_model.plant else "the config's (ideal)"),
        "decision_changes": end.changes if end is not None else None,
        "metrics": board_m, "simulate_metrics": host_m, "tolerance": {k: {"relative": r, "absolute": a}
                                                                      for k, (r, a) in TOLERANCE.items()},
        "comparison": verdict, "within_tolerance": within, "ok": bool(complete and within),
        **cycles, "cycle_unit": info.cycle_unit, "wall_s": round(wall, 3),
        "periods_per_s": rate, "wire": run.wire.as_dict(),
    }


def summary_line(data: dict[str, Any]) -> str:
    """The one-line result of an on-board run (no None, no rate without a run)."""
    wire = wire_text(data["wire"])
    wire = f"  {wire}" if wire else ""
    if data["periods_done"] is None:
        return (f"on-board run of {data['periods']} periods FAILED: {data['failure']}  "
                f"({data['samples']}/{data['samples_expected']} samples received){wire}")
    cmp = data["comparison"] or {}
    parts = "  ".join(f"{k} {v['board']:.4g}/{v['host']:.4g}{'' if v['ok'] else ' OUT'}" for k, v in cmp.items())
    parts = f"  board/host: {parts}" if parts else ""
    if data["within_tolerance"]:
        state = "within tolerance of simulate"
    elif data["complete"]:
        state = "OUTSIDE tolerance"
    else:
        why = f", {data['failure']}" if data["failure"] else ""
        state = f"INCOMPLETE ({data['samples']}/{data['samples_expected']} samples, status {data['status']}{why})"
    cyc = (f"  {data['cycle_unit']} min/mean/max {data['cycles_min']}/{data['cycles_mean']}/{data['cycles_max']}"
           if "cycles_min" in data else "")
    rate = f"  {data['periods_per_s']:,.0f} periods/s" if data["periods_per_s"] is not None else ""
    return f"{data['periods_done']}/{data['periods']} periods on board  {state}{parts}{rate}{cyc}{wire}"

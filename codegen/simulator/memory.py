"""Memory a closed-loop run's trace takes, checked before the run (docs/simulation.md "Limits").

A run records every member of its topology's trace struct
(:func:`codegen.simulator.driver.trace_fields`) for every period, plus the
float64 speed reference and load arrays of the scenario
(:func:`codegen.simulator.driver.scenario_arrays`).  A run whose trace
would exceed :data:`TRACE_LIMIT_BYTES` is refused with one line before
anything is built or run.

:func:`memory_room` says how much a process may still allocate on this
machine (the address-space limit ``RLIMIT_AS`` less what the process maps
already, and the kernel's ``MemAvailable``): ``mpcgen verify`` checks its
estimate against it before anything runs.
"""
from __future__ import annotations

import resource
from pathlib import Path

from codegen.errors import ConfigError
from codegen.model import Model
from codegen.simulator.driver import n_periods, trace_fields
from codegen.simulator.records import SimStruct

__all__ = ["TRACE_LIMIT_BYTES", "bytes_per_period", "trace_bytes", "check_trace_memory", "memory_room", "gb"]

#: Largest trace one run may take (2 GiB).
TRACE_LIMIT_BYTES = 2 * 1024**3
#: scenario arrays per period: speed reference and load torque, float64 each
_SCENARIO_BYTES = 2 * 8


def bytes_per_period(trace: SimStruct) -> int:
    """Bytes one period adds: every trace member (itemsize x values per period) + the scenario arrays."""
    return sum(dtype.itemsize * w for dtype, w in trace_fields(trace).values()) + _SCENARIO_BYTES


def trace_bytes(model: Model, trace: SimStruct) -> int:
    """Estimated trace memory of one run of ``model``'s scenario: periods x bytes per period."""
    return n_periods(model) * bytes_per_period(trace)


def gb(n: float) -> str:
    """Bytes as ``1.23 GB`` (decimal gigabytes, 3 significant digits)."""
    return f"{n / 1e9:.3g} GB"


def _proc_kib(path: str, key: str) -> int | None:
    """A ``key: N kB`` entry of a /proc file, in bytes (None where there is no such file or entry)."""
    try:
        text = Path(path).read_text()
    except OSError:
        return None
    for line in text.splitlines():
        name, _, rest = line.partition(":")
        if name == key and rest.split():
            return int(rest.split()[0]) * 1024
    return None


def memory_room() -> list[tuple[str, int, bool]]:
    """What this process may still allocate: (what limits it, bytes, whether it limits this process's
    address space alone) for the address-space limit (``RLIMIT_AS`` soft limit less the process's
    ``VmSize``; absent when unlimited) and the machine's available memory (``MemAvailable`` of
    /proc/meminfo, shared by every process of a run; absent where there is no /proc)."""
    out = []
    soft, _hard = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY:
        used = _proc_kib("/proc/self/status", "VmSize") or 0
        out.append(("the address-space limit (RLIMIT_AS)", max(0, soft - used), True))
    avail = _proc_kib("/proc/meminfo", "MemAvailable")
    if avail is not None:
        out.append(("the available memory (MemAvailable)", avail, False))
    return out


def check_trace_memory(model: Model, trace: SimStruct, limit_bytes: int = TRACE_LIMIT_BYTES) -> int:
    """Refuse (ConfigError, exit 2) a run whose trace would exceed ``limit_bytes``; return the estimate."""
    need = trace_bytes(model, trace)
    if need > limit_bytes:
        sc, dt = model.scenario, model.controller.dt_s
        raise ConfigError(
            model.source or model.name, "scenario.duration_s", sc.duration_s,
            f"with controller.dt_s = {dt:g} s the run has {n_periods(model)} periods whose trace takes about "
            f"{gb(need)} ({bytes_per_period(trace)} bytes per period), above the limit of {gb(limit_bytes)} "
            "per run: shorten scenario.duration_s or lengthen controller.dt_s")
    return need

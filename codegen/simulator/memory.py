"""Memory a closed-loop run's trace takes, checked before the run (docs/simulation.md "Limits").

A run records every member of its topology's trace struct
(:func:`codegen.simulator.driver.trace_fields`) for every period, plus the
float64 speed reference and load arrays of the scenario
(:func:`codegen.simulator.driver.scenario_arrays`).  A run whose trace
would exceed :data:`TRACE_LIMIT_BYTES` is refused with one line before
anything is built or run.
"""
from __future__ import annotations

from codegen.errors import ConfigError
from codegen.model import Model
from codegen.simulator.driver import n_periods, trace_fields
from codegen.simulator.records import SimStruct

__all__ = ["TRACE_LIMIT_BYTES", "bytes_per_period", "trace_bytes", "check_trace_memory"]

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


def _gb(n: float) -> str:
    return f"{n / 1e9:.3g} GB"


def check_trace_memory(model: Model, trace: SimStruct, limit_bytes: int = TRACE_LIMIT_BYTES) -> int:
    """Refuse (ConfigError, exit 2) a run whose trace would exceed ``limit_bytes``; return the estimate."""
    need = trace_bytes(model, trace)
    if need > limit_bytes:
        sc, dt = model.scenario, model.controller.dt_s
        raise ConfigError(
            model.source or model.name, "scenario.duration_s", sc.duration_s,
            f"with controller.dt_s = {dt:g} s the run has {n_periods(model)} periods whose trace takes about "
            f"{_gb(need)} ({bytes_per_period(trace)} bytes per period), above the limit of {_gb(limit_bytes)} "
            "per run: shorten scenario.duration_s or lengthen controller.dt_s")
    return need

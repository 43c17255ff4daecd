"""The closed-loop simulator of one topology: its records, C sources and generated API header.

A :class:`SimApi` names what a topology's simulator consists of: the
parameter, state and trace structs (:mod:`codegen.simulator.records`), its
C sources, its plant header and its part of the plant core.  At build time
:func:`header_path` renders ``sim_api.h`` from the structs through
``templates/sim/sim_api.h.j2`` into the build cache, so the C structs, the
cffi cdef and the numpy side all derive from the same field lists.

The plant core -- the dq motor, RK4, the inverter non-idealities, the speed
PI, the controller's motor inputs (:data:`CORE_HEADERS`) and each
topology's right-hand side (``SimApi.core``) -- is C written once on
``sim_real_t`` (``csrc/sim_real.h``): the host simulator compiles it in
float64, the firmware's on-board loop (the serial HIL's mode onboard) in
float32 with the topology's ``SimApi.board`` sources; :func:`firmware_files`
gives the firmware build those files.
"""
from __future__ import annotations

import hashlib
import importlib
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from codegen import __version__
from codegen.hostbuild import SimSources, cache_root
from codegen.simulator.records import MOTOR_STATE, SIM_PARAMS, SIM_STATE, SIM_TRACE, SimStruct

CSRC = Path(__file__).resolve().parent / "csrc"
#: The shared plant core, written once on sim_real_t: the real type, the dq model, RK4, the inverter
#: non-idealities, the speed PI and the controller's motor inputs (host float64, on board float32).
CORE_HEADERS: tuple[Path, ...] = (CSRC / "sim_real.h", CSRC / "pmsm_dq.h", CSRC / "pmsm_rk4.h",
                                  CSRC / "sim_inverter.h", CSRC / "speed_pi.h", CSRC / "sim_motor_inputs.h")
#: C sources of the host simulator's float64 entry points (dq model, speed PI), sensors and period
#: steps (host only).
SHARED_SOURCES: tuple[Path, ...] = (CSRC / "pmsm_dq.c", CSRC / "speed_pi.c", CSRC / "sim_sensors.c",
                                    CSRC / "sim_period.c")
#: (sim_exact.h: the exact integrator, float64, host only)
SHARED_HEADERS: tuple[Path, ...] = (*CORE_HEADERS, CSRC / "sim_sensors.h", CSRC / "sim_period.h", CSRC / "sim_exact.h")

#: File name of the generated API header (the same for every topology: sim_period.h includes it).
API_NAME = "sim_api.h"


@dataclass(frozen=True)
class SimApi:
    """One topology's closed-loop simulator: C prefix, structs, sources, plant header."""

    topology: str  # "twolevel" | "ttype"
    params: SimStruct
    state: SimStruct
    trace: SimStruct
    csrc: Path  # the topology's csrc/ directory
    errors: dict[int, str]  # messages of the run's nonzero return codes
    #: the topology's headers of the plant core (in csrc/, written once on sim_real_t)
    core: tuple[str, ...] = ()
    #: the topology's part of the firmware's on-board loop (in csrc/, float32; firmware/runtime/onboard.h)
    board: tuple[str, ...] = ()

    @property
    def prefix(self) -> str:
        """C prefix of the API functions and types (``<topology>_sim``)."""
        return f"{self.topology}_sim"

    @property
    def plant_header(self) -> Path:
        return self.csrc / f"{self.topology}_plant.h"

    @property
    def loop_source(self) -> Path:
        return self.csrc / f"{self.topology}_sim.c"

    @property
    def sources(self) -> tuple[Path, ...]:
        """Every C source of the simulator (shared first)."""
        return (*SHARED_SOURCES, self.csrc / f"{self.topology}_plant.c", self.loop_source)

    @property
    def core_headers(self) -> tuple[Path, ...]:
        """The topology's headers of the plant core."""
        return tuple(self.csrc / name for name in self.core)


def firmware_files(api: SimApi) -> dict[str, str]:
    """File name -> text of the on-board plant of ``api``'s topology: the plant core (shared and the
    topology's, compiled in float32 there) and the topology's on-board sources."""
    paths = (*CORE_HEADERS, *api.core_headers, *(api.csrc / name for name in api.board))
    return {p.name: p.read_text() for p in paths}


def hil_declarations(api: SimApi) -> str:
    """Declarations of the period-by-period entry points (``<topology>_sim.c``), appended to ``sim_api.h``.

    ``<api>_hil_input`` writes the controller input record (``mpc_input_t``)
    of period ``state->common.k``, changing nothing; ``<api>_hil_finish``
    takes that period's decision (``mpc_output_t``), records trace entry ``j``
    (``trace`` may be NULL), integrates the plant and commits the period
    (return codes as ``<api>_run``).  The same code as ``<api>_run``: a run
    through them with the compiled step's decisions equals ``<api>_run`` bit
    for bit.  ``void *``: the records are the generated binding's types.
    """
    a, p, s, t = api.prefix, api.params.ctype, api.state.ctype, api.trace.ctype
    pad = " " * (len(a) + 17)
    return (f"\n/* The closed loop period by period (the serial HIL's closed-loop mode): {a}_hil_input\n"
            f" * writes the input record of period state->common.k, {a}_hil_finish applies its decision. */\n"
            f"int {a}_hil_input(const {p} *p, const {s} *state, double speed_ref_rad_s,\n"
            f"{pad}double load_nm, void *in);\n"
            f"int {a}_hil_finish(const {p} *p, {s} *state, double speed_ref_rad_s,\n"
            f"{pad} double load_nm, const void *out, const {t} *trace, long j);\n")


def render_header(api: SimApi) -> str:
    """The text of ``sim_api.h`` (cdef-ready: no preprocessor lines)."""
    from codegen.render import environment

    return environment().get_template("sim/sim_api.h.j2").render(
        topology=api.topology, api=api.prefix, version=__version__,
        loop_source=f"codegen/topologies/{api.topology}/csrc/{api.loop_source.name}",
        motor_state=MOTOR_STATE, params_common=SIM_PARAMS, state_common=SIM_STATE,
        trace_common=SIM_TRACE, params=api.params, state=api.state, trace=api.trace,
    ) + hil_declarations(api)


def header_path(api: SimApi) -> Path:
    """Render ``sim_api.h`` into the build cache (content-addressed); return its path."""

    text = render_header(api)
    key = hashlib.sha256(text.encode()).hexdigest()[:16]
    path = cache_root() / "sim_api" / f"{api.topology}_{key}" / API_NAME
    if not path.is_file() or path.read_text() != text:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f"{API_NAME}.tmp{os.getpid()}")
        tmp.write_text(text)
        os.replace(tmp, path)  # atomic: parallel builds may race
    return path


def strip_preprocessor(text: str) -> str:
    """``text`` without its preprocessor lines (for ffi.cdef)."""
    return "\n".join(line for line in text.splitlines() if not line.lstrip().startswith("#"))


def cdef(api: SimApi) -> str:
    """cffi cdef of the simulator and its plant: sim_api.h + the plant header's declarations."""
    return render_header(api) + "\n" + strip_preprocessor(api.plant_header.read_text()) + "\n"


def sim_sources(api: SimApi) -> SimSources:
    """The :class:`~codegen.hostbuild.SimSources` of a host build (renders the header)."""

    header = header_path(api)
    headers = (*SHARED_HEADERS, *api.core_headers, api.plant_header, header)
    return SimSources(header, api.sources, headers)


def include_dirs(api: SimApi) -> list[Path]:
    """Include directories of a build of the simulator (shared, topology, generated header)."""
    return sorted({p.parent for p in (*api.sources, *SHARED_HEADERS, header_path(api))})


def simulator_of(module: str) -> Callable[[], SimSources]:
    """The closed-loop simulator's C of the topology module ``module`` (its ``SIM`` API), imported
    late: only builds with the simulator need it."""

    def sources() -> SimSources:
        return sim_sources(importlib.import_module(module).SIM)

    return sources

"""Record the golden controller outputs and simulation metrics (run by hand, once).

The golden files pin the behaviour of every example config and strategy
across refactorings: ``tests/test_golden.py`` recomputes them with the
Python reference and the compiled C and demands equal bits.

    .venv/bin/python tests/golden/record.py

The files in the repository were last recorded when the examples took the
seed papers' plant timing (issue 11), with today's field and key names.

Writes ``controller_<config>.npz`` (per strategy: input and output record
fields, keys ``<strategy>/in/<field>`` and ``<strategy>/out/<field>``) and
``simulate_<config>.json`` (the ``mpcgen simulate`` JSON without wall times).
"""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(ROOT))  # this checkout's codegen, not an installed copy
CONFIGS = ("seed001_spmsm", "seed001_ipmsm", "seed000_tlevel")
N_CLOSED, N_ADV, N_RANDOM = 1000, 1500, 1500
#: keys left out of the comparison: timings, file paths, versions, and the config hash (it changes
#: whenever the config schema gains a field, while the metrics must not)
VOLATILE = ("wall_s", "periods_per_s", "plots", "versions", "config_hash")


def _strip(d: object) -> object:
    if isinstance(d, dict):
        return {k: _strip(v) for k, v in d.items() if k not in VOLATILE}
    if isinstance(d, list):
        return [_strip(v) for v in d]
    return d


def _spaced(x: np.ndarray, n: int) -> np.ndarray:
    idx = np.linspace(0, len(x) - 1, num=min(n, len(x))).round().astype(np.intp)
    return x[idx]


def record_controller(name: str) -> None:
    from codegen.config import family_strategies, load_config
    from codegen.stages.training import with_trained_tables
    from codegen.topology import topology_of

    base = load_config(ROOT / "examples" / f"{name}.toml")
    topo = topology_of(base)
    family = family_strategies(base.inverter.topology, base.controller.strategy)  # the example's own family
    base = with_trained_tables(base, family)  # s2/s3: the tables trained on the example's scenario
    arrays: dict[str, np.ndarray] = {}
    for s in family:
        m = base.with_controller(strategy=s)
        t = topo.derive(m)
        lib = topo.host_library(m, t, with_sim=True)
        x = np.concatenate([_spaced(topo.closed_loop_states(m, lib), N_CLOSED),
                            topo.adversarial_states(m, t, N_ADV)[:N_ADV],
                            topo.random_states(m, t, N_RANDOM, 5)])
        ref, got = topo.step_batch(t, x), lib.step_batch(x)
        assert ref.tobytes() == got.tobytes(), f"{name}/{s}: C and reference differ"
        _store(arrays, s, x, ref)
    np.savez_compressed(HERE / f"controller_{name}.npz", **arrays)


def _store(arrays: dict[str, np.ndarray], strategy: str, x: np.ndarray, out: np.ndarray) -> None:
    for f in x.dtype.names or ():
        arrays[f"{strategy}/in/{f}"] = np.ascontiguousarray(x[f])
    for f in out.dtype.names or ():
        arrays[f"{strategy}/out/{f}"] = np.ascontiguousarray(out[f])


def record_simulate(name: str) -> None:
    out = HERE / f"simulate_{name}.json"
    tmp = HERE / f".tmp_{name}.json"
    subprocess.run([sys.executable, "-m", "codegen.cli", "simulate", str(ROOT / "examples" / f"{name}.toml"),
                    "--json", str(tmp), "-q"], check=True, stdout=subprocess.DEVNULL)
    data = _strip(json.loads(tmp.read_text()))
    tmp.unlink()
    out.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    for cfg in CONFIGS:
        print("recording", cfg, flush=True)
        record_controller(cfg)
        record_simulate(cfg)

"""The s2/s3 switch table a config uses: published, or derived by training.

``tables = "published"``: the seed's s2 table; for s3 the seed's published
row plus rows derived by the rule from the seed's own utilisation Tables 6-8
(utilisation.published_tables).

``tables = "derived"`` (mptc-two-level.md "Deriving switch tables from
utilisation"): the tables trained on the config's own scenario, which the
model carries in ``controller.trained_tables``: read from the file
``controller.tables_file`` names when the config is loaded
(``tables_file.load_into``), or put there by the training stage of the
commands that run the controller on the host.  :func:`tables_for` (the
plugin's ``derive``) only reads them: no compiler, no file, no run.

The training stage (:func:`utilisation_counts`, :func:`export_tables`) runs
the conventional controller closed loop over the config's scenario (the
compiled C step, proven equal to the reference), counts per condition and
sector how often each vector was chosen over the samples with
|dT| > eps_T, and applies the coverage rule (``tables_file``).  Counts are
cached per training configuration in ``MPCGEN_CACHE``.
"""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from codegen.cache import LAYOUT, cache_root, read_json, write_json
from codegen.errors import MISSING, ConfigError
from codegen.kernels.consts import Constants
from codegen.kernels.sector import sector12
from codegen.model import Model
from codegen.topologies.twolevel import tables_file
from codegen.topologies.twolevel.derive import SwitchTable, TwoLevelTables, derive_two_level
from codegen.topologies.twolevel.reference import flux_reference, step_batch
from codegen.topologies.twolevel.tables_file import MIN_CELL_SAMPLES, thin_cells, training_model
from codegen.topologies.twolevel.utilisation import count_utilisation, published_tables

__all__ = ["MIN_CELL_SAMPLES", "thin_cells", "training_model", "utilisation_counts", "derived_tables",
           "export_tables", "switch_table_for", "tables_for"]

Progress = Callable[[float], None]


def utilisation_counts(model: Model, progress: Progress | None = None) -> dict[str, np.ndarray]:
    """Counts (conditions, sectors, 7) for s2 (2 x 6) and s3 (4 x 12) from a training run (refused, as a
    scenario run is, when its trace would not fit in memory)."""
    from codegen.simulator.memory import check_trace_memory
    from codegen.topologies.twolevel.hostbuild import build_host_library
    from codegen.topologies.twolevel.sim import TRACE, controller_inputs, run_closed_loop

    train = training_model(model)
    check_trace_memory(train, TRACE)
    t = derive_two_level(train)
    lib = build_host_library(train, t, with_sim=True)
    trace = run_closed_loop(lib.ffi, lib.lib, train, progress=progress)
    states = controller_inputs(trace, train, t.nf)
    out = step_batch(t, states)
    k = Constants(t.consts)
    ops = t.nf.ops
    d_t = states["torque_ref_nm"] - out["te_est_nm"]
    psir, _ = flux_reference(t, ops, k, states["torque_ref_nm"])
    d_psi = psir - out["psi_est_wb"]
    mask = (np.abs(d_t) > k.EPS_T_NM) & (out["fault"] == 0)
    sec12 = sector12(ops, out["psi_alpha_wb"], out["psi_beta_wb"], k.TAN30, k.TAN60).astype(np.intp)
    vec = out["vector"].astype(np.intp)
    c2 = np.where(d_t > 0, 0, 1)
    c4 = np.where(d_t > 0, 0, 2) + np.where(d_psi > 0, 0, 1)
    return {
        "s2": count_utilisation(sec12 >> 1, c2, vec, mask, 6, 2),
        "s3": count_utilisation(sec12, c4, vec, mask, 12, 4),
    }


def _cache_file(model: Model) -> Path:
    return cache_root() / f"training_{training_model(model).config_hash()}_{LAYOUT}.json"


def trained_counts(model: Model, progress: Progress | None = None) -> dict[str, np.ndarray]:
    """The training run's counts for ``model``: from the cache, else from a run (then cached)."""
    entry = _cache_file(model)
    raw = read_json(entry)  # None: not cached, or damaged (warned, rebuilt)
    if isinstance(raw, dict) and set(raw) == set(tables_file.KINDS):
        return {k: np.array(v, dtype=np.int64) for k, v in raw.items()}
    counts = utilisation_counts(model, progress)
    write_json(entry, {k: v.tolist() for k, v in counts.items()})  # atomic, with its SHA-256
    return counts


def derived_tables(model: Model, progress: Progress | None = None) -> tuple[SwitchTable, SwitchTable, dict[str, np.ndarray]]:
    """(s2 table, s3 table, counts): from the config's tables file, else from the training run (cached)."""
    if model.controller.tables_file is not None:
        _, counts, tables = tables_file.read_tables_file(model)
    else:
        counts = trained_counts(model, progress)
        tables = tables_file.tables_from_counts(model, counts)
    return tables["s2"], tables["s3"], counts


def export_tables(model: Model, path: Path, progress: Progress | None = None) -> dict[str, Any]:
    """Run (or reuse) the training and write the tables artefact to ``path``."""
    train = training_model(model)
    s2, s3, counts = derived_tables(model.with_controller(tables="derived", tables_file=None, trained_tables=None),
                                    progress)
    thin = {k: thin_cells(v) for k, v in counts.items()}
    return tables_file.write_tables_file(path, train, counts, {"s2": s2, "s3": s3}, thin, MIN_CELL_SAMPLES)


def missing_tables(model: Model) -> ConfigError:
    """The error of a model whose strategy needs trained tables it does not carry (the generated code
    never trains: the tables come from a file)."""
    c = model.controller
    if c.tables_file is not None:
        return ConfigError(model.source, tables_file.FIELD, c.tables_file,
                           "the file is not read in (load the config with codegen.config.load_config)")
    return ConfigError(model.source, tables_file.FIELD, MISSING,
                       f"strategy {c.strategy} with controller.tables = 'derived' needs the switch tables trained "
                       f"on the config's scenario: write them with `mpcgen tables {model.source} --derive -o FILE`, "
                       "then set controller.tables_file = FILE (relative to the config's folder; or "
                       "--set controller.tables_file=FILE)")


def switch_table_for(model: Model) -> SwitchTable | None:
    """The table the config's strategy needs (None for conventional and s1): published, or the trained
    tables the model carries (``controller.trained_tables``)."""
    c = model.controller
    if c.strategy not in tables_file.KINDS:
        return None
    if c.tables == "published":
        s2, s3 = published_tables(c.derivation.coverage, c.derivation.max_active)
        return s2 if c.strategy == "s2" else s3
    if c.trained_tables is None:
        raise missing_tables(model)
    return dict(c.trained_tables[1])[c.strategy]


def needs_training(model: Model) -> bool:
    """True when ``model``'s strategy takes trained tables (s2/s3 with ``tables = "derived"``) and the
    model carries none (no ``tables_file`` read in, no training stage run)."""
    c = model.controller
    return c.strategy in tables_file.KINDS and c.tables == "derived" and c.trained_tables is None


def tables_for(model: Model) -> TwoLevelTables:
    """Derive everything the step needs for ``model`` (one call per variant); pure: no compiler, no file,
    no run (the training is a stage of its own)."""
    return derive_two_level(model, switch_table_for(model))

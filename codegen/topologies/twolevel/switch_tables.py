"""The s2/s3 switch table a config uses: published, or derived by training.

``tables = "published"``: the seed's s2 table; for s3 the seed's published
row plus rows derived by the rule from the seed's own utilisation Tables 6-8
(utilisation.published_tables).

``tables = "derived"`` (mptc-two-level.md "Deriving switch tables from
utilisation"): run the conventional controller closed loop over the config's
own scenario (the compiled C step, proven equal to the reference), count per
condition and sector how often each vector was chosen over the samples with
|dT| > eps_T, and apply the coverage rule.  A cell with fewer than
``MIN_CELL_SAMPLES`` active-vector choices is too thin to trust (a well-tuned
conventional controller rarely leaves the eps_T band in some cells; the
IPMSM run is an example) and takes the published-derived cell instead; the
``tables`` command reports which cells did.  Counts are cached per config.
"""
from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np

from codegen.errors import ConfigError
from codegen.kernels.consts import Constants
from codegen.kernels.sector import sector12
from codegen.model import Model, Plant
from codegen.topologies.twolevel import tables_file
from codegen.topologies.twolevel.derive import SwitchTable, TwoLevelTables, derive_two_level
from codegen.topologies.twolevel.reference import flux_reference, step_batch
from codegen.topologies.twolevel.utilisation import count_utilisation, derive_table, published_tables

#: Fewest active-vector choices in a cell for its derived set to be used.
MIN_CELL_SAMPLES = 100


def thin_cells(counts: np.ndarray) -> np.ndarray:
    """Mask (conditions, sectors) of cells with too few active-vector choices."""
    return counts[..., 1:].sum(axis=-1) < MIN_CELL_SAMPLES


def training_model(model: Model) -> Model:
    """The conventional variant whose closed-loop run is the training data (host target, no tables file)."""
    return model.with_controller(strategy="conventional", tables="published", tables_file=None,
                                 number_format="float32", fixed_q=None).replace(
        target="host", plant=Plant())


def utilisation_counts(model: Model, progress: Callable[[float], None] | None = None) -> dict[str, np.ndarray]:
    """Counts (conditions, sectors, 7) for s2 (2 x 6) and s3 (4 x 12) from a training run."""
    from codegen.topologies.twolevel.hostbuild import build_host_library
    from codegen.topologies.twolevel.sim import controller_inputs, run_closed_loop

    train = training_model(model)
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
    from codegen.hostbuild import cache_root

    return cache_root() / f"training_{training_model(model).config_hash()}.json"


def derived_tables(model: Model, progress: Callable[[float], None] | None = None) -> tuple[SwitchTable, SwitchTable, dict[str, np.ndarray]]:
    """(s2 table, s3 table, counts): from the config's tables file, else from the training run (cached)."""
    cache = _cache_file(model)
    if model.controller.tables_file is not None:
        counts, stored = tables_file.read_counts(model, training_model(model))
    elif cache.exists():
        raw = json.loads(cache.read_text())
        counts = {k: np.array(v, dtype=np.int64) for k, v in raw.items()}
    else:
        counts = utilisation_counts(model, progress)
        cache.parent.mkdir(parents=True, exist_ok=True)
        cache.write_text(json.dumps({k: v.tolist() for k, v in counts.items()}))
    d = model.controller.derivation
    pub2, pub3 = published_tables(d.coverage, d.max_active)
    trusted = {k: np.where(thin_cells(v)[..., None], 0, v) for k, v in counts.items()}
    s2 = derive_table(trusted["s2"], d.coverage, d.max_active, fallback=pub2)
    s3 = derive_table(trusted["s3"], d.coverage, d.max_active, fallback=pub3)
    if model.controller.tables_file is not None:
        mine = {"s2": [[list(c) for c in r] for r in s2], "s3": [[list(c) for c in r] for r in s3]}
        if stored != mine:
            raise ConfigError(model.source, tables_file.FIELD, model.controller.tables_file,
                              "its tables do not follow from its counts (edited by hand?); "
                              "re-run `mpcgen tables CONFIG --derive -o FILE`")
    return s2, s3, counts


def export_tables(model: Model, path: Path, progress: Callable[[float], None] | None = None) -> dict:
    """Run (or reuse) the training and write the tables artefact to ``path``."""
    train = training_model(model)
    s2, s3, counts = derived_tables(model.with_controller(tables="derived", tables_file=None), progress)
    thin = {k: thin_cells(v) for k, v in counts.items()}
    return tables_file.write_tables_file(path, train, counts, {"s2": s2, "s3": s3}, thin, MIN_CELL_SAMPLES)


def switch_table_for(model: Model, progress: Callable[[float], None] | None = None) -> SwitchTable | None:
    """The table the config's strategy needs (None for conventional and s1)."""
    c = model.controller
    if c.strategy not in ("s2", "s3"):
        return None
    if c.tables == "published":
        s2, s3 = published_tables(c.derivation.coverage, c.derivation.max_active)
    else:
        s2, s3, _ = derived_tables(model, progress)
    return s2 if c.strategy == "s2" else s3


def tables_for(model: Model, progress: Callable[[float], None] | None = None) -> TwoLevelTables:
    """Derive everything the step needs for ``model`` (one call per variant)."""
    return derive_two_level(model, switch_table_for(model, progress))

"""The trained s2/s3 switch tables as an explicit artefact (``mpcgen tables --derive -o FILE``).

A training run of the conventional controller (the compiled C step in the
compiled closed loop over the config's scenario, ``switch_tables``) counts
how often each vector is chosen per condition and sector; the coverage rule
turns the counts into the s2 and s3 tables (:func:`tables_from_counts`).  A
cell with fewer than ``MIN_CELL_SAMPLES`` active-vector choices is too thin
to trust and takes the published-derived cell instead.

The file keeps the counts, the tables and their provenance (training
scenario, derivation rule, thin cells, the training configuration's hash).
A config naming it (``controller.tables_file``) is read in when the config
is loaded (:func:`load_into`): the file is checked against the config
(another training configuration is refused with both hashes named; tables
that do not follow from their counts are refused) and its tables go into
``Controller.trained_tables``.  Nothing here compiles or simulates.
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np

from codegen import __version__
from codegen.config import resolve_path
from codegen.errors import ConfigError
from codegen.model import Model, Plant
from codegen.outputs import write_atomic
from codegen.topologies.twolevel.derive import SwitchTable
from codegen.topologies.twolevel.utilisation import derive_table, published_tables

__all__ = ["FORMAT", "FIELD", "MIN_CELL_SAMPLES", "KINDS", "thin_cells", "training_model", "training_hash",
           "tables_from_counts", "write_tables_file", "read_tables_file", "load_into"]

FORMAT = "mpcgen-switch-tables/1"
FIELD = "controller.tables_file"
#: Fewest active-vector choices in a cell for its derived set to be used.
MIN_CELL_SAMPLES = 100
#: the trained tables, with the shape of their counts (conditions, sectors, vectors)
KINDS: dict[str, tuple[int, int, int]] = {"s2": (2, 6, 7), "s3": (4, 12, 7)}


def thin_cells(counts: np.ndarray) -> np.ndarray:
    """Mask (conditions, sectors) of cells with too few active-vector choices."""
    return counts[..., 1:].sum(axis=-1) < MIN_CELL_SAMPLES


def training_model(model: Model) -> Model:
    """The conventional variant whose closed-loop run is the training data (host target, no tables file)."""
    return model.with_controller(strategy="conventional", tables="published", tables_file=None,
                                 trained_tables=None, number_format="float32", fixed_q=None).replace(
        target="host", plant=Plant())


def training_hash(train: Model) -> str:
    """Hash of the training configuration the counts belong to."""
    return train.config_hash()


def tables_from_counts(model: Model, counts: dict[str, np.ndarray]) -> dict[str, SwitchTable]:
    """The s2 and s3 tables by the config's coverage rule; thin cells take the published-derived set."""
    d = model.controller.derivation
    published = dict(zip(KINDS, published_tables(d.coverage, d.max_active)))
    return {k: derive_table(np.where(thin_cells(counts[k])[..., None], 0, counts[k]), d.coverage, d.max_active,
                            fallback=published[k]) for k in KINDS}


def _as_lists(table: SwitchTable) -> list[list[list[int]]]:
    return [[list(cell) for cell in row] for row in table]


def write_tables_file(path: Path, train: Model, counts: dict[str, np.ndarray], tables: dict[str, Any],
                      thin: dict[str, np.ndarray], min_cell_samples: int) -> dict[str, Any]:
    """Write the artefact; return what was written."""
    sc, c = train.scenario, train.controller
    data = {
        "format": FORMAT,
        "generator": f"mpcgen {__version__}",
        "training": {
            "config": train.name,
            "training_config_hash": training_hash(train),
            "strategy": c.strategy,
            "scenario": {"duration_s": sc.duration_s, "speed_ref_rpm": sc.speed_ref_rpm, "load_nm": sc.load_nm,
                         "speed_mode": sc.speed_mode},
            "dt_s": c.dt_s,
            "eps_t_nm": c.eps_t_nm,
            "samples_outside_eps": int(counts["s2"].sum()),
        },
        "derivation": {"coverage": c.derivation.coverage, "max_active": c.derivation.max_active,
                       "min_cell_samples": min_cell_samples},
        "counts": {k: v.tolist() for k, v in counts.items()},
        "thin_cells": {k: [[int(a), int(b)] for a, b in np.argwhere(v)] for k, v in thin.items()},
        "tables": {k: _as_lists(t) for k, t in tables.items()},
    }
    write_atomic(path, (json.dumps(data, indent=1) + "\n").encode())
    return data


def read_tables_file(model: Model) -> tuple[str, dict[str, np.ndarray], dict[str, SwitchTable]]:
    """(SHA-256 of the file, counts, tables) of the file ``model`` names; ConfigError if it is not such
    a file, was trained for another configuration, or its tables do not follow from its counts."""
    value = model.controller.tables_file
    if value is None:
        raise ValueError("the model names no tables file (controller.tables_file)")
    path = resolve_path(model.source, value)

    def bad(allowed: str) -> ConfigError:
        return ConfigError(model.source, FIELD, value, allowed)

    try:
        raw = path.read_bytes()
        data = json.loads(raw.decode())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise bad(f"not a switch-table file written by `mpcgen tables --derive` ({exc})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise bad(f"not a switch-table file of format {FORMAT} (write it with `mpcgen tables CONFIG --derive -o FILE`)")
    training = data.get("training")
    want, got = training_hash(training_model(model)), training.get("training_config_hash") if isinstance(training, dict) else None
    if got != want:
        raise bad(f"was derived for training configuration {got}, this config's is {want}: the motor, "
                  "scenario or derivation rule changed; re-run `mpcgen tables CONFIG --derive -o FILE`")
    try:
        counts = {k: np.array(data["counts"][k], dtype=np.int64) for k in KINDS}
        if any(counts[k].shape != shape for k, shape in KINDS.items()):
            raise ValueError("count arrays of the wrong shape")
        if any((v < 0).any() for v in counts.values()):
            raise ValueError("negative counts")
        stored = {k: data["tables"][k] for k in KINDS}
    except (KeyError, TypeError, ValueError) as exc:
        raise bad(f"damaged switch-table file ({exc})") from None
    tables = tables_from_counts(model, counts)
    if stored != {k: _as_lists(t) for k, t in tables.items()}:
        raise bad("its tables do not follow from its counts (edited by hand?); "
                  "re-run `mpcgen tables CONFIG --derive -o FILE`")
    return hashlib.sha256(raw).hexdigest(), counts, tables


def load_into(model: Model) -> Model:
    """``model`` with the trained tables of the file ``controller.tables_file`` names (a path relative to
    the config file's folder, ``model.source``) in ``controller.trained_tables``; ``model`` itself when
    it names none.  Reads and checks the file (:func:`read_tables_file`); no compiler, no run."""
    if model.controller.tables_file is None:
        return model
    digest, _, tables = read_tables_file(model)
    return model.with_controller(trained_tables=(digest, tuple((k, tables[k]) for k in KINDS)))

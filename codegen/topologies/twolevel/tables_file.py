"""The derived s2/s3 switch tables as an explicit artefact (``mpcgen tables --derive -o FILE``).

A training run of the conventional controller (the compiled C step in the
compiled closed loop over the config's scenario) counts how often each
vector is chosen per condition and sector; the coverage rule turns the
counts into the s2 and s3 tables.  The file keeps the counts, the tables and
their provenance (training scenario, derivation rule, thin cells, the
training configuration's hash), so that a config naming it
(``controller.tables_file``) generates without a compiler and without a
training run.  Reading checks the file against the config: another
training configuration is refused with both hashes named.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from codegen import __version__
from codegen.config import resolve_path
from codegen.errors import ConfigError
from codegen.model import Model

FORMAT = "mpcgen-switch-tables/1"
FIELD = "controller.tables_file"


def training_hash(train: Model) -> str:
    """Hash of the training configuration the counts belong to."""
    return train.config_hash()


def write_tables_file(path: Path, train: Model, counts: dict[str, np.ndarray], tables: dict[str, Any],
                      thin: dict[str, np.ndarray], min_cell_samples: int) -> dict:
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
        "tables": {k: [[list(cell) for cell in row] for row in t] for k, t in tables.items()},
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=1) + "\n")
    return data


def read_counts(model: Model, train: Model) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Counts and tables of the file the config names; ConfigError if it does not fit the config."""
    value = model.controller.tables_file
    assert value is not None
    path = resolve_path(model.source, value)

    def bad(allowed: str) -> ConfigError:
        return ConfigError(model.source, FIELD, value, allowed)

    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise bad(f"not a switch-table file written by `mpcgen tables --derive` ({exc})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise bad(f"not a switch-table file of format {FORMAT} (write it with `mpcgen tables --derive -o FILE`)")
    want, got = training_hash(train), data.get("training", {}).get("training_config_hash")
    if got != want:
        raise bad(f"was derived for training configuration {got}, this config's is {want}: the motor, "
                  "scenario or derivation rule changed; re-run `mpcgen tables CONFIG --derive -o FILE`")
    try:
        counts = {k: np.array(data["counts"][k], dtype=np.int64) for k in ("s2", "s3")}
        if counts["s2"].shape != (2, 6, 7) or counts["s3"].shape != (4, 12, 7):
            raise ValueError("count arrays of the wrong shape")
    except (KeyError, TypeError, ValueError) as exc:
        raise bad(f"damaged switch-table file ({exc})") from None
    return counts, data.get("tables", {})


"""``mpcgen hil`` with s2 and derived tables: without a tables file the training stage runs first, and
the board (virtual) runs the trained tables under the trained model's config hash."""
from __future__ import annotations

import json

from hil_support import SPMSM

from codegen.cli import main
from codegen.config import load_config
from codegen.stages.training import with_trained_tables


def test_hil_trains_first_without_a_tables_file(tmp_path, capsys):
    out = tmp_path / "hil.json"
    assert main(["hil", str(SPMSM), "--strategy", "s2", "--states", "300", "--json", str(out)]) == 0
    err = capsys.readouterr().err
    assert "training stage" in err
    data = json.loads(out.read_text())
    assert data["states"] == 300 and data["mismatches"] == 0 and data["lost"] == 0
    trained = with_trained_tables(load_config(SPMSM, {"controller.strategy": "s2"}), ["s2"])
    assert f"config {trained.config_hash()}" in err  # the handshake: the board runs the trained model

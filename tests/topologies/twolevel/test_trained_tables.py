"""Trained s2/s3 tables: ``derive`` is pure, ``load_into`` reads the file into the model, ``generate``
never trains, the host commands run the training stage first."""
from __future__ import annotations

import builtins
import hashlib
import json
import shutil
from pathlib import Path

import pytest

import codegen.hostbuild as hostbuild
from codegen.cli import main
from codegen.config import load_config
from codegen.errors import ConfigError
from codegen.stages.training import lacks_trained_tables, with_trained_tables
from codegen.topologies.twolevel import switch_tables
from codegen.topologies.twolevel.tables_file import load_into
from codegen.topology import topology_of


@pytest.fixture
def tables(spmsm_tables_file) -> tuple[Path, Path]:
    """A copy of the SPMSM example and its trained-tables file (conftest's, one training run)."""
    return spmsm_tables_file


def _with_file(cfg: Path, name: str, strategy: str = "s2", **more: object):
    return load_into(load_config(cfg, {"controller.strategy": strategy, "controller.tables_file": name, **more}))


def _forbid_builds_and_files(monkeypatch) -> None:
    """Any compile, training run or file opened from here on fails the test."""
    def fail(*_a, **_k):
        raise AssertionError("derive compiled, trained or opened a file")

    monkeypatch.setattr(hostbuild, "compiler", fail)
    monkeypatch.setattr(switch_tables, "utilisation_counts", fail)
    monkeypatch.setattr(builtins, "open", fail)
    monkeypatch.setattr(Path, "read_bytes", fail)
    monkeypatch.setattr(Path, "read_text", fail)


def test_load_into_reads_the_file_into_the_model(tables):
    cfg, path = tables
    bare = load_config(cfg, {"controller.strategy": "s2"})
    assert load_into(bare) is bare and bare.controller.trained_tables is None
    m = _with_file(cfg, f"t/{path.name}")
    digest, by_strategy = m.controller.trained_tables
    assert digest == hashlib.sha256(path.read_bytes()).hexdigest()
    data = json.loads(path.read_text())
    assert {k: [[list(c) for c in row] for row in t] for k, t in by_strategy} == data["tables"]
    hash(m)  # frozen and hashable
    # the config hash: a model without trained tables hashes as before (no key at all), one with them by
    # the file's digest only
    assert "trained_tables" not in bare.as_dict()["controller"]
    assert "trained_tables_sha256" not in bare.as_dict()["controller"]
    assert m.as_dict()["controller"]["trained_tables_sha256"] == digest
    assert m.config_hash() != m.with_controller(trained_tables=None).config_hash()


def test_config_hash_follows_the_file_content(tables, tmp_path):
    cfg, path = tables
    a = _with_file(cfg, str(path))
    same = tmp_path / "same.json"
    shutil.copy(path, same)
    b = _with_file(cfg, str(same))
    assert a.controller.trained_tables == b.controller.trained_tables
    data = json.loads(path.read_text())
    data["training"]["config"] = "renamed"  # still valid, another content
    other = tmp_path / "other.json"
    other.write_text(json.dumps(data))
    c = _with_file(cfg, str(other))
    assert c.controller.trained_tables[1] == a.controller.trained_tables[1]
    assert c.controller.trained_tables[0] != a.controller.trained_tables[0]
    assert c.config_hash() != a.with_controller(tables_file=str(other)).config_hash()
    assert c.config_hash() == c.with_controller(trained_tables=(c.controller.trained_tables[0], ())).config_hash()


@pytest.mark.parametrize("edit,message", [
    (lambda d: d["tables"]["s2"][0][0].append(6), "do not follow from its counts"),
    (lambda d: d["counts"]["s3"].pop(), "damaged switch-table file"),
    (lambda d: d.pop("counts"), "damaged switch-table file"),
    (lambda d: d.update(format="other/1"), "not a switch-table file of format"),
])
def test_edited_or_damaged_files_are_refused(tables, tmp_path, edit, message):
    cfg, path = tables
    data = json.loads(path.read_text())
    edit(data)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data))
    with pytest.raises(ConfigError, match=message) as err:
        _with_file(cfg, str(bad))
    assert err.value.field == "controller.tables_file" and err.value.value == str(bad)
    bad.write_text("{ not json")
    with pytest.raises(ConfigError, match="not a switch-table file written by"):
        _with_file(cfg, str(bad))


def test_derive_is_pure(tables, tmp_path, monkeypatch):
    """derive compiles nothing, runs nothing and opens no file: the tables come from the model."""
    cfg, path = tables
    loaded = {s: _with_file(cfg, f"t/{path.name}", s) for s in ("s2", "s3")}
    published = {s: load_config(cfg, {"controller.strategy": s, "controller.tables": "published"}) for s in ("s2", "s3")}
    bare = load_config(cfg, {"controller.strategy": "s3"})
    monkeypatch.setenv("MPCGEN_CACHE", str(tmp_path / "empty-cache"))
    _forbid_builds_and_files(monkeypatch)
    for s, m in loaded.items():
        t = topology_of(m).derive(m)
        assert t.rows == tuple(cell for row in dict(m.controller.trained_tables[1])[s] for cell in row)
    for m in published.values():
        topology_of(m).derive(m)
    with pytest.raises(ConfigError) as err:
        topology_of(bare).derive(bare)
    msg = str(err.value)
    assert err.value.field == "controller.tables_file" and "strategy s3" in msg
    assert f"mpcgen tables {cfg} --derive -o FILE" in msg and "set controller.tables_file" in msg


def test_generate_never_trains(tables, tmp_path, monkeypatch, capsys):
    """`CC=no-such-cc mpcgen generate CONFIG --strategy s2 --target stm32h743`: with the tables file it
    succeeds; without it, exit 2 and one line naming the command that writes the file."""
    cfg, path = tables
    monkeypatch.setenv("CC", "no-such-cc")
    monkeypatch.setenv("MPCGEN_CACHE", str(tmp_path / "empty-cache"))
    args = ["generate", str(cfg), "--strategy", "s2", "--target", "stm32h743", "-q"]
    assert main([*args, "-o", str(tmp_path / "a"), "--set", f"controller.tables_file=t/{path.name}"]) == 0
    assert (tmp_path / "a" / "spmsm_mpc.c").is_file()
    capsys.readouterr()
    assert main([*args, "-o", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert f"mpcgen tables {cfg} --derive -o FILE" in err and "controller.tables_file" in err
    assert not (tmp_path / "empty-cache").exists() or not list((tmp_path / "empty-cache").glob("training_*"))


def test_training_stage_puts_the_file_tables_into_the_model(tables):
    """The training stage's model carries what the file's would: the same tables and the same digest
    (the same artefact); a model that needs no trained tables is returned as it is."""
    cfg, path = tables
    bare = load_config(cfg, {"controller.strategy": "s3"})
    assert lacks_trained_tables(bare) and not lacks_trained_tables(bare.with_controller(strategy="s1"))
    assert with_trained_tables(bare, ["conventional", "s1"]) is bare
    trained = with_trained_tables(bare, ["s1", "s3"])
    assert trained.controller.tables_file is None
    assert trained.controller.trained_tables == _with_file(cfg, f"t/{path.name}", "s3").controller.trained_tables
    assert not lacks_trained_tables(trained)


def test_host_commands_train_first(tables, tmp_path, capsys):
    cfg, _ = tables
    js = tmp_path / "v.json"
    assert main(["verify", str(cfg), "--strategies", "s2", "--states", "300", "--no-closed-loop",
                 "--json", str(js)]) == 0
    err = capsys.readouterr().err
    assert "training stage" in err
    data = json.loads(js.read_text())
    assert data["strategies"]["s2"]["mismatches"] == 0
    bare = load_config(cfg)
    assert data["config_hash"] == with_trained_tables(bare, ["s2"]).config_hash() != bare.config_hash()

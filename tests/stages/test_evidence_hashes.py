"""Evidence names the C it is about: the C hash (``codegen.manifest``) in the manifest ``generate`` writes,
in ``<prefix>_report.md`` and ``<prefix>_quantisation.md`` beside it, in ``verify --json`` and in
``mpcgen report``; and the quantisation report compares constants like with like (issue 26)."""
from __future__ import annotations

import hashlib
import json
import math
import re
from pathlib import Path

import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.manifest import c_hash, c_hash_of, manifest, sources
from codegen.stages.training import with_trained_tables

from conftest import SPMSM, TWO_LEVEL

FIXED_S1 = ("--strategy", "s1", "--number-format", "fixed")


def _folder_c_hash(folder: Path) -> str:
    """The C hash as the docs recompute it from a folder: sha256sum of the .c/.h files sorted by name,
    hashed again."""
    names = sorted((p.name for p in folder.iterdir() if p.suffix in (".c", ".h")), key=str.encode)
    lines = "".join(f"{hashlib.sha256((folder / n).read_bytes()).hexdigest()}  {n}\n" for n in names)
    return hashlib.sha256(lines.encode()).hexdigest()


def _generate(out: Path, target: str, *extra: str) -> dict:
    assert main(["generate", str(SPMSM), "--target", target, "-o", str(out), "-q", *extra]) == 0
    return json.loads((out / "spmsm_manifest.json").read_text())


def test_c_hash_is_sha256sum_of_the_sorted_c_files_hashed_again():
    files = {"b.h": "int b;\n", "a.c": "int a;\n", "notes.md": "# x\n"}
    want = "".join(f"{hashlib.sha256(files[n].encode()).hexdigest()}  {n}\n" for n in ("a.c", "b.h"))
    assert c_hash_of(files) == hashlib.sha256(want.encode()).hexdigest()
    assert c_hash_of({**files, "notes.md": "changed"}) == c_hash_of(files)  # only .c and .h count
    assert c_hash_of({**files, "a.c": "int a; \n"}) != c_hash_of(files)
    assert list(manifest(files)) == ["a.c", "b.h", "notes.md"]
    assert manifest(files)["a.c"] == hashlib.sha256(b"int a;\n").hexdigest()
    with pytest.raises(ValueError):
        c_hash_of({"notes.md": "# x\n"})


def test_manifest_lists_every_file_and_the_c_hash_of_the_folder(tmp_path):
    out = tmp_path / "m7"
    man = _generate(out, "stm32h743", *FIXED_S1)
    written = sorted(p.name for p in out.iterdir() if p.name != "spmsm_manifest.json")
    assert sorted(man["files"]) == written
    for name, h in man["files"].items():
        assert hashlib.sha256((out / name).read_bytes()).hexdigest() == h, name
    assert man["c_hash"] == _folder_c_hash(out)
    m = load_config(SPMSM, {"controller.strategy": "s1", "controller.number_format": "fixed",
                            "target.name": "stm32h743"})
    assert (man["target"], man["strategy"], man["number_format"], man["config_hash"]) == \
        ("stm32h743", "s1", "fixed", m.config_hash())
    assert c_hash(m) == c_hash(m, "stm32h743") == man["c_hash"]  # what the HIL harness calls
    assert c_hash(m, "host") != man["c_hash"]  # another placement, another C
    assert f"C hash: `{man['c_hash']}`" in (out / "spmsm_report.md").read_text()
    quant = (out / "spmsm_quantisation.md").read_text()
    assert f"C hash `{man['c_hash']}`" in quant and f"(hash {m.config_hash()})" in quant
    again = _generate(tmp_path / "again", "stm32h743", *FIXED_S1)  # deterministic, byte for byte
    assert (tmp_path / "again" / "spmsm_manifest.json").read_bytes() == (out / "spmsm_manifest.json").read_bytes()
    assert again == man


def test_every_target_folder_names_its_own_c(tmp_path):
    """``--target all`` analyses once, yet each folder's reports name the C beside them."""
    assert main(["generate", str(SPMSM), "--target", "all", "-o", str(tmp_path), "-q", *FIXED_S1]) == 0
    hashes = {t: json.loads((tmp_path / t / "spmsm_manifest.json").read_text())["c_hash"]
              for t in ("host", "stm32h743", "tms320f28377")}
    assert len(set(hashes.values())) == 3
    for target, h in hashes.items():
        assert h == _folder_c_hash(tmp_path / target)
        for report in ("spmsm_quantisation.md", "spmsm_report.md"):
            text = (tmp_path / target / report).read_text()
            named = set(re.findall(r"[0-9a-f]{64}", text))
            assert h in named and not named & (set(hashes.values()) - {h}), (target, report)
        assert f"target {target}" in (tmp_path / target / "spmsm_quantisation.md").read_text()


@pytest.mark.parametrize("target", ["stm32h743", "host"])
def test_verify_json_names_the_hash_of_the_generated_c(tmp_path, target):
    man = _generate(tmp_path / "c", target, *FIXED_S1)
    js = tmp_path / "v.json"
    assert main(["verify", str(SPMSM), "--number-format", "fixed", "--strategies", "s1", "--states", "3000",
                 "--set", f"target.name={target}", "--json", str(js), "-q"]) == 0
    data = json.loads(js.read_text())
    r = data["strategies"]["s1"]
    assert data["target"] == r["c_hash_target"] == target
    assert r["mismatches"] == 0 and r["c_hash"] == man["c_hash"]
    assert r["compiled_target"] == "host"
    m = load_config(SPMSM, {"controller.strategy": "s1", "controller.number_format": "fixed",
                            "target.name": target})
    assert r["compiled_c_hash"] == c_hash_of(sources(m, "host"))  # the host C of this very config
    assert (r["compiled_c_hash"] == r["c_hash"]) == (target == "host")


def _constant_rows(md: str) -> list[list[str]]:
    """The cells of every row of every constants table in the quantisation markdown."""
    rows, inside = [], False
    for line in md.splitlines():
        if line.startswith("| constant |"):
            inside = True
            continue
        if inside and line.startswith("|---"):
            continue
        if inside and line.startswith("| "):
            rows.append([c.strip() for c in line.strip("|").split("|")])
        else:
            inside = False
    return rows


def test_report_compares_constants_like_with_like(tmp_path, capsys):
    """The observed report: sin/cos constants of the fixed step (N=4) against float32's (N=256) gave
    relative errors of 63 and nan.  Now each constant's error is against the float64 value of its own
    definition, and a constant float32 defines otherwise says so in its row."""
    js = tmp_path / "q.json"
    assert main(["report", str(SPMSM), "--number-format", "fixed", "--json", str(js), "-q"]) == 0
    md = capsys.readouterr().out
    rows = _constant_rows(md)
    assert len(rows) > 20
    for name, *_, rel, definition in rows:
        assert "nan" not in rel.lower() and "n/a" not in rel, name
        assert float(rel) <= 1e-3 or definition.startswith("differs by definition"), (name, rel, definition)
        if definition == "same":  # the same definition in both: only the fixed-point rounding is left
            assert float(rel) <= 1e-3, (name, rel)
    by_name = {r[0]: r for r in rows}
    for name in ("SINCOS_PER_RAD", "SINCOS_STEP_HI", "SIN_S5", "SIN_S7", "COS_C4", "COS_C8"):
        assert "differs by definition: N=4 vs N=256" in by_name[name][-1], name
    assert math.isclose(float(by_name["SINCOS_PER_RAD"][3]), 4 / (2 * math.pi), rel_tol=1e-15)
    assert float(by_name["SINCOS_STEP_HI"][6]) == 0.0
    data = json.loads(js.read_text())
    for s, d in data["strategies"].items():
        for c in d["constants"]:
            assert c["rel_error"] is not None and math.isfinite(c["rel_error"]), (s, c["name"])
        assert f"C hash `{d['c_hash']}`" in md and d["c_hash_target"] == data["target"] == "host"
    # the model analysed: trained s2/s3 tables read in (the config hash, and so every C banner, names them)
    m = with_trained_tables(load_config(SPMSM, {"controller.number_format": "fixed"}), TWO_LEVEL)
    for s in TWO_LEVEL:
        assert data["strategies"][s]["c_hash"] == c_hash(m.with_controller(strategy=s)), s

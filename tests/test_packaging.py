"""The installed package works outside the repository (templates and firmware as package data)."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from conftest import ROOT, SPMSM


@pytest.mark.slow
def test_installed_package_generates_outside_the_repo(tmp_path):
    target = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation",
                        "--target", str(target), str(ROOT)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert (target / "codegen" / "templates" / "twolevel" / "mpc.c.j2").is_file()
    assert (target / "codegen" / "firmware" / "runtime" / "sim2l.c").is_file()
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = {**os.environ, "PYTHONPATH": str(target)}
    code = ("import codegen.resources as r, codegen; print(codegen.__file__); "
            "print(r.templates_dir()); print(r.firmware_dir())")
    out = subprocess.run([sys.executable, "-c", code], cwd=work, env=env, capture_output=True, text=True, check=True).stdout
    assert all(line.startswith(str(target)) for line in out.split()), out
    r = subprocess.run([sys.executable, "-m", "codegen.cli", "generate", str(SPMSM), "--target", "stm32h743",
                        "--strategy", "s3", "--tables", "published", "-o", "out", "-q"],
                       cwd=work, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert (work / "out" / "spmsm_mpc.c").is_file()

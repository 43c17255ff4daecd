"""`mpcgen evidence`: one self-contained HTML page from real (small) runs of verify, simulate, report,
bench and hil, opened in headless Chromium; inputs of another config refused; the markdown subset.

Chromium is required, not optional: scripts/bootstrap.sh installs the Debian package ``chromium``.
"""
from __future__ import annotations

import hashlib
import json
import re
import shutil
import subprocess
import time
from pathlib import Path

import pytest

from codegen.cli import main
from codegen.evidence.markup import markdown_html

from conftest import SPMSM, require_tool

#: a short scenario, so that every run below takes seconds; evidence is given the same overrides
SHORT = ["--set", "scenario.duration_s=0.3", "--set", "scenario.speed_ref_rpm=[[0.0,500.0]]",
         "--set", "scenario.load_nm=[[0.0,10.0]]"]
#: the page's sections, by id
SECTIONS = ("config", "hashes", "manifest", "verify", "hil", "quantisation", "bench", "simulate", "plots")
#: bound of one Chromium run
CHROMIUM_TIMEOUT_S = 120


def _run(*argv: str) -> None:
    assert main([*argv, "-q"]) == 0, argv


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The outputs of real runs on the short scenario (strategies chosen so that the inputs name
    three of the config's hashes: untrained, with trained tables, and the fixed-point twin)."""
    require_tool("qemu-system-arm", "qemu-system-arm")
    require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    d = tmp_path_factory.mktemp("evidence-runs")
    cfg = str(SPMSM)
    out = {k: d / f"{k}.json" for k in ("verify", "simulate", "bench", "hil")}
    out["plots"], out["report"] = d / "plots", d / "quant"
    _run("verify", cfg, *SHORT, "--strategies", "conventional,s2", "--states", "2000", "--json", str(out["verify"]))
    _run("simulate", cfg, *SHORT, "--strategies", "conventional,s1", "--json", str(out["simulate"]),
         "--plots", str(out["plots"]))
    _run("report", cfg, *SHORT, "--strategies", "conventional", "--states", "500", "-o", str(out["report"]))
    _run("bench", cfg, *SHORT, "--strategies", "conventional", "--emulated", "--repeats", "1",
         "--json", str(out["bench"]))
    _run("hil", cfg, *SHORT, "--states", "200", "--json", str(out["hil"]))
    _run("generate", cfg, *SHORT, "-o", str(d / "gen"))
    manifests = sorted((d / "gen").glob("*_manifest.json"))
    assert len(manifests) == 1, "generate writes one <prefix>_manifest.json"
    out["manifest"] = manifests[0]
    return out


def _evidence_args(runs: dict[str, Path], html: Path, *extra: str) -> list[str]:
    return ["evidence", str(SPMSM), *SHORT, "--verify", str(runs["verify"]), "--simulate", str(runs["simulate"]),
            "--plots", str(runs["plots"]), "--report", str(runs["report"]), "--bench", str(runs["bench"]),
            "--hil", str(runs["hil"]), "--manifest", str(runs["manifest"]), "-o", str(html), "-q", *extra]


def _chromium(*args: str, profile: Path) -> subprocess.CompletedProcess[str]:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.fail("chromium not found: scripts/bootstrap.sh installs it (Debian package chromium)")
    profile.mkdir()
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={profile}", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=CHROMIUM_TIMEOUT_S)


def test_page_in_chromium(runs: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    html = tmp_path / "report.html"
    assert main(_evidence_args(runs, html)) == 0
    text = html.read_text()
    # self-contained: nothing fetched from outside the page
    assert not re.search(r"""(src|href)\s*=\s*["'](?!data:|#)""", text)
    assert "<link" not in text and "<script" not in text and "@import" not in text and "url(" not in text
    # every input named with its sha256
    for path in (runs["verify"], runs["simulate"], runs["bench"], runs["hil"], runs["manifest"]):
        assert path.name in text
        assert hashlib.sha256(path.read_bytes()).hexdigest() in text
    assert 'class="bad"' not in text, "a clean run has no red flag"

    t0 = time.monotonic()
    dom = _chromium("--dump-dom", f"file://{html}", profile=tmp_path / "profile-dom")
    assert dom.returncode == 0, dom.stderr[-2000:]
    for sid in SECTIONS:
        m = re.search(rf'<section id="{sid}">(.*?)</section>', dom.stdout, re.S)
        assert m, f"section {sid} missing from the rendered DOM"
        body = m.group(1)
        assert re.search(r"<h2>[^<]+</h2>", body), f"section {sid} has no heading"
        assert "sha256" in body, f"section {sid} names no source"
        if sid != "plots":
            assert re.search(r"<tr><td[^>]*>", body), f"section {sid} has no table row"
    plots = re.search(r'<section id="plots">(.*?)</section>', dom.stdout, re.S)
    assert plots and len(re.findall(r'<img src="data:image/png;base64,', plots.group(1))) == \
        len(list(runs["plots"].glob("*.png")))
    quant = re.search(r'<section id="quantisation">(.*?)</section>', dom.stdout, re.S)
    assert quant and "<th>Q format</th>" in quant.group(1) and '<img src="data:image/png;base64,' in quant.group(1)
    shot = tmp_path / "report.png"
    r = _chromium(f"--screenshot={shot}", "--window-size=1280,4000", f"file://{html}",
                  profile=tmp_path / "profile-shot")
    chromium_s = time.monotonic() - t0
    assert r.returncode == 0, r.stderr[-2000:]
    data = shot.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n") and len(data) > 10_000
    with capsys.disabled():
        print(f"\nevidence: page {len(text) / 1e6:.1f} MB, Chromium dump-dom + screenshot {chromium_s:.1f} s, "
              f"screenshot {shot}")


def test_page_is_deterministic(runs: dict[str, Path], tmp_path: Path) -> None:
    a, b = tmp_path / "a.html", tmp_path / "b.html"
    assert main(_evidence_args(runs, a)) == 0
    assert main(_evidence_args(runs, b)) == 0
    assert a.read_bytes() == b.read_bytes()


def test_inputs_of_another_config_are_refused(runs: dict[str, Path], tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    other = tmp_path / "other.json"
    data = json.loads(runs["verify"].read_text())
    data["config_hash"] = "0123456789abcdef"
    other.write_text(json.dumps(data))
    html = tmp_path / "mixed.html"
    argv = ["evidence", str(SPMSM), *SHORT, "--verify", str(other), "--bench", str(runs["bench"]),
            "-o", str(html), "-q"]
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "0123456789abcdef" in err and "--allow-mixed" in err
    assert not html.exists()
    assert main([*argv, "--allow-mixed"]) == 0
    text = html.read_text()
    assert re.search(r'<td class="bad">0123456789abcdef</td>', text)
    assert re.search(r'<li class="bad"><a href="#hashes">', text)


def test_the_config_without_overrides_refuses_the_short_runs(runs: dict[str, Path], tmp_path: Path,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    assert main(["evidence", str(SPMSM), "--simulate", str(runs["simulate"]), "-o", str(tmp_path / "x.html")]) == 2
    assert "--simulate" in capsys.readouterr().err


@pytest.mark.parametrize(("args", "words"), [
    (["--verify", "missing.json"], "no such file"),
    (["--plots", "missing-folder"], "no such folder"),
    (["--report", "."], "_quantisation.md"),
])
def test_bad_inputs_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str],
                                 words: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    capsys.readouterr()
    assert main(["evidence", str(SPMSM), *args, "-o", "x.html", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and words in err


def test_not_json_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "v.json"
    bad.write_text("[1, 2")
    assert main(["evidence", str(SPMSM), "--verify", str(bad), "-o", str(tmp_path / "x.html"), "-q"]) == 2
    assert "not JSON" in capsys.readouterr().err


def test_page_without_inputs_says_what_is_missing(tmp_path: Path) -> None:
    html = tmp_path / "bare.html"
    assert main(["evidence", str(SPMSM), "-o", str(html), "-q"]) == 0
    text = html.read_text()
    for option in ("--verify", "--simulate", "--plots", "--report", "--bench", "--hil"):
        assert f"<code>{option} " in text, option


def test_markdown_subset() -> None:
    md = ("# Title\n\n- a `code` item\n- **b**\n\nsome\ntext <x>\n\n| a | b \\| c |\n|---|---|\n| 1 | 2 |\n\n"
          "![alt](p.png)\n\n```\nraw <y>\n```\n")
    out = markdown_html(md, lambda src, alt: f"[{alt}:{src}]")
    assert "<h3>Title</h3>" in out
    assert "<li>a <code>code</code> item</li>" in out and "<li><strong>b</strong></li>" in out
    assert "<p>some text &lt;x&gt;</p>" in out
    assert "<th>a</th><th>b | c</th>" in out and "<tr><td>1</td><td>2</td></tr>" in out
    assert "[alt:p.png]" in out and "<pre>raw &lt;y&gt;</pre>" in out

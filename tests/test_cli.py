"""Command line: --help everywhere, bad input -> one clear line and exit code 2; commands registered by
other packages (the entry-point group ``mpcgen.commands``: ``hil``)."""
from __future__ import annotations

import argparse
import subprocess
import sys
from importlib.metadata import EntryPoint

import pytest

from codegen import cli
from codegen.cli import main

from conftest import ROOT, SPMSM

SUBCOMMANDS = ("generate", "verify", "simulate", "tables", "bench", "firmware", "sweep", "report", "hil", "tune")


@pytest.mark.parametrize("sub", SUBCOMMANDS)
def test_help(sub, capsys):
    assert main([sub, "--help"]) == 0
    assert "usage: mpcgen " + sub in capsys.readouterr().out


def test_help_lists_every_command(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for sub in SUBCOMMANDS:
        assert f"\n    {sub} " in out, sub


def test_console_script_is_codegens(tmp_path):
    """The installed ``mpcgen`` is codegen.cli:main; it lists ``hil``, which hil registers as an entry point."""
    from importlib.metadata import entry_points

    (script,) = [e for e in entry_points(group="console_scripts") if e.name == "mpcgen"]
    assert script.value == "codegen.cli:main"
    (hil,) = [e for e in entry_points(group=cli.ENTRY_POINT_GROUP) if e.name == "hil"]
    assert hil.load() in cli.registered_commands()
    r = subprocess.run([sys.executable, "-m", "codegen.cli", "hil", "--help"], capture_output=True, text=True,
                       cwd=tmp_path)
    assert r.returncode == 0 and "usage: mpcgen hil" in r.stdout, r.stderr


def _hello(args: argparse.Namespace) -> int:
    print(f"hello {args.who}")
    return 7


#: a command registered through a (fake) entry point below
HELLO = cli.Command("hello", "say hello", lambda p: p.add_argument("who"), _hello)


def test_registered_commands_come_from_the_entry_point_group(monkeypatch, capsys):
    group = cli.ENTRY_POINT_GROUP
    eps = [EntryPoint("hello", f"{__name__}:HELLO", group),
           EntryPoint("broken", "no_such_module_anywhere:COMMAND", group),
           EntryPoint("generate", f"{__name__}:HELLO", group),  # codegen's name: left out
           EntryPoint("other", f"{__name__}:HELLO", group)]  # a Command of another name: left out
    monkeypatch.setattr(cli, "entry_points", lambda group: [e for e in eps if e.group == group])
    assert cli.registered_commands() == [HELLO]
    err = capsys.readouterr().err
    assert "'broken'" in err and "'generate'" in err and "'other'" in err
    assert main(["hello", "world"]) == 7
    assert capsys.readouterr().out == "hello world\n"
    assert main(["--help"]) == 0 and "say hello" in capsys.readouterr().out
    assert main(["generate", "--help"]) == 0 and "usage: mpcgen generate" in capsys.readouterr().out


def _edit(tmp_path, old: str, new: str, name: str = "bad.toml"):
    text = SPMSM.read_text()
    assert old in text, old
    p = tmp_path / name
    p.write_text(text.replace(old, new, 1))
    return p


BAD = [
    # (old text, new text, field named in the message, value fragment)
    ("rs_ohm = 0.2", "rs_ohm = -0.2", "motor.rs_ohm", "-0.2"),
    ("rs_ohm = 0.2", "", "motor.rs_ohm", "missing"),
    ("rs_ohm = 0.2", 'rs_ohm = "0.2"', "motor.rs_ohm", "'0.2'"),
    ("rs_ohm = 0.2", "rs_ohm = true", "motor.rs_ohm", "True"),
    ("ld_h = 8.5e-3", "ld_h = 9.5e-3", "predictor", "flux-geometry"),
    ("pole_pairs = 4", "pole_pairs = 0", "motor.pole_pairs", "0"),
    ("pole_pairs = 4", "pole_pairs = 4.5", "motor.pole_pairs", "4.5"),
    ("psi_f_wb = 0.175", "psi_f_wb = 0.0", "motor.psi_f_wb", "0.0"),
    ('strategy = "conventional"', 'strategy = "s4"', "controller.strategy", "'s4'"),
    ('strategy = "conventional"', 'strategy = "mpdtc63"', "controller.strategy", "mpdtc63"),
    ('predictor = "flux-geometry"', 'predictor = "rk4"', "controller.predictor", "'rk4'"),
    ('tables = "derived"', 'tables = "magic"', "controller.tables", "'magic'"),
    ("dt_s = 50e-6", "dt_s = 0.5", "controller.dt_s", "0.5"),
    ("psi_ref_wb = 0.3", "psi_ref_wb = -1", "controller.psi_ref_wb", "-1"),
    ("eps_t_nm = 0.6", "eps_t_nm = 20.0", "controller.eps_t_nm", "20.0"),
    ('number_format = "float32"', 'number_format = "q15"', "controller.number_format", "'q15'"),
    ("coverage = 0.90", "coverage = 1.5", "controller.derivation.coverage", "1.5"),
    ("udc_v = 312.0", "udc_v = 100.0", "inverter.udc_min_v", "150.0"),
    ("i_trip_a = 60.0", "i_trip_a = 0", "inverter.i_trip_a", "0"),
    ('topology = "two-level"', 'topology = "t-type"', "controller.predictor", "belongs to inverter.topology = 'two-level'"),
    ("limit_nm = 30.0", "limit_nm = -30.0", "speed_loop.limit_nm", "-30.0"),
    ("duration_s = 4.0", "duration_s = 0", "scenario.duration_s", "0"),
    ("[[0.0, 500.0], [2.0, -500.0]]", "[[0.5, 500.0], [2.0, -500.0]]", "scenario.speed_ref_rpm", "0.5"),
    ("[[0.0, 10.0], [1.0, -10.0], [3.0, 10.0]]", "[[0.0, 10.0], [3.0, -10.0], [1.0, 10.0]]", "scenario.load_nm", "1.0"),
    ('prefix = "spmsm"', 'prefix = "9lives"', "meta.prefix", "'9lives'"),
    ('name = "host"', 'name = "arduino"', "target", "'arduino'"),
    ("j_kgm2 = 0.01", "j_kgm2 = 0.01\nfoo = 1", "motor.foo", "1"),
    ("[speed_loop]", "[speed_lop]", "speed_lop", ""),
]


@pytest.mark.parametrize("old,new,field,value", BAD, ids=[f"{i}-{b[2]}" for i, b in enumerate(BAD)])
def test_bad_config_one_line_exit_2(tmp_path, capsys, old, new, field, value):
    path = _edit(tmp_path, old, new)
    assert main(["generate", str(path), "-o", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert str(path) in err and field in err and value in err, err
    assert "Traceback" not in err


def test_not_toml_and_missing_file(tmp_path, capsys):
    p = tmp_path / "x.toml"
    p.write_text("this is = = not toml\n")
    assert main(["verify", str(p)]) == 2
    assert str(p) in capsys.readouterr().err
    assert main(["tables", str(tmp_path / "nope.toml")]) == 2
    assert "nope.toml" in capsys.readouterr().err


def test_bad_arguments(capsys):
    assert main(["verify", str(SPMSM), "--states", "0"]) == 2
    assert "--states" in capsys.readouterr().err
    assert main(["verify", str(SPMSM), "--strategies", "mpdtc27"]) == 2
    assert "mpdtc27" in capsys.readouterr().err
    assert main(["simulate", str(SPMSM), "--sweep-eps", "a:b"]) == 2


def test_subprocess_has_no_traceback(tmp_path):
    path = _edit(tmp_path, "rs_ohm = 0.2", "rs_ohm = nan")
    r = subprocess.run([sys.executable, "-m", "codegen.cli", "verify", str(path)], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr and "motor.rs_ohm" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_option_abbreviations_are_refused(tmp_path, capsys):
    """``--plot X`` once meant ``--plots X`` (argparse prefix matching) and wrote a folder named X."""
    assert main(["simulate", str(SPMSM), "--plot", str(tmp_path / "abbr.png"), "-q"]) == 2
    assert "unrecognized arguments: --plot" in capsys.readouterr().err
    assert not (tmp_path / "abbr.png").exists()


@pytest.mark.parametrize("text,value", [("1000000", 1_000_000), ("1e6", 1_000_000), ("1_000", 1000), ("2.0e3", 2000)])
def test_counts_are_written_as_the_docs_write_them(text, value):
    from codegen.cliargs import count

    assert count(text) == value


@pytest.mark.parametrize("text", ["1.5e0", "ten", "1e30"])
def test_a_count_that_is_not_whole_is_refused(text):
    import argparse

    from codegen.cliargs import count

    with pytest.raises(argparse.ArgumentTypeError):
        count(text)


def test_start_up_imports_no_numpy_or_templates():
    """``mpcgen --version`` (and the import of the console script) loads neither numpy nor jinja2 nor a
    topology: the heavy modules load when a command runs (issue 30: start-up under 0.1 s)."""
    import subprocess
    import sys

    code = ("import sys; from codegen.cli import main; rc = main(['--version']); "
            "print(sorted(m for m in ('numpy', 'jinja2', 'codegen.topology', 'cffi') if m in sys.modules)); "
            "raise SystemExit(rc)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines() == [f"mpcgen {__import__('codegen').__version__}", "[]"], r.stdout

"""The fixed-point step: verified bit for bit against the integer reference for every strategy,
strict-clean on gcc, arm-none-eabi-gcc and a 16-bit-int type model (the C28x's), free of
undefined behaviour under the sanitizers over the verification states, and refusing configs whose
signals the format cannot hold."""
from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.stages.verify import verify_strategy
from codegen.topology import topology_of

from conftest import (
    EXAMPLES,
    IPMSM,
    SPMSM,
    STRICT_WARN,
    TTYPE,
    TTYPE_STRATEGIES,
    TWO_LEVEL,
    check_target_c,
    require_tool,
)

CASES = ([(SPMSM, s) for s in TWO_LEVEL] + [(IPMSM, s) for s in TWO_LEVEL] + [(TTYPE, s) for s in TTYPE_STRATEGIES])
IDS = [f"{p.stem}-{s}" for p, s in CASES]


def _fixed(path: Path, strategy: str, **extra: object):
    over = {"controller.number_format": "fixed", "controller.strategy": strategy, **extra}
    if path != TTYPE:
        over["controller.tables"] = "published"
    return load_config(path, over)


@pytest.mark.parametrize("path,strategy", CASES, ids=IDS)
def test_fixed_step_is_bit_exact_with_the_integer_reference(path, strategy):
    r = verify_strategy(_fixed(path, strategy), 30_000, log=lambda s: None)
    assert r.states == 30_000 and r.mismatches == 0, r.first_mismatch
    assert r.sources["closed_loop"] > 0 and r.sources["adversarial"] > 0 and r.faulted_states > 0


@pytest.mark.parametrize("path,strategy", [(SPMSM, "s3"), (IPMSM, "conventional"), (TTYPE, "mpdtc27"),
                                           (TTYPE, "mpdtc63")], ids=["spmsm-s3", "ipmsm-conv", "t27", "t63"])
def test_fixed_c_is_strict_clean_on_every_compiler_and_the_16_bit_int_model(tmp_path, path, strategy):
    clang = require_tool("clang", "clang")
    extra = ["--tables", "published"] if path != TTYPE else []
    for target in ("host", "stm32h743", "tms320f28377"):
        out = tmp_path / target
        assert main(["generate", str(path), "--number-format", "fixed", "--strategy", strategy, "--target", target,
                     "-o", str(out), "-q", *extra]) == 0
        src = next(out.glob("*_mpc.c"))
        code = re.sub(r"/\*.*?\*/", "", src.read_text(), flags=re.S)
        assert "float" not in code and "sqrtf" not in code  # no floating point in the fixed step
        check_target_c(out, tmp_path, target, int16_model=True)
    # the C28x type model: 16-bit int (clang's MSP430 target: sizeof(int) == 2)
    probe = subprocess.run([clang, "--target=msp430", "-ffreestanding", "-dM", "-E", "-x", "c", "/dev/null"],
                           capture_output=True, text=True).stdout
    assert "#define __SIZEOF_INT__ 2" in probe


_DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
#include "PREFIX_mpc.h"
int main(int argc, char **argv)
{
    FILE *f = fopen(argv[1], "rb");
    long n;
    PREFIX_input_t *in;
    PREFIX_output_t *out;
    (void)argc;
    fseek(f, 0, SEEK_END);
    n = ftell(f) / (long)sizeof(PREFIX_input_t);
    fseek(f, 0, SEEK_SET);
    in = malloc((size_t)n * sizeof *in);
    out = malloc((size_t)n * sizeof *out);
    if (fread(in, sizeof *in, (size_t)n, f) != (size_t)n) return 3;
    fclose(f);
    PREFIX_step_batch(in, out, (uint32_t)n);
    f = fopen(argv[2], "wb");
    fwrite(out, sizeof *out, (size_t)n, f);
    fclose(f);
    free(in);
    free(out);
    return 0;
}
"""


@pytest.mark.parametrize("path,strategy", [(SPMSM, "s3"), (IPMSM, "conventional"), (TTYPE, "mpdtc27"),
                                           (TTYPE, "mpdtc63")], ids=["spmsm-s3", "ipmsm-conv", "t27", "t63"])
def test_fixed_c_has_no_undefined_behaviour_over_the_verification_states(tmp_path, path, strategy):
    """The generated step under -fsanitize=address,undefined -fno-sanitize-recover=all over closed-loop,
    adversarial (saturation extremes included) and random states: no finding, outputs bit-exact."""
    m = _fixed(path, strategy)
    topo = topology_of(m)
    t = topo.derive(m)
    lib = topo.host_library(m, t, with_sim=True)
    x = np.concatenate([topo.closed_loop_states(m, lib)[:20_000], topo.adversarial_states(m, t, 20_000),
                        topo.random_states(m, t, 20_000, 3)])
    ext = x.copy()[:64]
    for f in topo.input_record.fields:  # every real input at both int32 extremes
        if f.kind == "real":
            ext[f.name][: len(ext) // 2] = np.iinfo(np.int32).max
            ext[f.name][len(ext) // 2:] = np.iinfo(np.int32).min
    x = np.concatenate([x, ext])
    out = tmp_path / "gen"
    assert main(["generate", str(path), "--number-format", "fixed", "--strategy", strategy, "--target", "host",
                 "-o", str(out), "-q", *(["--tables", "published"] if path != TTYPE else [])]) == 0
    drv = tmp_path / "driver.c"
    drv.write_text(_DRIVER.replace("PREFIX", m.prefix))
    exe = tmp_path / "step"
    subprocess.run(["gcc", *STRICT_WARN, "-g", "-fsanitize=address,undefined", "-fno-sanitize-recover=all",
                    f"-I{out}", str(next(out.glob("*_mpc.c"))), str(drv), "-o", str(exe)], check=True)
    inp, outp = tmp_path / "in.bin", tmp_path / "out.bin"
    np.ascontiguousarray(x, lib.records.input.dtype).tofile(inp)
    r = subprocess.run([str(exe), str(inp), str(outp)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0 and "runtime error" not in r.stderr and "Sanitizer" not in r.stderr, r.stderr[-2000:]
    got = np.fromfile(outp, lib.records.output.dtype)
    ref = topo.step_batch(t, x)
    assert len(got) == len(x) and got.tobytes() == ref.tobytes()


#: configs the fixed-point format cannot hold: (overrides, field named, text in the message)
BAD = [
    ({"controller.fixed_q": 24}, "controller.fixed_q", "does not fit Q7.24"),           # udc 540 V > 128
    ({"controller.fixed_q": 16, "inverter.i_trip_a": 60000.0}, "controller.fixed_q", "does not fit Q15.16"),
    ({"controller.fixed_q": 30}, "controller.fixed_q", "does not fit Q1.30"),
    ({"controller.fixed_q": 8}, "controller.fixed_q", "keeps"),                         # dt/L constants vanish
    ({"controller.fixed_q": 20, "inverter.udc_max_v": 3000.0, "inverter.udc_v": 2000.0}, "controller.fixed_q",
     "does not fit Q11.20"),
    ({"controller.eps_t_nm": 1e-9, "controller.strategy": "s1"}, "controller.eps_t_nm", "constant EPS_T_NM"),
]


@pytest.mark.parametrize("over,field,text", BAD, ids=[f"bad{i}" for i in range(len(BAD))])
def test_unrepresentable_configs_are_refused_with_one_line(tmp_path, capsys, over, field, text):
    sets = [a for k, v in over.items() for a in ("--set", f"{k}={v}")]
    rc = main(["generate", str(SPMSM), "--number-format", "fixed", "--tables", "published", "-o",
               str(tmp_path / "o"), "-q", *sets])
    lines = capsys.readouterr().err.strip().splitlines()
    err = "\n".join(line for line in lines if not line.startswith("mpcgen: warning:"))  # load-time warnings
    assert rc == 2 and len(err.splitlines()) == 1, lines
    assert field in err and text in err and "Traceback" not in "\n".join(lines), lines
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def _refuses_fixed(config: Path) -> str | None:
    """The one-line refusal of ``config`` in fixed point (its strategy runs in float32 only), or None."""
    from codegen.errors import ConfigError

    try:
        load_config(config, {"controller.number_format": "fixed"})
    except ConfigError as e:
        return str(e)
    return None


_EXAMPLES = sorted(EXAMPLES.glob("*.toml"))
_FIXED_EXAMPLES = [c for c in _EXAMPLES if _refuses_fixed(c) is None]
_FLOAT_ONLY_EXAMPLES = [c for c in _EXAMPLES if c not in _FIXED_EXAMPLES]


@pytest.mark.parametrize("config", _FLOAT_ONLY_EXAMPLES, ids=lambda p: p.stem)
def test_float_only_examples_refuse_fixed_point(config):
    """An example whose strategy runs in float32 only (the long-horizon family) is refused in fixed point
    by the config, in one line; these are exactly the mpcc examples."""
    err = _refuses_fixed(config)
    assert err is not None and "float32 only" in err and "\n" not in err
    assert config.stem.startswith("mpcc_")


@pytest.mark.slow
@pytest.mark.parametrize("config", _FIXED_EXAMPLES, ids=lambda p: p.stem)
def test_every_example_strategy_verifies_in_fixed_point(tmp_path, config):
    """``mpcgen verify examples/X.toml --number-format fixed --states 200000``: every strategy of every
    example that fixed point supports, 0 mismatches (the 32-bit helpers and the Newton square root against
    the reference)."""
    js = tmp_path / "verify.json"
    assert main(["verify", str(config), "--number-format", "fixed", "--states", "200000", "--json", str(js),
                 "-q"]) == 0
    data = json.loads(js.read_text())
    assert data["strategies"]
    for s, e in data["strategies"].items():
        assert e["states"] == 200_000 and e["mismatches"] == 0, s

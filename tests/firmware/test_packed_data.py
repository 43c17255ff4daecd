"""Embedded test data as packed words: the canonical layout of RecordLayout, decoded by the firmware
runtime bit for bit.

The image embeds every record in its canonical little-endian layout as 32-bit words
(``RecordLayout.words``, printed by ``fwdata.c_words``); the runtime reads each value at the offset
the generated value table gives (``mpc_values_unpack``) and builds the C record from the values
(generated ``mpc_*_from_values``).  A harness program, the project's own sources with its main
replaced, decodes records holding every awkward bit pattern (NaN payloads, signalling NaNs,
-0.0, infinities, subnormals, int32 extremes, 0xFFFF; a float straddling two words in the
T-type input record) and prints their values, which must equal the octets Python packed, on the
host and on the emulated Cortex-M7 and Cortex-M3.
"""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from codegen.records import RecordLayout
from codegen.stages import emulate
from codegen.stages import firmware as firmware
from codegen.stages.fwdata import c_words, layouts

from fw_support import example, needs_qemu

#: bit patterns per value kind: every one decoded unchanged or the test fails
PATTERNS = {
    "MPC_VALUE_F32": (0x7FC00000, 0x7FC00001, 0x7F800001, 0xFFBFFFFF, 0x80000000, 0x7F800000, 0xFF800000,
                      0x00000001, 0x807FFFFF, 0x7F7FFFFF, 0x3F800000, 0x00000000),
    "MPC_VALUE_I32": (0x80000000, 0xFFFFFFFF, 0x7FFFFFFF, 0x00000000, 0x00000001, 0x80000001, 0x12345678),
    "MPC_VALUE_U16": (0xFFFF, 0x8000, 0x0000, 0x0001, 0x7FFF, 0x00FF),
}
#: (example, strategy, number format): both topologies, float32 and fixed point
COMBOS = [("spmsm", "s3", None), ("spmsm", "conventional", "fixed"), ("tlevel", "mpdtc27", None),
          ("tlevel", "mpdtc63", "fixed")]
N_RECORDS = 13


def special_octets(layout: RecordLayout, n: int = N_RECORDS) -> tuple[np.ndarray, np.ndarray]:
    """(n, octets) canonical records whose every value cycles through its kind's PATTERNS, and the
    (n, values) expected values (as the runtime flattens them: float and int32 bits, uint16 value)."""
    size = layout.packed_dtype.itemsize
    octets = np.zeros((n, size), np.uint8)
    values = np.zeros((n, len(layout.values)), np.uint32)
    for k, (v, off) in enumerate(zip(layout.values, layout.value_offsets)):
        width = 2 if v.kind == "MPC_VALUE_U16" else 4
        pats = PATTERNS[v.kind]
        for i in range(n):
            bits = pats[(i + k) % len(pats)]
            values[i, k] = bits
            octets[i, off:off + width] = np.frombuffer(bits.to_bytes(width, "little"), np.uint8)
    return octets, values


@pytest.mark.parametrize("config,strategy,fmt", COMBOS)
def test_words_are_the_canonical_layout(config, strategy, fmt):
    """words() holds pack()'s octets (little-endian, zero-padded to a word), value_offsets locate
    every value there, and c_words prints exactly the words (unsigned constants, leading zeros
    dropped)."""
    m, _ = example(config, strategy, fmt)
    for layout in layouts(m):
        octets, values = special_octets(layout)
        records = layout.unpack(octets.tobytes())
        assert np.array_equal(layout.pack(records), octets)  # every bit survives the record dtype
        words = layout.words(records)
        assert words.dtype == np.uint32 and words.shape == (N_RECORDS, layout.word_count)
        raw = words.astype("<u4").tobytes()
        stride = 4 * layout.word_count
        for i in range(N_RECORDS):
            rec = raw[i * stride:(i + 1) * stride]
            assert rec[:octets.shape[1]] == octets[i].tobytes() and set(rec[octets.shape[1]:]) <= {0}
        text = c_words(words)
        assert [int(t, 0) for t in re.findall(r"(0x[0-9a-f]+|\b0)u,", text)] == words.ravel().tolist()
        assert c_words(words, suffix="ul").replace("ul,", "u,") == text
        assert not re.search(r"0x0", text)  # no leading zeros
        # the offsets cover the record: each value starts where the previous ends
        widths = [2 if v.kind == "MPC_VALUE_U16" else 4 for v in layout.values]
        assert list(layout.value_offsets) == list(np.cumsum([0, *widths[:-1]]))
        assert sum(widths) == layout.packed_dtype.itemsize
        assert values.shape == (N_RECORDS, len(layout.values))


def harness_main(inp: RecordLayout, out: RecordLayout) -> tuple[str, np.ndarray, np.ndarray]:
    """A main.c decoding special input and output records (``mpc_input_decode``/``mpc_output_decode``)
    and printing each decoded record's values; with the values expected."""
    in_oct, in_vals = special_octets(inp)
    out_oct, out_vals = special_octets(out)
    in_words = inp.words(inp.unpack(in_oct.tobytes()))
    out_words = out.words(out.unpack(out_oct.tobytes()))
    text = f"""/* test harness: decode special records, print their values */
#include "console.h"
#include "port.h"
#include "selftest.h"

static const uint32_t in_words[{N_RECORDS}u * MPC_INPUT_WORDS] = {{
{c_words(in_words)}}};
static const uint32_t out_words[{N_RECORDS}u * MPC_OUTPUT_WORDS] = {{
{c_words(out_words)}}};

static void put_values(const char *tag, uint32_t i, const uint32_t *v, uint16_t n)
{{
    uint16_t k;
    console_puts(tag);
    console_kv_u32("i", i);
    for (k = 0u; k < n; ++k) {{
        console_putc((uint16_t)' ');
        console_put_hex32(v[k]);
    }}
    console_eol();
}}

int main(void)
{{
    static mpc_input_t in;
    static mpc_output_t out;
    static uint32_t iv[MPC_INPUT_NVALUES], ov[MPC_OUTPUT_NVALUES];
    uint32_t i;
    port_init();
    for (i = 0u; i < {N_RECORDS}u; ++i) {{
        mpc_input_decode(&in_words[i * MPC_INPUT_WORDS], &in, iv);
        put_values("RAWIN", i, iv, MPC_INPUT_NVALUES);
        mpc_input_values(&in, iv); /* back from the C record */
        put_values("IN", i, iv, MPC_INPUT_NVALUES);
        mpc_output_decode(&out_words[i * MPC_OUTPUT_WORDS], &out, ov);
        put_values("RAWOUT", i, ov, MPC_OUTPUT_NVALUES);
        mpc_output_values(&out, ov);
        put_values("OUT", i, ov, MPC_OUTPUT_NVALUES);
    }}
    console_puts("DONE");
    console_eol();
    port_exit(0u);
    return 0;
}}
"""
    return text, in_vals, out_vals


def _decoded(text: str, tag: str) -> np.ndarray:
    rows = [line.split()[2:] for line in text.splitlines() if line.startswith(f"{tag} ")]
    return np.array([[int(x, 16) for x in r] for r in rows], dtype=np.uint64).astype(np.uint32)


def _check_board(tmp_path: Path, board: str, config: str, strategy: str, fmt: str | None) -> None:
    m, t = example(config, strategy, fmt)
    inp, out = layouts(m)
    firmware.write_firmware_project(m, t, board, tmp_path, 1, n_bench=0)
    main_c, in_vals, out_vals = harness_main(inp, out)
    (tmp_path / "firmware/runtime/main.c").write_text(main_c)
    build = firmware.build_firmware(tmp_path, board)
    if board == "host":
        text = subprocess.run([str(build.image)], capture_output=True, text=True, timeout=60).stdout
    else:
        run = emulate.run_qemu(build.image, timeout_s=120, board=board)
        assert not run.timed_out, run.uart[-500:]
        text = run.uart
    assert "DONE" in text and "FAULT" not in text, text[-2000:]
    for tag, want in (("RAWIN", in_vals), ("IN", in_vals), ("RAWOUT", out_vals), ("OUT", out_vals)):
        got = _decoded(text, tag)
        assert got.shape == want.shape, (tag, got.shape, want.shape)
        bad = np.argwhere(got != want)
        assert bad.size == 0, [(tag, int(i), (inp if "IN" in tag else out).values[int(k)].name,
                                hex(int(got[i, k])), hex(int(want[i, k]))) for i, k in bad[:10]]


@pytest.mark.parametrize("config,strategy,fmt", COMBOS)
def test_runtime_decodes_records_bit_for_bit_on_the_host(tmp_path, config, strategy, fmt):
    _check_board(tmp_path, "host", config, strategy, fmt)


@needs_qemu
@pytest.mark.slow
@pytest.mark.parametrize("board,config,strategy,fmt", [("qemu-m7", "tlevel", "mpdtc27", None),
                                                       ("qemu-m7", "spmsm", "s3", None),
                                                       ("qemu-m3", "tlevel", "mpdtc63", "fixed")])
def test_runtime_decodes_records_bit_for_bit_emulated(tmp_path, board, config, strategy, fmt):
    """The same on the emulated Cortex-M7 (hard float: the float goes through an FPU register) and
    the Cortex-M3 (no FPU)."""
    _check_board(tmp_path, board, config, strategy, fmt)


def test_data_file_is_packed_words(tmp_path):
    """The data file holds uint32 word arrays (no per-value float literals), one initializer
    constant per record word, and the value tables carry the canonical offsets."""
    m, t = example("tlevel", "mpdtc27")
    inp, out = layouts(m)
    n = 50
    firmware.write_firmware_project(m, t, "host", tmp_path, n, n_bench=20)
    data = (tmp_path / "gen/mpc_selftest_data.c").read_text()
    assert "0x1p" not in data and "NAN" not in data and "INFINITY" not in data
    for name, rows, words in (("selftest_states", n, "MPC_INPUT_WORDS"), ("selftest_expected", n, "MPC_OUTPUT_WORDS"),
                              ("bench_states", 20, "MPC_INPUT_WORDS"), ("bench_expected", 20, "MPC_OUTPUT_WORDS")):
        body = re.search(rf"static const uint32_t {name}\[{rows}u \* {words}\] = {{\n(.*?)}};", data, re.S)
        assert body is not None, name
        count = len(re.findall(r"(?:0x[0-9a-f]+|\b0)ul?,", body.group(1)))
        assert count == rows * (inp if "states" in name else out).word_count, name
    header = (tmp_path / "gen/mpc_values.h").read_text()
    assert f"#define MPC_INPUT_WORDS {inp.word_count}u" in header
    assert f"#define MPC_OUTPUT_WORDS {out.word_count}u" in header
    # constants of the board's uint32_t: unsigned int on the host, unsigned long for arm-none-eabi-gcc
    assert re.search(r"\b0x[0-9a-f]+u,", data) and not re.search(r"ul,", data)
    firmware.write_firmware_project(m, t, "qemu-m7", tmp_path / "m7", n, n_bench=0)
    arm = (tmp_path / "m7/gen/mpc_selftest_data.c").read_text()
    assert re.search(r"\b0x[0-9a-f]+ul,", arm) and not re.search(r"0x[0-9a-f]+u,", arm)
    values_c = (tmp_path / "gen/mpc_values.c").read_text()
    # the T-type input's float after the uint16 previous vector straddles two words
    assert '{ "t_n_prev_s", MPC_VALUE_F32, 30u }' in values_c
    assert "in->t_n_prev_s = mpc_f32_from_bits(values[" in values_c


def test_float64_records_are_refused():
    """A value the runtime cannot hold (8 octets) is a one-line error, not C that does not compile."""
    from codegen.numfmt import number_format
    from codegen.topology import topology_of

    m, _ = example("spmsm", "s3")
    layout = topology_of(m).input_record.bind(number_format("float64"))
    with pytest.raises(firmware.FirmwareError) as err:
        firmware.value_table(layout)
    assert "MPC_VALUE_F64" in str(err.value) and "\n" not in str(err.value)

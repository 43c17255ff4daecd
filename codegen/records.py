"""Records defined once: every layout of a controller record derives from one field list.

A :class:`Record` is an ordered list of :class:`Field` (name, kind, length,
doc, with the unit in the name).  Bound to a number format
(:meth:`Record.bind`), it gives every layout the product uses:

* ``dtype``: the numpy structured dtype laid out like the C struct (natural
  alignment; cffi checks it against the compiler at build time);
* ``members``: the C struct members (type, name, array length, comment);
* ``packed_dtype`` / :meth:`RecordLayout.pack`: fixed-width little-endian
  bytes with no padding, field order stable: the canonical serialisation
  (CRC digests, firmware test data, the serial wire);
* ``values``: the record flattened into 32-bit values (float bits or
  integers), as the firmware runtime reads it; ``value_offsets``: where each
  value lies in the canonical bytes;
* :meth:`RecordLayout.words`: the canonical bytes of each record as
  little-endian 32-bit words, zero-padded to a whole word (the firmware's
  embedded test data, decoded by the runtime with ``value_offsets``);
* ``layout_hash``: a hash of the whole layout (names, kinds, lengths, C
  types), so two builds from different schemas can tell each other apart.
"""
from __future__ import annotations

import hashlib
import zlib
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from .numfmt import NumberFormat

__all__ = ["REAL", "U16", "F64", "F32", "I32", "I64", "KINDS", "fields", "Field", "Record", "RecordLayout", "CMember", "Value"]

#: a real value, stored as the number format says (float32, fixed point)
REAL = "real"
#: an unsigned 16-bit integer (decisions, indices, counts, fault bits)
U16 = "u16"
#: fixed-width kinds that do not depend on the number format (host simulator records)
F64 = "f64"  # IEEE double
F32 = "f32"  # IEEE single
I32 = "i32"  # signed 32-bit integer
I64 = "i64"  # signed 64-bit integer

#: numpy dtype, C type and C zero literal of every fixed-width kind
_FIXED: dict[str, tuple[np.dtype, str, str]] = {
    U16: (np.dtype(np.uint16), "uint16_t", "0u"),
    F64: (np.dtype(np.float64), "double", "0.0"),
    F32: (np.dtype(np.float32), "float", "0.0f"),
    I32: (np.dtype(np.int32), "int32_t", "0"),
    I64: (np.dtype(np.int64), "int64_t", "0"),
}
#: every kind
KINDS: tuple[str, ...] = (REAL, *_FIXED)


@dataclass(frozen=True)
class Field:
    """One record member: name (with its unit), kind, array length (1 = scalar), meaning."""

    name: str
    kind: str  # REAL | U16 | F64 | F32 | I32 | I64
    length: int
    doc: str
    #: SI unit (``codegen.numfmt.units``) when the name's suffix does not say it
    unit_override: str | None = None

    @property
    def unit(self) -> str:
        """SI unit of the value: the override, else the name's unit suffix (``_a``, ``_v``, ``_nm``,
        ``_wb``, ``_s``, ``_rad``, ``_rad_s``), else dimensionless ``""``.  Fixes a real field's
        fixed-point Q format."""
        if self.unit_override is not None:
            return self.unit_override
        for suffix, unit in _UNIT_SUFFIXES:
            if self.name.endswith(suffix):
                return unit
        return ""


#: unit of a field by its name's suffix (longest first)
_UNIT_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_rad_s", "rad/s"), ("_rad", "rad"), ("_nm", "N*m"), ("_wb", "Wb"), ("_a", "A"), ("_v", "V"), ("_s", "s"),
)


def fields(table: str, units: dict[str, str] | None = None, **lengths: int) -> tuple[Field, ...]:
    """Fields from a text table, one per line: ``name  kind  length  meaning...``.

    ``kind`` is a kind's value (``real``, ``u16``, ``f64``, ...); ``length`` a
    number or the name of a keyword argument (``fields(TABLE, N_SEG=7)``).
    Blank lines are skipped.  ``units``: the SI unit of a field whose name
    has no unit suffix (``Field.unit``).
    """
    out = []
    for line in table.strip().splitlines():
        if not line.strip():
            continue
        name, kind, length, doc = line.split(None, 3)
        if kind not in KINDS:
            raise ValueError(f"field {name}: unknown kind {kind!r}; kinds: {', '.join(KINDS)}")
        out.append(Field(name, kind, lengths[length] if length in lengths else int(length), doc.strip(),
                         (units or {}).get(name)))
    return tuple(out)


@dataclass(frozen=True)
class Record:
    """A named, ordered list of fields; bind it to a number format for its layouts."""

    name: str
    fields: tuple[Field, ...]

    def bind(self, nf: NumberFormat) -> RecordLayout:
        """This record's layouts in number format ``nf``."""
        return RecordLayout(self, nf)

    def field(self, name: str) -> Field:
        """The field called ``name``."""
        for f in self.fields:
            if f.name == name:
                return f
        raise KeyError(name)


@dataclass(frozen=True)
class CMember:
    """One C struct member of a bound record (what templates print)."""

    ctype: str
    name: str
    length: int
    doc: str
    kind: str
    zero: str  # C literal of zero of this type


@dataclass(frozen=True)
class Value:
    """One flattened 32-bit value of a record: its member (``costs[3]``), the firmware runtime's
    value kind and the runtime function that reads it as 32 bits (templates print
    ``values[i] = reader(rec->member);``)."""

    name: str
    kind: str  # MPC_VALUE_F32 | MPC_VALUE_U16 (firmware/runtime/selftest.h)
    reader: str  # mpc_f32_bits | mpc_u16_value (firmware/runtime/mpc_runtime.h)


class RecordLayout:
    """A record bound to a number format: numpy dtypes, C members, bytes, hash."""

    def __init__(self, record: Record, nf: NumberFormat) -> None:
        self.record = record
        self.nf = nf

    @property
    def fields(self) -> tuple[Field, ...]:
        return self.record.fields

    def np_type(self, f: Field) -> np.dtype:
        """numpy scalar dtype of field ``f``."""
        return self.nf.real_dtype if f.kind == REAL else _FIXED[f.kind][0]

    def c_type(self, f: Field) -> str:
        """C type of field ``f``."""
        return self.nf.c_type if f.kind == REAL else _FIXED[f.kind][1]

    @cached_property
    def dtype(self) -> np.dtype:
        """numpy structured dtype laid out like the C struct (natural alignment)."""
        spec = [(f.name, self.np_type(f), (f.length,)) if f.length > 1 else (f.name, self.np_type(f))
                for f in self.fields]
        return np.dtype(spec, align=True)

    @cached_property
    def packed_dtype(self) -> np.dtype:
        """Little-endian, unpadded dtype: the canonical byte layout."""
        spec = [(f.name, self.np_type(f).newbyteorder("<"), (f.length,)) if f.length > 1
                else (f.name, self.np_type(f).newbyteorder("<")) for f in self.fields]
        return np.dtype(spec)

    @cached_property
    def members(self) -> tuple[CMember, ...]:
        """C struct members in field order."""
        return tuple(CMember(self.c_type(f), f.name, f.length, f.doc, f.kind,
                             self.nf.literal(self.nf.const(0.0)) if f.kind == REAL else _FIXED[f.kind][2])
                     for f in self.fields)

    @cached_property
    def values(self) -> tuple[Value, ...]:
        """The record flattened into 32-bit values, array fields element by element."""
        out: list[Value] = []
        for f in self.fields:
            for s in ([f"[{j}]" for j in range(f.length)] if f.length > 1 else [""]):
                if f.kind == REAL:
                    out.append(Value(f.name + s, self.nf.value_kind, self.nf.value_reader))
                else:
                    out.append(Value(f.name + s, "MPC_VALUE_U16", "mpc_u16_value"))
        return tuple(out)

    @cached_property
    def value_offsets(self) -> tuple[int, ...]:
        """Octet offset of each of :attr:`values` in the canonical layout (:attr:`packed_dtype`)."""
        placed = self.packed_dtype.fields
        assert placed is not None
        out: list[int] = []
        for f in self.fields:
            base = placed[f.name][1]
            size = self.np_type(f).itemsize
            out.extend(base + j * size for j in range(f.length))
        return tuple(out)

    @property
    def word_count(self) -> int:
        """32-bit words of one record in the canonical layout, the last one zero-padded."""
        return -(-self.packed_dtype.itemsize // 4)

    def words(self, records: np.ndarray) -> np.ndarray:
        """(n, :attr:`word_count`) uint32 array: each record's canonical bytes (:meth:`pack`) read as
        little-endian 32-bit words, the last word zero-padded."""
        octets = self.pack(records)
        padded = np.zeros((len(records), 4 * self.word_count), np.uint8)
        padded[:, :octets.shape[1]] = octets
        return padded.view(np.dtype("<u4")).astype(np.uint32).reshape(len(records), self.word_count)

    @cached_property
    def layout_hash(self) -> str:
        """SHA-256 (hex, 16 chars) of the layout: record name, field names, kinds, C types, lengths."""
        text = self.record.name + ";" + ";".join(
            f"{f.name}:{f.kind}:{self.c_type(f)}:{f.length}" for f in self.fields)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def encode(self, name: str, x: object) -> np.ndarray:
        """SI values ``x`` of real field ``name`` stored in the format (its unit's Q format in fixed point)."""
        return self.nf.encode(self.record.field(name).unit, x)

    def decode(self, name: str, n: object) -> np.ndarray:
        """SI values (float64) of stored values ``n`` of real field ``name``."""
        return self.nf.decode(self.record.field(name).unit, n)

    def zeros(self, n: int) -> np.ndarray:
        """``n`` zeroed records."""
        return np.zeros(n, self.dtype)

    def pack(self, records: np.ndarray) -> np.ndarray:
        """(n, octets) uint8 array: each record's values, little-endian, no padding."""
        packed = np.zeros(len(records), self.packed_dtype)
        for f in self.fields:
            packed[f.name] = records[f.name]
        return packed.view(np.uint8).reshape(len(records), self.packed_dtype.itemsize)

    def unpack(self, octets: bytes | np.ndarray, n: int | None = None) -> np.ndarray:
        """Records (aligned dtype) from canonical bytes."""
        buf = np.frombuffer(bytes(octets), dtype=self.packed_dtype, count=-1 if n is None else n)
        out = self.zeros(len(buf))
        for f in self.fields:
            out[f.name] = buf[f.name]
        return out

    def crc(self, records: np.ndarray) -> int:
        """CRC-32 of every value of every record (the firmware's crc_in / crc_out)."""
        return zlib.crc32(self.pack(records).tobytes()) & 0xFFFFFFFF

    def record_crcs(self, records: np.ndarray) -> list[int]:
        """CRC-32 of each record's values (compact expected outputs)."""
        return [zlib.crc32(row.tobytes()) & 0xFFFFFFFF for row in self.pack(records)]

    def rows(self, records: np.ndarray) -> list[dict[str, Any]]:
        """Plain Python rows (float32 values as exact Python floats), for templates."""
        cols = {f.name: records[f.name].tolist() for f in self.fields}
        return [{f.name: cols[f.name][i] for f in self.fields} for i in range(len(records))]


#: Motor measurements every controller step takes first (every topology).
MOTOR_INPUT_FIELDS: tuple[Field, ...] = fields("""
    ia_a           real  1  sampled phase-a current, A
    ib_a           real  1  sampled phase-b current, A
    theta_e_rad    real  1  electrical rotor angle, rad (|x| <= angle guard)
    omega_e_rad_s  real  1  electrical rotor speed, rad/s
""")

"""``mpcgen tables`` for the T-type topology: the derivations against the seed's Tables 2-3
(mpdtc-three-level.md "Virtual vectors", "Candidate table (Table 3), derived").

Structured checks (for tests and the ``tables`` command) and ``tables_report()``.

Comparison of a Table-3 row (sector I): the seed names a previous *vector*;
u0 is the state OOO (the zero 63-MPDTC applies); a small vector u1..u6 stands
for two states, both compared: its N-type state (which is also the end state
of the virtual vectors the seed lists in the row header) and its P-type state.
A seed item ``u_s1`` without superscript names the group whatever versions it
holds; ``u_s1^u2`` requires the group to hold exactly that version.  Basic
items (``u1``) name the group whatever redundant states it holds.  A row
MATCHes when seed items and derived groups correspond one to one.
"""
from __future__ import annotations

from dataclasses import dataclass

from codegen.topologies.ttype import candidates as cd
from codegen.topologies.ttype import published as pub
from codegen.topologies.ttype import vectors as v
from codegen.topologies.ttype import virtual as vv

# --- Table 2 ----------------------------------------------------------------

@dataclass(frozen=True)
class Table2Check:
    name: str
    derived: str  # 'ONN-OON-...'
    seed: str  # seed's sequence with '0' read as 'O'
    match: bool


def table2_check() -> tuple[Table2Check, ...]:
    out = []
    for row in pub.TABLE2_SEQUENCES:
        derived = vv.virtual_by_name(row.name).sequence_names()
        out.append(Table2Check(row.name, derived, row.sequence, derived == row.sequence))
    return tuple(out)


# --- Table 3 ----------------------------------------------------------------

@dataclass(frozen=True)
class Table3Check:
    prev_label: str  # 'u2 (OON)'
    prev_state: int
    derived: tuple[str, ...]  # group labels, table order
    source_sector: int  # 0-based; != 0 means fallback from sector I
    seed: tuple[str, ...] | None  # ASCII transcription; None: not in the seed
    seed_printed: str
    status: str  # 'MATCH' | 'DIFFERS' | 'DERIVED' (no seed row)
    note: str

    @property
    def n_groups(self) -> int:
        return len(self.derived)


def _split_label(label: str) -> tuple[str, str | None]:
    base, _, split = label.partition("^")
    return base, (split or None)


def compare_labels(seed: tuple[str, ...], derived: tuple[str, ...]) -> tuple[bool, str]:
    """One-to-one correspondence of seed items and derived group labels."""
    d = {_split_label(x)[0]: x for x in derived}
    missing, versions = [], []
    used = set()
    for item in seed:
        base, split = _split_label(item)
        if base not in d:
            missing.append(item)
            continue
        used.add(base)
        if split is not None and d[base] != item:
            versions.append(f"{item} vs derived {d[base]}")
    extra = [x for x in derived if _split_label(x)[0] not in used]
    parts = []
    if missing:
        parts.append("not derived: " + ", ".join(missing))
    if extra:
        parts.append("derived, not in the paper: " + ", ".join(extra))
    if versions:
        parts.append("split version: " + "; ".join(versions))
    return (not parts), "; ".join(parts)


def _row_states(prev: int) -> tuple[int, ...]:
    if prev == 0:
        return (v.OOO,)
    if 1 <= prev <= 6:
        return (v.n_type(prev), v.p_type(prev))
    return v.BASIC_STATES[prev]


def _check(prev_state: int, label: str, seed_row: pub.Table3Row | None) -> Table3Check:
    row = cd.derive_candidate_table().row(prev_state, 0)
    derived = cd.row_labels(row)
    fb = f"fallback to sector {cd.SECTOR_NAMES[row.source_sector]}" if row.fallback else ""
    if seed_row is None:
        return Table3Check(label, prev_state, derived, row.source_sector, None, "", "DERIVED", fb)
    ok, note = compare_labels(seed_row.candidates, derived)
    note = "; ".join(x for x in (fb, note) if x)
    return Table3Check(label, prev_state, derived, row.source_sector, seed_row.candidates,
                       seed_row.printed, "MATCH" if ok else "DIFFERS", note)


def table3_check() -> tuple[Table3Check, ...]:
    """Every seed Table-3 row against the derived sector-I rows (small vectors: both states)."""
    out = []
    for seed_row in pub.TABLE3_SECTOR_I:
        for s in _row_states(seed_row.prev):
            out.append(_check(s, f"u{seed_row.prev} ({v.STATES[s].name})", seed_row))
    return tuple(out)


#: spec acceptance rows (mpdtc-three-level.md "Candidate table"): sector I,
#: exact group labels (a label without '^' means both split versions)
SPEC_REQUIRED_ROWS: dict[str, tuple[str, ...]] = {
    "OOO": ("u0", "u1", "u_s1", "u_m1", "u_L1"),
    "PNN": ("u1", "u_s1^u1", "u_m1^u1", "u_L1", "u7", "u8"),
    "PON": ("u1", "u_s1", "u_m1", "u_L1", "u7", "u8"),
    "PPN": ("u_s1^u2", "u_m1^u2", "u8"),
}


def required_rows_check() -> dict[str, bool]:
    """Spec acceptance: the four rows exactly (as sets) and ONN with 7 groups."""
    t = cd.derive_candidate_table()
    out = {name: set(cd.row_labels(t.row(v.state_by_name(name), 0))) == set(want)
           for name, want in SPEC_REQUIRED_ROWS.items()}
    out["ONN has 7 groups"] = t.row(v.state_by_name("ONN"), 0).n_groups == 7
    return out


def fallback_example_check() -> tuple[bool, str]:
    """The seed's worked example (prev u7, u* in sector VI -> sector II)."""
    ex = pub.FALLBACK_EXAMPLE
    (state,) = v.BASIC_STATES[ex.prev]
    row = cd.derive_candidate_table().row(state, ex.sector)
    ok = row.source_sector == ex.used_sector and set(cd.row_labels(row)) == set(ex.candidates)
    return ok, (f"prev u{ex.prev}, u* in sector {cd.SECTOR_NAMES[ex.sector]}: derived sector "
                f"{cd.SECTOR_NAMES[row.source_sector]} {{{', '.join(cd.row_labels(row))}}}; paper sector "
                f"{cd.SECTOR_NAMES[ex.used_sector]} {{{', '.join(ex.candidates)}}}")


def group_count_histogram(states: tuple[int, ...] | None = None) -> dict[int, int]:
    """Rows per group count over ``states`` (default: states 63-MPDTC can apply)."""
    states = cd.applied_states_63() if states is None else states
    t = cd.derive_candidate_table()
    hist: dict[int, int] = {}
    for s in states:
        for k in range(cd.N_SECTORS):
            n = t.row(s, k).n_groups
            hist[n] = hist.get(n, 0) + 1
    return dict(sorted(hist.items()))


# --- text -------------------------------------------------------------------

def _fmt_row(labels: tuple[str, ...]) -> str:
    return "{" + ", ".join(labels) + "}"


def tables_report() -> str:
    """Seed notation: Table 2 sequences, sector-I candidate rows vs Table 3."""
    lines = ["T-type three-level 63-MPDTC: derived tables vs the MPDTC paper", "",
             "Table 2: virtual-vector sequences (sectors I, II)"]
    for c in table2_check():
        lines.append(f"  {c.name:<8} {c.derived}  {'MATCH' if c.match else 'DIFFERS (paper ' + c.seed + ')'}")
    lines += ["", "Spec acceptance rows (sector I)"]
    t = cd.derive_candidate_table()
    for name, ok in required_rows_check().items():
        if name in SPEC_REQUIRED_ROWS:
            s = v.state_by_name(name)
            got = _fmt_row(cd.row_labels(t.row(s, 0)))
            lines.append(f"  u{v.STATES[s].number} ({name}): {got}  {'MATCH' if ok else 'DIFFERS'}")
        else:
            lines.append(f"  {name}: {'yes' if ok else 'NO'}")
    ok, text = fallback_example_check()
    lines += ["", f"Seed fallback example: {text}  {'MATCH' if ok else 'DIFFERS'}", "",
              "Table 3: u* in sector I, derived rows vs the paper (extracted text)"]
    for r in table3_check():
        lines.append(f"  {r.prev_label:<11} derived {_fmt_row(r.derived)} [{r.n_groups}]  {r.status}")
        if r.status == "DIFFERS":
            lines.append(f"  {'':<11} paper   {r.seed_printed}")
        if r.note:
            lines.append(f"  {'':<11} ({r.note})")
    for name in ("NNN", "PPP"):
        row = t.row(v.state_by_name(name), 0)
        extra = " short: no sector offers 3 groups; never applied by 63-MPDTC" if row.short else ""
        lines.append(f"  u0 ({name})    derived {_fmt_row(cd.row_labels(row))} [{row.n_groups}]  "
                     f"not in the paper{extra}")
    hist = group_count_histogram()
    lines += ["", "Group counts over the 25 states 63-MPDTC applies x 12 sectors: "
              + ", ".join(f"{n} groups: {k} rows" for n, k in hist.items())
              + f" (paper: {' or '.join(map(str, pub.PUBLISHED_GROUP_COUNTS))})"]
    return "\n".join(lines) + "\n"


def tables_rows() -> list[dict[str, object]]:
    """The derived tables as rows (``tables --json/--csv``): every vector with its 7-segment
    sequence, and every candidate-table row (state applied last x sector of u*) with its groups."""
    rows: list[dict[str, object]] = []
    for i in range(vv.N_VECTORS):
        seq = vv.virtual_of(i).sequence_names() if vv.is_virtual(i) else ""
        rows.append({"table": "vectors", "vector_id": i, "name": vv.vector_name(i), "virtual": vv.is_virtual(i),
                     "sequence": seq})
    t = cd.derive_candidate_table()
    for r in t.rows:
        rows.append({"table": "candidates", "prev_state": v.STATES[r.prev_state].name,
                     "sector": cd.SECTOR_NAMES[r.sector], "groups": " ".join(cd.row_labels(r)),
                     "n_groups": r.n_groups, "fallback_from": cd.SECTOR_NAMES[r.source_sector] if r.fallback else ""})
    return rows

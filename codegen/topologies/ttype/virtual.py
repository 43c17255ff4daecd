"""Virtual vectors of 63-MPDTC: 24 small triangles, 36 seven-segment sequences.

mpdtc-three-level.md "Virtual vectors (section 2.1, Table 2)"; seed 000
eq. (8)-(9), Table 2, Fig. 4.

Triangles: the 19 basic vectors u0..u18 form a lattice of pitch Udc/3; a small
triangle is a triple of pairwise adjacent vectors (found by search, 24 of
them).  Each virtual vector applies its triangle's three vertices Ts/3 each
(eq. (8)-(9)) and so points at the centroid.  Kinds by vertices:
virtual small {zero, small, small}, virtual medium {small, small, medium},
virtual large {small, medium, large}.  Names follow the seed: u_s1..u_s6,
u_m1..u_m6 and u_L1..u_L12 in ascending centroid angle from 0 deg (u_s1, u_m1
at 30 deg; u_L1 in [0, 30) deg, u_L12 in (330, 360) deg).

Split pair: a small vertex whose redundant pair (N-type, P-type) shares the
vertex's Ts/3.  Virtual small/medium have two small vertices, hence two
versions ("u_s1^u1", "u_s1^u2": superscript = the split pair, as in the
seed's Table 2); a virtual large has one ("u_L1").  36 virtual vectors, 24
distinct voltages.

Sequence rule (derived, not typed): start at the split pair's N-type state,
raise one leg by one level per step through one state of each other vertex
to the split pair's P-type state, then mirror back:
    [N, b, c, P, c, b, N]
The path is searched over all states of the two other vertices in both orders
and asserted unique.  Segment times (spec):
    [T_N/2, T_b/2, T_c/2, T_P, T_c/2, T_b/2, T_N/2],
    T_b = T_c = Ts/3,  T_N + T_P = Ts/3,
T_N set at run time by the neutral-point deadbeat split (eq. (10)-(11)).  The
period average is the centroid for any T_N.

The 63-vector id space of 63-MPDTC: ids 0..26 are the basic states (id =
state index), ids 27..62 the virtual vectors in ``VIRTUAL`` order: u_s1^u1,
u_s1^u2, u_s2^u2, u_s2^u3, ..., u_s6^u6, u_s6^u1, u_m1^u1, ..., u_m6^u1,
u_L1, ..., u_L12 (split versions in counter-clockwise order of the split pair).
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import cache

import numpy as np

from codegen.topologies.ttype import vectors as v

N_TRIANGLES = 24
N_VIRTUAL = 36
N_VECTORS = v.N_STATES + N_VIRTUAL  # 63
FIRST_VIRTUAL_ID = v.N_STATES  # 27

#: segment roles of the 7-segment sequence
SEGMENT_ROLES: tuple[str, ...] = ("N", "b", "c", "P", "c", "b", "N")
#: segment time = factor * T_<role>;  T_b = T_c = Ts/3, T_P = Ts/3 - T_N
SEGMENT_TIMES: tuple[tuple[str, float], ...] = (
    ("T_N", 0.5), ("T_b", 0.5), ("T_c", 0.5), ("T_P", 1.0), ("T_c", 0.5), ("T_b", 0.5), ("T_N", 0.5),
)

_KIND_BY_VERTICES: dict[tuple[str, ...], str] = {
    ("small", "small", "zero"): "small",
    ("medium", "small", "small"): "medium",
    ("large", "medium", "small"): "large",
}
_PREFIX = {"small": "s", "medium": "m", "large": "L"}


@dataclass(frozen=True)
class Triangle:
    """One of the 24 small triangles of the three-level hexagon."""

    index: int  # 0..23, ascending (kind small, medium, large; then number)
    kind: str  # 'small' | 'medium' | 'large' (kind of virtual vector)
    number: int  # 1..6 (small, medium) or 1..12 (large)
    vertices: tuple[int, int, int]  # basic numbers u0..u18, ascending
    alpha: float  # centroid / Udc
    beta: float
    angle_deg: float  # centroid angle in [0, 360)

    @property
    def name(self) -> str:
        return f"u_{_PREFIX[self.kind]}{self.number}"

    @property
    def key(self) -> tuple[int, int]:
        """3 x centroid in the exact lattice coordinates of ``vectors.lattice_key``."""
        keys = [v.STATES[v.BASIC_STATES[n][0]].key for n in self.vertices]
        return (sum(k[0] for k in keys), sum(k[1] for k in keys))


@dataclass(frozen=True)
class VirtualVector:
    """A virtual vector: a triangle, its split pair and its 7-segment sequence."""

    id: int  # 27..62 in the 63-vector id space
    name: str  # 'u_s1^u1', 'u_m6^u1', 'u_L1'
    kind: str  # 'small' | 'medium' | 'large'
    number: int  # 1..6 / 1..12
    split: int  # basic number (1..6) of the split small pair
    triangle: int  # index into TRIANGLES
    sequence: tuple[int, ...]  # 7 state indices [N, b, c, P, c, b, N]
    alpha: float  # period-average voltage (centroid) / Udc, float64
    beta: float
    angle_deg: float

    @property
    def group_name(self) -> str:
        """Name without the split superscript ('u_s1'); equal for both versions."""
        return self.name.split("^")[0]

    @property
    def start_state(self) -> int:
        """First (and last) state applied: the split pair's N-type state."""
        return self.sequence[0]

    @property
    def end_state(self) -> int:
        return self.sequence[-1]

    @property
    def n_state(self) -> int:
        return self.sequence[0]

    @property
    def b_state(self) -> int:
        return self.sequence[1]

    @property
    def c_state(self) -> int:
        return self.sequence[2]

    @property
    def p_state(self) -> int:
        return self.sequence[3]

    @property
    def key(self) -> tuple[int, int]:
        return TRIANGLES[self.triangle].key

    def sequence_names(self) -> str:
        """'ONN-OON-OOO-POO-OOO-OON-ONN' (the seed's Table 2 notation)."""
        return "-".join(v.STATES[s].name for s in self.sequence)


def _adjacent(n1: int, n2: int) -> bool:
    """Basic vectors one lattice pitch (Udc/3) apart, exact."""
    s1 = v.STATES[v.BASIC_STATES[n1][0]].levels
    s2 = v.STATES[v.BASIC_STATES[n2][0]].levels
    d = (s1[0] - s2[0], s1[1] - s2[1], s1[2] - s2[2])
    return v.m36(d) == 4  # 36 (1/3)^2


def _centroid(vertices: tuple[int, ...]) -> tuple[float, float]:
    reps = [v.STATES[v.BASIC_STATES[n][0]] for n in vertices]
    return (sum(r.alpha for r in reps) / 3.0, sum(r.beta for r in reps) / 3.0)


def _derive_triangles() -> tuple[Triangle, ...]:
    found: dict[str, list[tuple[float, tuple[int, int, int], float, float]]] = {
        "small": [], "medium": [], "large": []}
    for tri in itertools.combinations(range(v.N_BASIC), 3):
        if all(_adjacent(a, b) for a, b in itertools.combinations(tri, 2)):
            kinds = tuple(sorted(v.STATES[v.BASIC_STATES[n][0]].kind for n in tri))
            kind = _KIND_BY_VERTICES[kinds]
            ca, cb = _centroid(tri)
            found[kind].append((v.angle_deg(ca, cb), tri, ca, cb))
    out: list[Triangle] = []
    for kind in ("small", "medium", "large"):
        for number, (ang, tri, ca, cb) in enumerate(sorted(found[kind]), start=1):
            out.append(Triangle(len(out), kind, number, tri, ca, cb, ang))
    assert [t.kind for t in out].count("small") == 6
    assert [t.kind for t in out].count("medium") == 6
    assert len(out) == N_TRIANGLES
    return tuple(out)


TRIANGLES: tuple[Triangle, ...] = _derive_triangles()


def sequence_paths(tri: Triangle, split: int) -> list[tuple[int, int, int, int]]:
    """Every path N -> b -> c -> P obeying the sequence rule (should be one).

    N, P: the split pair's N- and P-type states; b, c: one state of each of
    the triangle's two other vertices, in either order; each step raises
    exactly one leg by exactly one level.
    """
    start, end = v.n_type(split), v.p_type(split)
    others = [n for n in tri.vertices if n != split]
    paths = []
    for vb, vc in itertools.permutations(others):
        for sb in v.BASIC_STATES[vb]:
            for sc in v.BASIC_STATES[vc]:
                path = (start, sb, sc, end)
                if all(_rises_one_leg(path[k], path[k + 1]) for k in range(3)):
                    paths.append(path)
    return paths


def _rises_one_leg(s0: int, s1: int) -> bool:
    d = [b - a for a, b in zip(v.STATES[s0].levels, v.STATES[s1].levels)]
    return sorted(d) == [0, 0, 1]


def _derive_virtual() -> tuple[VirtualVector, ...]:
    out: list[VirtualVector] = []
    for tri in TRIANGLES:
        smalls = [n for n in tri.vertices if 1 <= n <= 6]
        # counter-clockwise order of the split pair (u6 before u1 across 0 deg)
        smalls.sort(key=lambda n: (v.STATES[v.BASIC_STATES[n][0]].angle_deg - tri.angle_deg + 180.0) % 360.0)
        for split in smalls:
            paths = sequence_paths(tri, split)
            if len(paths) != 1:
                raise AssertionError(f"{tri.name} split u{split}: {len(paths)} sequence paths, expected 1")
            n, b, c, p = paths[0]
            name = tri.name if tri.kind == "large" else f"{tri.name}^u{split}"
            out.append(VirtualVector(
                id=FIRST_VIRTUAL_ID + len(out),
                name=name,
                kind=tri.kind,
                number=tri.number,
                split=split,
                triangle=tri.index,
                sequence=(n, b, c, p, c, b, n),
                alpha=tri.alpha,
                beta=tri.beta,
                angle_deg=tri.angle_deg,
            ))
    assert len(out) == N_VIRTUAL
    return tuple(out)


#: the 36 virtual vectors, id order (id = 27 + position)
VIRTUAL: tuple[VirtualVector, ...] = _derive_virtual()


def virtual_by_name(name: str) -> VirtualVector:
    """Look up 'u_s1^u2', 'u_L1', ... (exact names of ``VIRTUAL``)."""
    for vv in VIRTUAL:
        if vv.name == name:
            return vv
    raise ValueError(f"no virtual vector named {name!r}")


def segment_times(t_n: float, ts: float) -> np.ndarray:
    """Segment durations [T_N/2, Ts/6, Ts/6, Ts/3 - T_N, Ts/6, Ts/6, T_N/2], float64.

    ``t_n`` is the start (N-type) state's time, 0 <= t_n <= Ts/3.
    """
    third = ts / 3.0
    if not 0.0 <= t_n <= third:
        raise ValueError(f"T_N = {t_n} outside [0, Ts/3 = {third}]")
    tt = {"T_N": t_n, "T_b": third, "T_c": third, "T_P": third - t_n}
    return np.array([f * tt[role] for role, f in SEGMENT_TIMES])


# --- the 63-vector id space -------------------------------------------------

def is_virtual(vid: int) -> bool:
    _check_id(vid)
    return vid >= FIRST_VIRTUAL_ID


def virtual_of(vid: int) -> VirtualVector:
    if not is_virtual(vid):
        raise ValueError(f"vector id {vid} is a basic state")
    return VIRTUAL[vid - FIRST_VIRTUAL_ID]


def vector_name(vid: int) -> str:
    """A state's letters ('PON') or a virtual vector's name ('u_s1^u1')."""
    return virtual_of(vid).name if is_virtual(vid) else v.STATES[vid].name


def start_state(vid: int) -> int:
    """First state applied by vector ``vid`` (itself for a basic state)."""
    return virtual_of(vid).start_state if is_virtual(vid) else vid


def end_state(vid: int) -> int:
    """State applied last by ``vid``: a virtual vector ends in its start state."""
    return virtual_of(vid).end_state if is_virtual(vid) else vid


def vector_key(vid: int) -> tuple[int, int]:
    """Exact voltage identity, 3 x lattice coordinates (equal <=> same voltage)."""
    if is_virtual(vid):
        return virtual_of(vid).key
    k = v.STATES[vid].key
    return (3 * k[0], 3 * k[1])


def vector_voltage(vid: int) -> tuple[float, float]:
    """(alpha, beta) / Udc, period average, float64."""
    x = virtual_of(vid) if is_virtual(vid) else v.STATES[vid]
    return (x.alpha, x.beta)


def vector_angle_deg(vid: int) -> float:
    x = virtual_of(vid) if is_virtual(vid) else v.STATES[vid]
    return x.angle_deg


def vector_magnitude(vid: int) -> float:
    a, b = vector_voltage(vid)
    return math.hypot(a, b)


def vector_group_name(vid: int) -> str:
    """Seed notation of the voltage: 'u8', 'u0', 'u_s1', 'u_L1'."""
    return virtual_of(vid).group_name if is_virtual(vid) else f"u{v.STATES[vid].number}"


@cache
def vector_voltages() -> tuple[np.ndarray, np.ndarray]:
    """(alpha, beta) / Udc of the 63 vectors by id, float64 arrays."""
    ab = [vector_voltage(i) for i in range(N_VECTORS)]
    return (np.array([a for a, _ in ab]), np.array([b for _, b in ab]))


def _check_id(vid: int) -> None:
    if not 0 <= vid < N_VECTORS:
        raise ValueError(f"vector id {vid} outside 0..{N_VECTORS - 1}")

"""T-type three-level inverter: switching states and basic vectors.

mpdtc-three-level.md "Inverter, vectors, neutral point"; seed 000 Fig. 2,
Table 1, eq. (1)-(2) (eq. (2) as corrected by the spec).

Leg level S in {P, O, N} = {+1, 0, -1}; leg voltage S*Udc/2 against the DC
midpoint o.  A state is indexed ``9*(Sa+1) + 3*(Sb+1) + (Sc+1)``, so NNN = 0,
OOO = 13, PPP = 26, and named by its legs a, b, c, e.g. ``'PON'``.

Space vector (amplitude invariant), eq. in the spec:
    u = (2/3) (Sa + a Sb + a^2 Sc) Udc/2,   a = exp(j 2 pi/3),
returned here per unit of Udc (float64): u/Udc = (Sa + a Sb + a^2 Sc)/3.
Classification is exact (integers), from 36 |u/Udc|^2 = (2Sa-Sb-Sc)^2 + 3(Sb-Sc)^2
in {0, 4, 12, 16}: zero, small (Udc/3), medium (Udc/sqrt 3), large (2Udc/3).
A small state is P-type if no leg is at N (POO, PPO, ...), N-type if no leg is
at P (ONN, OON, ...).

Basic-vector numbering of the seed's tables: u0 zero; u1..u6 small at 0, 60,
..., 300 deg; u7..u18 large (odd) and medium (even) alternating every 30 deg
starting with u7 = PNN at 0 deg, u8 = PON at 30 deg, u9 = PPN at 60 deg.

Neutral point (spec, correcting eq. (2)): the current drawn from the midpoint
is i_o = sum_x (1 - |S_x|) i_x, i.e. the phases whose leg is at O.
``State.io`` holds these 0/1 coefficients for (i_a, i_b, i_c).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

N_STATES = 27
N_BASIC = 19  # u0..u18: distinct space vectors

LEVEL_CHAR: dict[int, str] = {1: "P", 0: "O", -1: "N"}
CHAR_LEVEL: dict[str, int] = {c: s for s, c in LEVEL_CHAR.items()}

#: 36 |u/Udc|^2 of each kind (exact integer classification)
_KIND_OF_36M2: dict[int, str] = {0: "zero", 4: "small", 12: "medium", 16: "large"}
MAGNITUDE: dict[str, float] = {
    "zero": 0.0,
    "small": 1.0 / 3.0,
    "medium": 1.0 / math.sqrt(3.0),
    "large": 2.0 / 3.0,
}

Levels = tuple[int, int, int]


@dataclass(frozen=True)
class State:
    """One of the 27 switching states."""

    index: int  # 9*(Sa+1) + 3*(Sb+1) + (Sc+1)
    name: str  # legs a, b, c, e.g. 'PON'
    levels: Levels  # (Sa, Sb, Sc), each +1/0/-1
    alpha: float  # u_alpha / Udc
    beta: float  # u_beta / Udc
    kind: str  # 'zero' | 'small' | 'medium' | 'large'
    small_type: str  # 'P' or 'N' for small states, '' otherwise
    number: int  # seed basic-vector number 0..18 (u0..u18)
    angle_deg: float  # angle of u in [0, 360); 0.0 for the zero vector
    io: Levels  # neutral-point coefficients: i_o = io . (i_a, i_b, i_c)

    @property
    def key(self) -> tuple[int, int]:
        """Exact identity of the space vector: (Sa - Sb, Sb - Sc)."""
        return lattice_key(self.levels)


def state_index(levels: Levels) -> int:
    """Index of the state with leg levels ``levels``."""
    sa, sb, sc = levels
    for s in levels:
        if s not in (-1, 0, 1):
            raise ValueError(f"leg level must be -1, 0 or +1, got {levels}")
    return 9 * (sa + 1) + 3 * (sb + 1) + (sc + 1)


def lattice_key(levels: Levels) -> tuple[int, int]:
    """Two line voltages in Udc/2 units; equal keys <=> equal space vectors."""
    sa, sb, sc = levels
    return (sa - sb, sb - sc)


def m36(levels: Levels) -> int:
    """36 |u/Udc|^2 as an exact integer."""
    sa, sb, sc = levels
    return (2 * sa - sb - sc) ** 2 + 3 * (sb - sc) ** 2


def space_vector(levels: Levels) -> tuple[float, float]:
    """(u_alpha, u_beta) / Udc of a state: (Sa + a Sb + a^2 Sc)/3, float64."""
    sa, sb, sc = levels
    a = np.exp(2j * np.pi / 3)
    z = (sa + a * sb + a * a * sc) / 3.0
    ux, uy = float(z.real), float(z.imag)
    # exact zeros where the geometry has them (cancellation leaves ~1e-17)
    return (0.0 if abs(ux) < 1e-12 else ux, 0.0 if abs(uy) < 1e-12 else uy)


def angle_deg(alpha: float, beta: float) -> float:
    """Angle in [0, 360) deg; 0.0 for a zero vector."""
    if alpha == 0.0 and beta == 0.0:
        return 0.0
    a = math.degrees(math.atan2(beta, alpha)) % 360.0
    return 0.0 if a >= 360.0 - 1e-9 else a


def _make_state(index: int) -> State:
    levels = (index // 9 - 1, (index // 3) % 3 - 1, index % 3 - 1)
    kind = _KIND_OF_36M2[m36(levels)]
    alpha, beta = space_vector(levels)
    ang = angle_deg(alpha, beta)
    small_type = ""
    if kind == "small":
        small_type = "N" if 1 not in levels else "P"
    if kind == "zero":
        number = 0
    elif kind == "small":
        number = 1 + round(ang / 60.0) % 6
    else:
        number = 7 + round(ang / 30.0) % 12
    return State(
        index=index,
        name="".join(LEVEL_CHAR[s] for s in levels),
        levels=levels,
        alpha=alpha,
        beta=beta,
        kind=kind,
        small_type=small_type,
        number=number,
        angle_deg=ang,
        io=tuple(1 - abs(s) for s in levels),  # type: ignore[arg-type]
    )


#: the 27 states, by index
STATES: tuple[State, ...] = tuple(_make_state(i) for i in range(N_STATES))
_BY_NAME: dict[str, int] = {s.name: s.index for s in STATES}

#: states of each basic vector u0..u18, ascending state index
#: (u0: NNN, OOO, PPP; a small vector: its N-type then its P-type state)
BASIC_STATES: tuple[tuple[int, ...], ...] = tuple(
    tuple(s.index for s in STATES if s.number == n) for n in range(N_BASIC)
)

OOO = _BY_NAME["OOO"]
PPP = _BY_NAME["PPP"]
NNN = _BY_NAME["NNN"]


def state_by_name(name: str) -> int:
    """Index of a state given as three letters of P/O/N, e.g. 'PON'."""
    try:
        return _BY_NAME[name.upper()]
    except KeyError:
        raise ValueError(f"not a switching state: {name!r} (three of P, O, N)") from None


def n_type(number: int) -> int:
    """N-type state of the small vector u<number> (1..6)."""
    return _small_of_type(number, "N")


def p_type(number: int) -> int:
    """P-type state of the small vector u<number> (1..6)."""
    return _small_of_type(number, "P")


def _small_of_type(number: int, t: str) -> int:
    if not 1 <= number <= 6:
        raise ValueError(f"small vectors are u1..u6, got u{number}")
    (idx,) = [i for i in BASIC_STATES[number] if STATES[i].small_type == t]
    return idx


def basic_voltages() -> tuple[np.ndarray, np.ndarray]:
    """(alpha, beta) / Udc of u0..u18, float64 arrays of length 19."""
    reps = [STATES[b[0]] for b in BASIC_STATES]
    return (np.array([s.alpha for s in reps]), np.array([s.beta for s in reps]))


def state_voltages() -> tuple[np.ndarray, np.ndarray]:
    """(alpha, beta) / Udc of the 27 states by index, float64 arrays."""
    return (np.array([s.alpha for s in STATES]), np.array([s.beta for s in STATES]))


def io_matrix() -> np.ndarray:
    """27 x 3 int array: i_o(state) = io_matrix()[state] @ (i_a, i_b, i_c)."""
    return np.array([s.io for s in STATES], dtype=np.int64)

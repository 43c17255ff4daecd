"""Published data of seed 000 (Zheng Weijie et al., Chinese Journal of
Scientific Instrument, 2023) as frozen fixtures, transcribed from the seed's
text extraction.

Nothing here is computed or corrected.  Each Table-3 row keeps the extracted
text verbatim (``printed``, ``header_printed``) next to an ASCII transcription
(``candidates``) in the notation used by ``codegen.topologies.ttype``:

* ``u0`` .. ``u18``: basic vectors (u0 zero, u1..u6 small, u7.. large/medium);
* ``u_s1``, ``u_m1``, ``u_L1``: a virtual vector without superscript;
* ``u_s1^u2``: the version whose split (first) vector is u2 (the seed's
  superscript).

Extraction artefacts (kept as printed, noted in comments): ``00N``/``000``
for OON/OOO in Table 2 (digit zero for the letter O); in the Table-3 row
headers some subscripts are garbled (e.g. row u2 lists u_s2^u2 and u_s6^u2
where the virtual vectors starting at u2 are u_s1^u2, u_s2^u2, u_m1^u2,
u_m2^u2, u_L2, u_L3).
"""
from __future__ import annotations

from typing import NamedTuple

from codegen.paper import SeedMotor
from codegen.texttable import records, split_rows


def _words(cell: str) -> tuple[str, ...]:
    """A cell of space-separated names as a tuple."""
    return tuple(cell.split())

# ---------------------------------------------------------------------------
# Table 1: output vector magnitudes (表1 T型三电平逆变器输出矢量幅值).
# ---------------------------------------------------------------------------
TABLE1_VECTOR_CLASSES: dict[str, tuple[str, ...]] = {
    "large": ("PNN", "PPN", "PNP", "NNP", "NPN", "NPP"),  # 2Udc/3
    "medium": ("PON", "PNO", "OPN", "ONP", "NOP", "NPO"),  # sqrt(3)Udc/3
    "small": ("ONN", "PPO", "NON", "OPP", "NNO", "POP",
              "POO", "OON", "OPO", "NOO", "OOP", "ONO"),  # Udc/3
    "zero": ("OOO", "PPP", "NNN"),  # 0
}


# ---------------------------------------------------------------------------
# Table 2: virtual vectors in sectors I and II (表2 第I、II扇区虚拟矢量).
# ---------------------------------------------------------------------------
class Table2Row(NamedTuple):
    name: str  # ASCII name
    printed: str  # sequence exactly as extracted ('0' = letter O)

    @property
    def sequence(self) -> str:
        """The printed sequence with the digit 0 read as the letter O."""
        return self.printed.replace("0", "O")


TABLE2_SEQUENCES: tuple[Table2Row, ...] = records(Table2Row, split_rows("""
# name    | printed sequence
    u_s1^u1 | ONN-00N-000-POO-000-00N-ONN
    u_s1^u2 | 00N-000-POO-PPO-POO-000-00N
    u_m1^u1 | ONN-00N-PON-POO-PON-00N-ONN
    u_m1^u2 | 00N-PON-POO-PPO-POO-PON-00N
    u_L1    | ONN-PNN-PON-POO-PON-PNN-ONN
    u_L2    | 00N-PON-PPN-PPO-PPN-PON-00N
""", 2))


# ---------------------------------------------------------------------------
# Table 3: prediction switch table, u* in sector I (表3 u_s^*位于第一扇区时预测开关表).
# ---------------------------------------------------------------------------
class Table3Row(NamedTuple):
    prev: int  # basic-vector number of the row's previous vector (u<prev>)
    header_printed: str  # previous-vector cell as extracted
    printed: str  # candidate cell as extracted
    candidates: tuple[str, ...]  # ASCII transcription, printed order


TABLE3_SECTOR_I: tuple[Table3Row, ...] = records(Table3Row, split_rows("""
# prev | previous-vector cell as extracted | candidate cell as extracted | ASCII transcription
0 | u_0 | u_0, u_{s1}, u_1, u_{m1}, u_{L1} | u0 u_s1 u1 u_m1 u_L1
1 | u_1, u_{s1}^{u_1}, u_{m1}^{u_1}, u_{L1}^{u_1}, u_{s6}^{u_1}, u_{m6}^{u_1}, u_{L12} | u_0, u_1, u_{s1}, u_{m1}, u_{L1}, u_7, u_8 | u0 u1 u_s1 u_m1 u_L1 u7 u8
# header garbled: u_s2^u2 / u_s6^u2 / u_L2^u2 (virtual vectors starting at u2
# are u_s1^u2, u_s2^u2, u_m1^u2, u_m2^u2, u_L2, u_L3)
2 | u_2, u_{s2}^{u_2}, u_{m1}^{u_2}, u_{L2}^{u_2}, u_{s6}^{u_2}, u_{m2}^{u_2}, u_{L3} | u_0, u_{s1}, u_{m1}, u_{L1}, u_8 | u0 u_s1 u_m1 u_L1 u8
3 | u_3, u_{s3}^{u_3}, u_{m2}^{u_3}, u_{L4}^{u_3}, u_{s6}^{u_3}, u_{m3}^{u_3}, u_{L5} | u_0, u_{s2}^{u_2}, u_{m2}^{u_2} | u0 u_s2^u2 u_m2^u2
# candidate cell identical to row u3's as printed
4 | u_4, u_{s4}^{u_4}, u_{m3}^{u_4}, u_{L6}^{u_4}, u_{s6}^{u_4}, u_{m4}^{u_4}, u_{L7} | u_0, u_{s2}^{u_2}, u_{m2}^{u_2} | u0 u_s2^u2 u_m2^u2
# header lists u_L8 twice
5 | u_5, u_{s5}^{u_5}, u_{m4}^{u_5}, u_{L8}^{u_5}, u_{s6}^{u_5}, u_{m5}^{u_5}, u_{L8} | u_0, u_{s6}^{u_6}, u_{m6}^{u_6} | u0 u_s6^u6 u_m6^u6
6 | u_6, u_{s6}^{u_6}, u_{m5}^{u_6}, u_{L10}^{u_6}, u_{s6}^{u_6}, u_{m6}^{u_6}, u_{L11} | u_0, u_1, u_{s1}^{u_1}, u_{m1}^{u_1}, u_{L1} | u0 u1 u_s1^u1 u_m1^u1 u_L1
7 | u_7 | u_1, u_{s1}^{u_1}, u_{m1}^{u_1}, u_{L1}, u_7, u_8 | u1 u_s1^u1 u_m1^u1 u_L1 u7 u8
8 | u_8 | u_1, u_{s1}, u_{m1}, u_{L1}, u_7, u_8 | u1 u_s1 u_m1 u_L1 u7 u8
9 | u_9 | u_{s1}^{u_2}, u_{m1}^{u_2}, u_8 | u_s1^u2 u_m1^u2 u8
10 | u_{10} | u_2, u_{s1}^{u_2}, u_{m1}^{u_2}, u_{L2}, u_9 | u2 u_s1^u2 u_m1^u2 u_L2 u9
11 | u_{11} | u_{s2}^{u_3}, u_{m2}^{u_3}, u_{10} | u_s2^u3 u_m2^u3 u10
12 | u_{12} | u_3, u_{s2}^{u_3}, u_{m2}^{u_3}, u_{L4}, u_{11} | u3 u_s2^u3 u_m2^u3 u_L4 u11
# 'u_{L2}' breaks the pattern of the neighbouring rows (u12 expected)
13 | u_{13} | u_{s3}^{u_4}, u_{m3}^{u_4}, u_{L2} | u_s3^u4 u_m3^u4 u_L2
14 | u_{14} | u_5, u_{s5}, u_{m5}, u_{L9}, u_{15} | u5 u_s5 u_m5 u_L9 u15
15 | u_{15} | u_{s5}^{u_5}, u_{m5}^{u_5}, u_{16} | u_s5^u5 u_m5^u5 u16
16 | u_{16} | u_6, u_{s6}^{u_6}, u_{m6}^{u_6}, u_{L11}, u_{17} | u6 u_s6^u6 u_m6^u6 u_L11 u17
17 | u_{17} | u_{s6}^{u_6}, u_{m6}^{u_6}, u_{18} | u_s6^u6 u_m6^u6 u18
18 | u_{18} | u_1, u_{s1}^{u_1}, u_{m1}^{u_1}, u_{L1}, u_7 | u1 u_s1^u1 u_m1^u1 u_L1 u7
""", 4), (int, str, str, _words))


# ---------------------------------------------------------------------------
# Worked fallback example (section 2.2, 2)): previous vector u7 (large), u* in
# sector 6 (VI) which offers nothing; sector 2 (II) is used instead:
# "即 u_{s1}^{u_1}, u_{m1}^{u_1}, u_8".
# ---------------------------------------------------------------------------
class FallbackExample(NamedTuple):
    prev: int  # basic-vector number
    sector: int  # sector of u*, 0-based (VI -> 5)
    used_sector: int  # 0-based (II -> 1)
    candidates: tuple[str, ...]


FALLBACK_EXAMPLE = FallbackExample(7, 5, 1, ("u_s1^u1", "u_m1^u1", "u8"))

#: candidate counts stated in the text (寻优次数 "3 或 5 或 6 或 7")
PUBLISHED_GROUP_COUNTS: tuple[int, ...] = (3, 5, 6, 7)


# ---------------------------------------------------------------------------
# Table 4: the experiment's motor (表4 电机参数) and section 3's operating points.
# ---------------------------------------------------------------------------
TABLE4_MOTOR = SeedMotor(1.75, 1.6e-3, 1.6e-3, 0.045, 5, 3000.0, 1.27)
#: section 3 / 3.1: Udc = 220 V, control period 50 us, steady runs at rated load 1.27 N*m
UDC_V = 220.0
TS_S = 50e-6


# ---------------------------------------------------------------------------
# Table 5: torque ripple, flux ripple and i_a THD of both MPDTC at the three
# steady speeds (表5 两种MPDTC各项控制目标), T* = 1.27 N*m.  The seed names the
# columns Delta T_e / N*m, Delta psi_s / Wb and i_a THD / % without defining
# the ripple statistic (RMSE, std or peak-to-peak: not stated).
# ---------------------------------------------------------------------------
class Table5Row(NamedTuple):
    speed_rpm: float
    strategy: str  # "mpdtc27" | "mpdtc63"
    dte_nm: float  # Delta T_e / N*m
    dpsi_wb: float  # Delta psi_s / Wb
    thd_ia_percent: float  # i_a THD / %


TABLE5_STEADY: tuple[Table5Row, ...] = records(Table5Row, split_rows("""
# speed | strategy | dTe   | dpsi   | THD
  300   | mpdtc27  | 0.372 | 0.0027 | 16.85
  300   | mpdtc63  | 0.249 | 0.0019 | 9.36
  1800  | mpdtc27  | 0.413 | 0.0026 | 18.28
  1800  | mpdtc63  | 0.265 | 0.0018 | 11.49
  3000  | mpdtc27  | 0.302 | 0.0025 | 17.25
  3000  | mpdtc63  | 0.189 | 0.0017 | 9.57
""", 5), (float, str, float, float, float))

# Text after Table 5: reductions (%) of 63- vs 27-MPDTC per speed, as printed
# (torque ripple, flux ripple, i_a THD); they equal 100*(1 - 63/27) of Table 5.
TABLE5_REDUCTIONS_PERCENT: dict[float, tuple[float, float, float]] = {
    300.0: (33.06, 29.63, 44.45),
    1800.0: (35.84, 30.77, 37.14),
    3000.0: (37.42, 32.00, 44.52),
}

# Section 3.1, Fig. 9 (图9 程序执行时间): execution time per control period on
# the TMS320F28377 (200 MHz), us; the text gives the reduction 11.52 %.
FIG9_EXEC_TIME_US: dict[str, float] = {"mpdtc27": 38.2, "mpdtc63": 33.8}
FIG9_EXEC_TIME_REDUCTION_PERCENT = 11.52

# Section 3.2, Fig. 11 text: u_ab THD at rated load and speed, % (reduction 33.08 %).
FIG11_UAB_THD_PERCENT: dict[str, float] = {"mpdtc27": 86.75, "mpdtc63": 58.05}
FIG11_UAB_THD_REDUCTION_PERCENT = 33.08

# Section 3.2, Fig. 12 text: largest line-voltage jump, in units of Udc/2:
# 27-MPDTC jumps by +-Udc "frequently" (2 units; up to 2 Udc = 4 units possible
# per the introduction), 63-MPDTC "basically" limited to Udc/2 (1 unit; some
# +-Udc at dead time).
FIG12_MAX_JUMP_UDC2: dict[str, int] = {"mpdtc27": 2, "mpdtc63": 1}

# Candidates evaluated per period: 27 for 27-MPDTC, "3 or 5 or 6 or 7" for
# 63-MPDTC (section 3.1 text; PUBLISHED_GROUP_COUNTS).
CANDIDATES_27 = 27

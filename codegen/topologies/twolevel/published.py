"""Published data of seed 001 (Li Yaohua et al., Control Theory & Applications
40(10), 2023) as frozen fixtures, transcribed exactly from the seed text.

Nothing here is computed or corrected: a value that looks wrong in the seed is
kept as printed and the oddity is noted in a comment (the tests check the
transcription, e.g. that utilisation columns sum to ~100 %).

Layout conventions (shared by every table in the product):

* Utilisation tables (Tables 3-8) are stored in the seed's layout: 7 rows
  (eta_V0 .. eta_V6, in %) of n_sectors columns (theta_1 .. theta_n).
* Sectors are 0-based in arrays: the paper's sector 1 is index 0.
* Vectors are ints 0..6 (V0..V6).
* A switch table is a tuple over conditions of tuples over sectors of tuples
  of vector ints, V0 first then ascending vector number, e.g. (0, 2, 3, 4).
* Condition index c: s2: 0 = dT > 0, 1 = dT < 0; s3: 0 = (dT>0, dpsi>0),
  1 = (dT>0, dpsi<=0), 2 = (dT<0, dpsi>0), 3 = (dT<0, dpsi<=0).
"""
from __future__ import annotations

from typing import NamedTuple

from codegen.paper import SeedMotor
from codegen.texttable import int_cells, number_rows, numbers, records, split_rows

Cell = tuple[int, ...]
SwitchTable = tuple[tuple[Cell, ...], ...]
UtilisationTable = tuple[tuple[float, ...], ...]  # 7 rows (V0..V6) x sectors


def _utilisation_tables(text: str, count: int) -> tuple[UtilisationTable, ...]:
    """``count`` utilisation tables written side by side: one line per vector V0..V6, the
    tables' rows separated by ``|``, one column per sector."""
    lines = split_rows(text, count)
    if len(lines) != 7:
        raise ValueError("a utilisation table has 7 rows (V0..V6)")
    tables = tuple(tuple(tuple(float(v) for v in numbers(line[k])) for line in lines) for k in range(count))
    for table in tables:
        if len({len(row) for row in table}) != 1:
            raise ValueError("the rows of a utilisation table have one column per sector")
    return tables


def _cells(text: str) -> tuple[Cell, ...]:
    """Switch-table cells from text: one line per sector, vector numbers separated by spaces."""
    return tuple(row[0] for row in int_cells(text))


# ---------------------------------------------------------------------------
# Table 1: zero-vector utilisation vs torque-error band (conventional MPTC,
# SPMSM scenario, 80 000 samples).  eta_V0 = N_V0 / N (eq. (6)).
# ---------------------------------------------------------------------------
class Table1Row(NamedTuple):
    band_nm: float  # |dT| <= band_nm; math.inf stands for the "> 1.5" row (all samples)
    n: int  # N: samples inside the band
    n_v0: int  # N_V0: of those, samples where V0 was chosen
    eta_v0_percent: float  # eta_V0 / %


# Seed Table 1 (表1 零电压矢量利用率).
# Columns: the bands |dT| <= 0.1 .. 1.5 N*m, then "> 1.5" (inf: the whole run).
TABLE1_ZERO_VECTOR_UTILISATION: tuple[Table1Row, ...] = records(Table1Row, zip(*number_rows("""
      0.1   0.2   0.3   0.4   0.5   0.6   0.7   0.8   0.9   1.0   1.1   1.2   1.3   1.4   1.5   inf  # band_nm
     6018 12153 18397 24714 30896 36874 42757 48384 53452 58233 62382 65930 68792 71166 73130 80000  # N
     4509  8913 13014 16669 19687 22101 23942 25349 26293 26962 27400 27700 27889 28017 28058 28092  # N_V0
    74.93 73.34 70.74 67.45 63.72 59.94 56.00 52.39 49.19 46.30 43.92 42.01 40.54 39.37 38.37 35.12  # eta_V0 %
""")))


# ---------------------------------------------------------------------------
# Table 2: SPMSM performance of strategy s1 vs the torque-error threshold
# eps_T (band [-eps_T, eps_T]); metrics of eq. (7)-(10).
# ---------------------------------------------------------------------------
class Table2Row(NamedTuple):
    band_nm: float  # eps_T / N*m
    t_rip_nm: float  # T_rip RMSE, eq. (7)
    psi_rip_wb: float  # psi_rip RMSE, eq. (8)
    cal_ave: float  # Cal_ave, eq. (10)
    f_ave_khz: float  # f_ave / kHz, eq. (9)


# Seed Table 2 (表2 电机系统性能), threshold sweep rows.
# Columns: the thresholds eps_T = 0.1 .. 1.5 N*m.
TABLE2_THRESHOLD_SWEEP: tuple[Table2Row, ...] = records(Table2Row, zip(*number_rows("""
       0.1    0.2    0.3    0.4    0.5    0.6    0.7    0.8    0.9    1.0    1.1    1.2    1.3    1.4    1.5  # eps_T / N*m
    0.9613 0.9644 0.9733 0.9762 0.9851 1.0037 1.0086 0.9961 0.9988 1.0289  1.076  1.131  1.193 1.2601 1.3273  # T_rip
    0.0046 0.0047 0.0051 0.0052 0.0057 0.0064 0.0088 0.0086 0.0099 0.0128 0.0171 0.0238 0.0297 0.0349 0.0392  # psi_rip
      6.49   5.97   5.42   4.85   4.38      4   3.62   2.87   2.35   2.16   2.06   1.99   1.93   1.89   1.86  # Cal_ave
      6.32   6.13   5.91   5.56    5.2   4.93   4.57   3.54   2.74   2.41   2.16      2   1.88    1.8   1.73  # f_ave / kHz
""")))

# Seed Table 2, last row "传统模型预测控制" (conventional MPTC, no threshold);
# band_nm = 0.0 (no zero-vector shortcut).
TABLE2_CONVENTIONAL: Table2Row = Table2Row(0.0, 0.9614, 0.0045, 7, 6.45)


# ---------------------------------------------------------------------------
# Tables 3-4: utilisation (%) of V0..V6 per 6-sector (eq. (11)), conventional
# MPTC, SPMSM scenario, samples with dT > 0.6 N*m (Table 3) and dT < -0.6 N*m
# (Table 4).  Rows V0..V6, columns theta_1..theta_6; the two tables side by side.
# ---------------------------------------------------------------------------
# Seed Table 3 (表3 电压矢量利用率, 转矩误差大于0.6 N·m) | Seed Table 4 (表4, 转矩误差小于-0.6 N·m).
TABLE3_UTIL_DT_POS, TABLE4_UTIL_DT_NEG = _utilisation_tables("""
    12.39  8.14  4.15  3.24  6.54 11.55 |  3.07  6.16 10.59 13.62 11.37  6.02  # V0
     2.22  0.05  0.92 17.57 52.26 21.13 | 18.53 49.43 21.05  2.53  0.03   1.8  # V1
    23.48  2.32     0  0.61 17.77 45.39 |  1.28 20.95 40.15  20.6  1.73  0.03  # V2
    40.22  22.1  0.86     0  1.46 18.42 |  0.03  2.74 23.15 38.04 19.84  1.57  # V3
    19.76 46.14 20.51  0.58  0.05   1.5 |  1.03     0   2.3 23.16 44.52 18.41  # V4
     1.84 19.43 55.52 19.71  1.36  0.09 | 19.38   1.5  0.08  2.01  20.2 52.63  # V5
     0.09  1.82 18.04 58.29 20.55  1.92 | 56.67 19.22  2.67  0.05  2.31 19.54  # V6
""", 2)
# Samples per sector behind Table 3 (seed text before Table 3; total 23875).
TABLE3_SECTOR_SAMPLES: tuple[int, ...] = (4510, 4005, 3471, 3460, 3961, 4468)
TABLE3_TOTAL_SAMPLES: int = 23875
# Samples per sector behind Table 4 (seed text before Table 4; total 21889).
TABLE4_SECTOR_SAMPLES: tuple[int, ...] = (3194, 3393, 3776, 4038, 3931, 3557)
TABLE4_TOTAL_SAMPLES: int = 21889


# ---------------------------------------------------------------------------
# Tables 5-8: utilisation (%) of V0..V6 per 12-sector (eq. (12)), conventional
# MPTC, SPMSM scenario, |dT| > 0.6 N*m split by the sign of the flux error.
# Rows V0..V6, columns theta_1..theta_12; the four tables side by side:
# Seed Table 5 (表5, dT > 0.6 N·m and dpsi > 0) | Table 6 (表6, dT > 0.6 N·m and
# dpsi < 0) | Table 7 (表7, dT < -0.6 N·m and dpsi > 0) | Table 8 (表8, dT < -0.6 N·m
# and dpsi < 0).
#
# NOTE (seed defect, kept as printed): Table 5 column theta_5 sums to 94.20 %,
# and its V4/V5/V6 entries (18.41, 52.63, 19.54) are identical to Table 4
# theta_6, which suggests a copy error in the seed.  It is also the one sector
# where the seed's published s3 set {V0 V4 V5} disagrees with its own numbers
# (V6 19.54 % > V4 18.41 %).  Table 6 theta_9 V5 is printed "0%".
# ---------------------------------------------------------------------------
(TABLE5_UTIL_DT_POS_DPSI_POS, TABLE6_UTIL_DT_POS_DPSI_NEG,
 TABLE7_UTIL_DT_NEG_DPSI_POS, TABLE8_UTIL_DT_NEG_DPSI_NEG) = _utilisation_tables("""
    16.65  9.44   8.8  6.21  3.62  3.45  4.85  4.65 12.96  9.17 18.22 12.37 | 12.38 18.37  9.53 11.68  3.27  6.33  3.41   8.9  8.34 17.34 12.11  21.9 |  2.54  6.39  7.09 13.28 14.37  14.1 12.29 16.92  9.03 13.39  4.31  8.18 |  8.46  4.26 17.18  9.01 22.86 10.94 24.01 10.44 19.02  9.13 15.22  6.43  # V0
        0     0     0     0     0     0  1.83 13.52 43.96 60.18 42.14 24.33 |     0     0     0     0     0     0 14.82 43.48 68.57 36.48     8  1.31 |  15.9 44.47 58.25 30.32 13.99  2.46     0     0     0     0     0     0 |  1.21 13.19 37.29    50 44.44 38.68     0     0     0     0     0     0  # V1
     46.1 24.21     0     0     0     0     0     0   2.1 11.12 38.31 49.97 |  8.21  1.43     0     0     0     0     0     0 14.97  45.1 57.67 30.83 |     0     0 20.39 53.22 42.63 31.48 13.56   2.9     0     0     0     0 |     0     0  0.98  8.76 30.69 41.86  45.1 24.24     0     0     0     0  # V2
    34.84 50.61 48.15 17.72     0     0     0     0     0     0  1.33 13.34 | 54.22 31.57  8.91  1.48     0     0     0     0     0     0 22.22 45.97 |     0     0     0     0 29.01 51.96 46.86 37.65 12.47  2.46     0     0 |     0     0     0     0  2.01  8.52 29.84 56.57  41.6  18.5     0     0  # V3
     2.41 15.74 40.05 62.19 18.41 13.62     0     0     0     0     0     0 | 25.19 48.62 58.04    40 11.32  0.97     0     0     0     0     0     0 |     0     0     0     0     0     0 27.29 42.53 57.45 45.18 14.15  2.34 |     0     0     0     0     0     0  1.05  8.75 38.65 65.34 43.23 13.12  # V4
        0     0  2.99 13.88 52.63 69.39    43 17.16     0     0     0     0 |     0     0 23.51 46.85  69.3  47.4  9.89  1.03     0     0     0     0 |  15.8  2.05     0     0     0     0     0     0 21.05 38.98 63.82  50.8 | 45.42 16.62     0     0     0     0     0     0  0.74  7.03 40.33 72.97  # V5
        0     0     0     0 19.54 13.53 50.32 64.67 40.98 19.53     0     0 |     0     0     0     0  16.1 45.29 71.88 46.58  8.11  1.08     0     0 | 65.76 47.09 14.27  3.18     0     0     0     0     0     0 17.71 38.68 | 44.91 65.93 44.55 32.23     0     0     0     0     0     0  1.22  7.48  # V6
""", 4)
# Samples per sector behind Table 5 (seed text before Table 5; total 14063).
TABLE5_SECTOR_SAMPLES: tuple[int, ...] = (
    1243, 1239, 1136, 1095, 939, 1101, 928, 1183, 1142, 1331, 1279, 1447,
)
TABLE5_TOTAL_SAMPLES: int = 14063

# Utilisation tables in condition order (index = condition c).
S2_UTILISATION: tuple[UtilisationTable, ...] = (TABLE3_UTIL_DT_POS, TABLE4_UTIL_DT_NEG)
S3_UTILISATION: tuple[UtilisationTable, ...] = (
    TABLE5_UTIL_DT_POS_DPSI_POS,
    TABLE6_UTIL_DT_POS_DPSI_NEG,
    TABLE7_UTIL_DT_NEG_DPSI_POS,
    TABLE8_UTIL_DT_NEG_DPSI_NEG,
)


# ---------------------------------------------------------------------------
# Published switch tables.
# ---------------------------------------------------------------------------
# Seed section 4 (simplified strategy 2; spec "Strategies", s2 table):
# condition 0 = dT > 0, condition 1 = dT < 0; sectors theta_1..theta_6.
PUBLISHED_S2: SwitchTable = tuple(zip(*int_cells("""
#  dT > 0   |  dT < 0
    0 2 3 4 | 0 1 5 6
    0 3 4 5 | 0 1 2 6
    0 4 5 6 | 0 1 2 3
    0 1 5 6 | 0 2 3 4
    0 1 2 6 | 0 3 4 5
    0 1 2 3 | 0 4 5 6
""")))

# Seed section 5 (simplified strategy 3; spec "Strategies", s3 row): the only
# published s3 row, condition 0 = (dT > 0, dpsi > 0), sectors theta_1..theta_12.
# Sector 11 is garbled in the seed as "V0 V1 V1 V2"; the spec fixes it to
# {V0 V1 V2}.
PUBLISHED_S3_ROW: tuple[Cell, ...] = _cells("""
    0 2 3
    0 2 3 4
    0 3 4
    0 3 4 5
    0 4 5
    0 4 5 6
    0 5 6
    0 1 5 6
    0 1 6
    0 1 2 6
    0 1 2
    0 1 2 3
""")


# ---------------------------------------------------------------------------
# Table 9: IPMSM (section 6) performance per strategy (anchors only).
# ---------------------------------------------------------------------------
class Table9Row(NamedTuple):
    strategy: str  # "conventional", "s1", "s2", "s3"
    t_rip_nm: float  # T_rip RMSE, eq. (7)
    psi_rip_wb: float  # psi_rip RMSE, eq. (8)
    thd_percent: float  # THD of phase-a current / %
    cal_ave: float  # Cal_ave, eq. (10)
    f_ave_khz: float  # f_ave / kHz, eq. (9)


# Seed Table 9 (表9 电机系统性能).
TABLE9_IPMSM: tuple[Table9Row, ...] = records(Table9Row, split_rows("""
# strategy    | T_rip  | psi_rip | THD  | Cal  | f_ave
  conventional | 1.2668 | 0.0043  | 6.8  | 7    | 5.15
  s1           | 1.3894 | 0.0053  | 6.78 | 4.08 | 3.99
  s2           | 1.3793 | 0.0051  | 6.95 | 2.3  | 3.97
  s3           | 1.3953 | 0.0056  | 6.86 | 2.04 | 3.92
""", 6), (str, float, float, float, float, float))

# Seed text accompanying Table 9: zero-vector usage (%) per strategy.
TABLE9_ZERO_VECTOR_PERCENT: tuple[tuple[str, float], ...] = records(lambda s, p: (s, p), split_rows("""
  conventional | 34.42
  s1           | 45.65
  s2           | 46.00
  s3           | 46.02
""", 2), (str, float))


# ---------------------------------------------------------------------------
# The seed's motors and scenarios (section 3: SPMSM, Tables 1-8 and 10-11;
# section 6: IPMSM, Table 9).  Used to tell whether a config runs the
# paper's case (its published figures apply) or another one.
# ---------------------------------------------------------------------------
# Section 3 text (仿真用表面式永磁同步电机参数): 4 s, 80 000 samples of 50 us,
# 500 -> -500 r/min at 2 s, load 10 / -10 (1 s) / 10 (3 s) N*m.
SPMSM_MOTOR = SeedMotor(0.2, 0.0085, 0.0085, 0.175, 4)
SPMSM_DURATION_S = 4.0
# Section 6 text (内置式永磁同步电机): 2 s, 1000 -> -1000 r/min at 1 s, load
# 15 / -15 (0.5 s) / 15 (1.5 s) N*m, eps_T = 0.75 N*m.
IPMSM_MOTOR = SeedMotor(0.25, 0.0033, 0.0073, 0.2264, 3)
IPMSM_DURATION_S = 2.0


# ---------------------------------------------------------------------------
# Section 6 text after Table 9: the ratios the seed draws (strategy / conventional, %).
# ---------------------------------------------------------------------------
# "平均开关频率分别为传统模型预测转矩控制的 77.48%, 77.09% 和 76.12%"
TABLE9_F_AVE_RATIO_PERCENT: dict[str, float] = {"s1": 77.48, "s2": 77.09, "s3": 76.12}
# "平均遍历电压矢量个数分别为传统模型预测转矩控制的 58.29%, 32.86% 和 29.14%"
TABLE9_CAL_AVE_RATIO_PERCENT: dict[str, float] = {"s1": 58.29, "s2": 32.86, "s3": 29.14}


# ---------------------------------------------------------------------------
# Table 11 (表11 不同控制策略的计算耗时): SPMSM scenario on an STM32H743,
# 80 000 steps of each strategy (test cases of Table 10), times in ms.
# ---------------------------------------------------------------------------
class Table11Row(NamedTuple):
    strategy: str
    zero_outputs: int  # steps that output V0 directly (torque error within eps_T)
    predictions: int  # steps that ran the prediction loop (s3: 22456 with 3 + 25123 with 4 candidates)
    total_ms: float  # total computation time


TABLE11_TIMING: tuple[Table11Row, ...] = records(Table11Row, split_rows("""
# strategy    | V0 outputs | predictions | total / ms
  conventional | 0          | 80000       | 2592.4
  s1           | 34236      | 45764       | 1495.7
  s2           | 34115      | 45885       | 854.5
  s3           | 32421      | 47579       | 764.2
""", 4), (str, int, int, float))
TABLE11_STEPS = 80000
# Section 7 text: "计算总耗时分别为传统模型预测转矩控制的 57.70%, 32.96% 和 29.48%"
TABLE11_TIME_RATIO_PERCENT: dict[str, float] = {"s1": 57.70, "s2": 32.96, "s3": 29.48}

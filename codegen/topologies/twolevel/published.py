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

import math
from typing import NamedTuple

Cell = tuple[int, ...]
SwitchTable = tuple[tuple[Cell, ...], ...]
UtilisationTable = tuple[tuple[float, ...], ...]  # 7 rows (V0..V6) x sectors


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
TABLE1_ZERO_VECTOR_UTILISATION: tuple[Table1Row, ...] = (
    Table1Row(0.1, 6018, 4509, 74.93),
    Table1Row(0.2, 12153, 8913, 73.34),
    Table1Row(0.3, 18397, 13014, 70.74),
    Table1Row(0.4, 24714, 16669, 67.45),
    Table1Row(0.5, 30896, 19687, 63.72),
    Table1Row(0.6, 36874, 22101, 59.94),
    Table1Row(0.7, 42757, 23942, 56.00),
    Table1Row(0.8, 48384, 25349, 52.39),
    Table1Row(0.9, 53452, 26293, 49.19),
    Table1Row(1.0, 58233, 26962, 46.30),
    Table1Row(1.1, 62382, 27400, 43.92),
    Table1Row(1.2, 65930, 27700, 42.01),
    Table1Row(1.3, 68792, 27889, 40.54),
    Table1Row(1.4, 71166, 28017, 39.37),
    Table1Row(1.5, 73130, 28058, 38.37),
    Table1Row(math.inf, 80000, 28092, 35.12),  # "> 1.5": the whole run
)


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
TABLE2_THRESHOLD_SWEEP: tuple[Table2Row, ...] = (
    Table2Row(0.1, 0.9613, 0.0046, 6.49, 6.32),
    Table2Row(0.2, 0.9644, 0.0047, 5.97, 6.13),
    Table2Row(0.3, 0.9733, 0.0051, 5.42, 5.91),
    Table2Row(0.4, 0.9762, 0.0052, 4.85, 5.56),
    Table2Row(0.5, 0.9851, 0.0057, 4.38, 5.2),
    Table2Row(0.6, 1.0037, 0.0064, 4, 4.93),
    Table2Row(0.7, 1.0086, 0.0088, 3.62, 4.57),
    Table2Row(0.8, 0.9961, 0.0086, 2.87, 3.54),
    Table2Row(0.9, 0.9988, 0.0099, 2.35, 2.74),
    Table2Row(1.0, 1.0289, 0.0128, 2.16, 2.41),
    Table2Row(1.1, 1.076, 0.0171, 2.06, 2.16),
    Table2Row(1.2, 1.131, 0.0238, 1.99, 2),
    Table2Row(1.3, 1.193, 0.0297, 1.93, 1.88),
    Table2Row(1.4, 1.2601, 0.0349, 1.89, 1.8),
    Table2Row(1.5, 1.3273, 0.0392, 1.86, 1.73),
)

# Seed Table 2, last row "传统模型预测控制" (conventional MPTC, no threshold);
# band_nm = 0.0 (no zero-vector shortcut).
TABLE2_CONVENTIONAL: Table2Row = Table2Row(0.0, 0.9614, 0.0045, 7, 6.45)


# ---------------------------------------------------------------------------
# Tables 3-4: utilisation (%) of V0..V6 per 6-sector (eq. (11)), conventional
# MPTC, SPMSM scenario, samples with dT > 0.6 N*m (Table 3) and dT < -0.6 N*m
# (Table 4).  Rows V0..V6, columns theta_1..theta_6.
# ---------------------------------------------------------------------------
# Seed Table 3 (表3 电压矢量利用率, 转矩误差大于0.6 N·m).
TABLE3_UTIL_DT_POS: UtilisationTable = (
    (12.39, 8.14, 4.15, 3.24, 6.54, 11.55),  # V0
    (2.22, 0.05, 0.92, 17.57, 52.26, 21.13),  # V1
    (23.48, 2.32, 0, 0.61, 17.77, 45.39),  # V2
    (40.22, 22.1, 0.86, 0, 1.46, 18.42),  # V3
    (19.76, 46.14, 20.51, 0.58, 0.05, 1.5),  # V4
    (1.84, 19.43, 55.52, 19.71, 1.36, 0.09),  # V5
    (0.09, 1.82, 18.04, 58.29, 20.55, 1.92),  # V6
)
# Samples per sector behind Table 3 (seed text before Table 3; total 23875).
TABLE3_SECTOR_SAMPLES: tuple[int, ...] = (4510, 4005, 3471, 3460, 3961, 4468)
TABLE3_TOTAL_SAMPLES: int = 23875

# Seed Table 4 (表4 电压矢量利用率, 转矩误差小于-0.6 N·m).
TABLE4_UTIL_DT_NEG: UtilisationTable = (
    (3.07, 6.16, 10.59, 13.62, 11.37, 6.02),  # V0
    (18.53, 49.43, 21.05, 2.53, 0.03, 1.8),  # V1
    (1.28, 20.95, 40.15, 20.6, 1.73, 0.03),  # V2
    (0.03, 2.74, 23.15, 38.04, 19.84, 1.57),  # V3
    (1.03, 0, 2.3, 23.16, 44.52, 18.41),  # V4
    (19.38, 1.5, 0.08, 2.01, 20.2, 52.63),  # V5
    (56.67, 19.22, 2.67, 0.05, 2.31, 19.54),  # V6
)
# Samples per sector behind Table 4 (seed text before Table 4; total 21889).
TABLE4_SECTOR_SAMPLES: tuple[int, ...] = (3194, 3393, 3776, 4038, 3931, 3557)
TABLE4_TOTAL_SAMPLES: int = 21889


# ---------------------------------------------------------------------------
# Tables 5-8: utilisation (%) of V0..V6 per 12-sector (eq. (12)), conventional
# MPTC, SPMSM scenario, |dT| > 0.6 N*m split by the sign of the flux error.
# Rows V0..V6, columns theta_1..theta_12.
# ---------------------------------------------------------------------------
# Seed Table 5 (表5, dT > 0.6 N·m and dpsi > 0).
# NOTE (seed defect, kept as printed): column theta_5 sums to 94.20 %, and its
# V4/V5/V6 entries (18.41, 52.63, 19.54) are identical to Table 4 theta_6,
# which suggests a copy error in the seed.  It is also the one sector where
# the seed's published s3 set {V0 V4 V5} disagrees with its own numbers
# (V6 19.54 % > V4 18.41 %).
TABLE5_UTIL_DT_POS_DPSI_POS: UtilisationTable = (
    (16.65, 9.44, 8.8, 6.21, 3.62, 3.45, 4.85, 4.65, 12.96, 9.17, 18.22, 12.37),  # V0
    (0, 0, 0, 0, 0, 0, 1.83, 13.52, 43.96, 60.18, 42.14, 24.33),  # V1
    (46.1, 24.21, 0, 0, 0, 0, 0, 0, 2.1, 11.12, 38.31, 49.97),  # V2
    (34.84, 50.61, 48.15, 17.72, 0, 0, 0, 0, 0, 0, 1.33, 13.34),  # V3
    (2.41, 15.74, 40.05, 62.19, 18.41, 13.62, 0, 0, 0, 0, 0, 0),  # V4
    (0, 0, 2.99, 13.88, 52.63, 69.39, 43, 17.16, 0, 0, 0, 0),  # V5
    (0, 0, 0, 0, 19.54, 13.53, 50.32, 64.67, 40.98, 19.53, 0, 0),  # V6
)
# Samples per sector behind Table 5 (seed text before Table 5; total 14063).
TABLE5_SECTOR_SAMPLES: tuple[int, ...] = (
    1243, 1239, 1136, 1095, 939, 1101, 928, 1183, 1142, 1331, 1279, 1447,
)
TABLE5_TOTAL_SAMPLES: int = 14063

# Seed Table 6 (表6, dT > 0.6 N·m and dpsi < 0).  theta_9 V5 is printed "0%".
TABLE6_UTIL_DT_POS_DPSI_NEG: UtilisationTable = (
    (12.38, 18.37, 9.53, 11.68, 3.27, 6.33, 3.41, 8.9, 8.34, 17.34, 12.11, 21.9),  # V0
    (0, 0, 0, 0, 0, 0, 14.82, 43.48, 68.57, 36.48, 8, 1.31),  # V1
    (8.21, 1.43, 0, 0, 0, 0, 0, 0, 14.97, 45.1, 57.67, 30.83),  # V2
    (54.22, 31.57, 8.91, 1.48, 0, 0, 0, 0, 0, 0, 22.22, 45.97),  # V3
    (25.19, 48.62, 58.04, 40, 11.32, 0.97, 0, 0, 0, 0, 0, 0),  # V4
    (0, 0, 23.51, 46.85, 69.3, 47.4, 9.89, 1.03, 0, 0, 0, 0),  # V5
    (0, 0, 0, 0, 16.1, 45.29, 71.88, 46.58, 8.11, 1.08, 0, 0),  # V6
)

# Seed Table 7 (表7, dT < -0.6 N·m and dpsi > 0).
TABLE7_UTIL_DT_NEG_DPSI_POS: UtilisationTable = (
    (2.54, 6.39, 7.09, 13.28, 14.37, 14.1, 12.29, 16.92, 9.03, 13.39, 4.31, 8.18),  # V0
    (15.9, 44.47, 58.25, 30.32, 13.99, 2.46, 0, 0, 0, 0, 0, 0),  # V1
    (0, 0, 20.39, 53.22, 42.63, 31.48, 13.56, 2.9, 0, 0, 0, 0),  # V2
    (0, 0, 0, 0, 29.01, 51.96, 46.86, 37.65, 12.47, 2.46, 0, 0),  # V3
    (0, 0, 0, 0, 0, 0, 27.29, 42.53, 57.45, 45.18, 14.15, 2.34),  # V4
    (15.8, 2.05, 0, 0, 0, 0, 0, 0, 21.05, 38.98, 63.82, 50.8),  # V5
    (65.76, 47.09, 14.27, 3.18, 0, 0, 0, 0, 0, 0, 17.71, 38.68),  # V6
)

# Seed Table 8 (表8, dT < -0.6 N·m and dpsi < 0).
TABLE8_UTIL_DT_NEG_DPSI_NEG: UtilisationTable = (
    (8.46, 4.26, 17.18, 9.01, 22.86, 10.94, 24.01, 10.44, 19.02, 9.13, 15.22, 6.43),  # V0
    (1.21, 13.19, 37.29, 50, 44.44, 38.68, 0, 0, 0, 0, 0, 0),  # V1
    (0, 0, 0.98, 8.76, 30.69, 41.86, 45.1, 24.24, 0, 0, 0, 0),  # V2
    (0, 0, 0, 0, 2.01, 8.52, 29.84, 56.57, 41.6, 18.5, 0, 0),  # V3
    (0, 0, 0, 0, 0, 0, 1.05, 8.75, 38.65, 65.34, 43.23, 13.12),  # V4
    (45.42, 16.62, 0, 0, 0, 0, 0, 0, 0.74, 7.03, 40.33, 72.97),  # V5
    (44.91, 65.93, 44.55, 32.23, 0, 0, 0, 0, 0, 0, 1.22, 7.48),  # V6
)

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
PUBLISHED_S2: SwitchTable = (
    (  # dT > 0
        (0, 2, 3, 4),
        (0, 3, 4, 5),
        (0, 4, 5, 6),
        (0, 1, 5, 6),
        (0, 1, 2, 6),
        (0, 1, 2, 3),
    ),
    (  # dT < 0
        (0, 1, 5, 6),
        (0, 1, 2, 6),
        (0, 1, 2, 3),
        (0, 2, 3, 4),
        (0, 3, 4, 5),
        (0, 4, 5, 6),
    ),
)

# Seed section 5 (simplified strategy 3; spec "Strategies", s3 row): the only
# published s3 row, condition 0 = (dT > 0, dpsi > 0), sectors theta_1..theta_12.
# Sector 11 is garbled in the seed as "V0 V1 V1 V2"; the spec fixes it to
# {V0 V1 V2}.
PUBLISHED_S3_ROW: tuple[Cell, ...] = (
    (0, 2, 3),
    (0, 2, 3, 4),
    (0, 3, 4),
    (0, 3, 4, 5),
    (0, 4, 5),
    (0, 4, 5, 6),
    (0, 5, 6),
    (0, 1, 5, 6),
    (0, 1, 6),
    (0, 1, 2, 6),
    (0, 1, 2),
    (0, 1, 2, 3),
)


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
TABLE9_IPMSM: tuple[Table9Row, ...] = (
    Table9Row("conventional", 1.2668, 0.0043, 6.8, 7, 5.15),
    Table9Row("s1", 1.3894, 0.0053, 6.78, 4.08, 3.99),
    Table9Row("s2", 1.3793, 0.0051, 6.95, 2.3, 3.97),
    Table9Row("s3", 1.3953, 0.0056, 6.86, 2.04, 3.92),
)

# Seed text accompanying Table 9: zero-vector usage (%) per strategy.
TABLE9_ZERO_VECTOR_PERCENT: tuple[tuple[str, float], ...] = (
    ("conventional", 34.42),
    ("s1", 45.65),
    ("s2", 46.00),
    ("s3", 46.02),
)

"""T-type three-level inverter derivations for MPDTC (mpdtc-three-level.md, seed 000).

Pure-Python, derived once at import: the 27 switching states and 19 basic
vectors (``vectors``), the 24 small triangles and 36 seven-segment virtual
vectors (``virtual``), the switching constraint (``transitions``), the
63-MPDTC candidate table (``candidates``), the seed's published Table 3
(``published``) and a text report comparing both (``report``).
"""

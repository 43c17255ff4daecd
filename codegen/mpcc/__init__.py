"""Long-horizon finite-control-set current control with a sphere decoder, shared by every topology.

The strategy family of issue 31 (docs/mpcc.md): the exactly discretised alpha-beta model of a surface
PMSM (``lattice``), the cost as an integer least-squares problem ||H U - U_bar||^2 with H upper
triangular, derived once in float64 and rounded once (``tables``), the generated C of the step and
its depth-first sphere decoder (``render``, templates/mpcc/), and the independent numpy reference:
the same search vectorised over lanes and an exhaustive enumeration of the same float32 objective
(``reference``, ``exhaustive``).  A topology supplies only its alphabet of per-phase positions, its
jump rule, how its input gives the DC link and the applied positions and how its output encodes the
decision (an :class:`codegen.mpcc.tables.Adapter`); this package never names a topology.
"""

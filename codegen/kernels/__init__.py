"""Controller kernels written once, shared by every topology's Python reference.

Each kernel computes through the number format's operation helpers
(:class:`codegen.numfmt.Ops`), one helper per C operation in the C's order;
``templates/common/kernels.j2`` holds the same kernels as jinja2 macros (the
independent C implementation).
"""

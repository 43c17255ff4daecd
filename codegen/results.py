"""JSON-ready results every stage and topology writes: cleaning, versions, table cells."""
from __future__ import annotations

import math
import platform
from typing import Any

import numpy as np

from codegen import __version__

__all__ = ["clean_json", "versions", "fmt_cell"]


def clean_json(v: Any) -> Any:
    """JSON-safe: NaN/inf -> None, numpy scalars -> Python, recursively."""
    if isinstance(v, dict):
        return {k: clean_json(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [clean_json(x) for x in v]
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def versions() -> dict[str, str]:
    """Versions that determine the results."""
    import cffi
    import scipy

    return {"mpcgen": __version__, "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "cffi": cffi.__version__}


def fmt_cell(v: Any, spec: str) -> str:
    """A table cell: ``format(v, spec)``, or ``n/a`` for a missing or non-finite value."""
    return "   n/a" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)

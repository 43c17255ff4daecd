"""Where the templates and firmware sources are, in a checkout or installed.

The repository keeps them at the top level (``templates/``, ``firmware/``);
the installed package ships them as ``codegen.templates`` and
``codegen.firmware`` (pyproject.toml package-dir), i.e. as the directories
codegen/templates/ and codegen/firmware/ of the installed ``codegen``
package.  Both are found through importlib.resources, so the installed
package works outside the repository.
"""
from __future__ import annotations

import importlib.resources
from pathlib import Path


def _package_dir(package: str, fallback: str) -> Path:
    """The data directory shipped as ``package`` (installed) or ``<repo>/<fallback>`` (checkout).

    The directory is looked up inside the ``codegen`` package rather than by
    importing ``package``: ``codegen.firmware`` is also the name of the module
    codegen/firmware.py (firmware projects), which wins over the data
    directory on import.
    """
    sub = package.rsplit(".", 1)[-1]
    try:
        path = Path(str(importlib.resources.files("codegen"))) / sub
        if path.is_dir():
            return path
    except (ModuleNotFoundError, TypeError):
        pass
    # running from a checkout without installing: <repo>/<fallback>
    here = Path(__file__).resolve().parent.parent / fallback
    if here.is_dir():
        return here
    raise FileNotFoundError(f"cannot find the {fallback}/ directory (package {package})")


def templates_dir() -> Path:
    """Directory holding the jinja2 templates."""
    return _package_dir("codegen.templates", "templates")


def firmware_dir() -> Path:
    """Directory holding the hand-written firmware sources."""
    return _package_dir("codegen.firmware", "firmware")

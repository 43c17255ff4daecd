"""The topology registry: the one place that names the topology plugins.

Each ``inverter.topology`` value maps to a plugin package under
``codegen/topologies/``.  A package has two entry modules, both loaded by
name so that no layer below the plugins imports a topology package:

- ``<package>.section``: its part of the configuration (its strategies, its
  own config fields with their checks, its load-time consistency checks and
  artefacts); read by :mod:`codegen.config` while a file is loaded;
- ``<package>.plugin``: the :class:`codegen.topology.Topology` facets every
  stage calls.

Adding a topology is one line here (``docs/architecture.md``, "Adding a
topology").
"""
from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["TOPOLOGY_PACKAGES", "topology_names", "topology_module"]

#: ``inverter.topology`` value -> the topology's plugin package
TOPOLOGY_PACKAGES: dict[str, str] = {
    "two-level": "codegen.topologies.twolevel",
    "t-type": "codegen.topologies.ttype",
}


def topology_names() -> tuple[str, ...]:
    """Every ``inverter.topology`` value, in registry order."""
    return tuple(TOPOLOGY_PACKAGES)


def topology_module(name: str, module: str) -> ModuleType:
    """Module ``module`` (``"section"`` or ``"plugin"``) of topology ``name``'s package."""
    try:
        package = TOPOLOGY_PACKAGES[name]
    except KeyError:
        raise ValueError(f"unknown topology {name!r}; allowed: {', '.join(TOPOLOGY_PACKAGES)}") from None
    return importlib.import_module(f"{package}.{module}")

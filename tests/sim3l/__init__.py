"""Closed-loop simulator, plant, metrics and plot tests (a package, so its conftest
does not shadow tests/conftest.py, which other tests import as ``conftest``)."""

"""Tests of each topology's package (a package, so that equal basenames in
twolevel/ and ttype/ do not clash and their conftests do not shadow
tests/conftest.py, which other tests import as ``conftest``)."""

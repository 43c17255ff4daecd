"""Shared helpers of the HIL tests: the example models with their tables (from tests/conftest.py)."""
from __future__ import annotations

from conftest import CASE_IDS, CASES, ROOT, SPMSM, example
from conftest import TTYPE as TLEVEL

__all__ = ["CASES", "CASE_IDS", "ROOT", "SPMSM", "TLEVEL", "example"]


def run_mode(board, mode, m, t):  # type: ignore[no-untyped-def]
    """``mode(session, m, t)`` on a board running ``m``'s controller, after the handshake."""
    from hil.schema import Schema
    from hil.session import Session

    with board(m, t) as link:
        session = Session(link, Schema.of(m))
        session.handshake()
        return mode(session, m, t, show_progress=False)

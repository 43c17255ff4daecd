"""The generated long-horizon step against its Python reference, bit for bit (every output field:
the sequence, U_bar, the distance and the decoder's node count and budget events), for every horizon
1..6 of both topologies, with and without delay compensation (two-level) and with a budget that binds."""
from __future__ import annotations

import pytest

from codegen.stages.verify import verify_strategy

from .helpers import mpcc_model

CASES = [("spmsm", {"horizon": n}) for n in range(1, 7)] + [("tlevel", {"horizon": n}) for n in range(1, 7)] + [
    ("spmsm", {"horizon": 3, "delay_compensation": False}), ("spmsm", {"horizon": 4, "node_budget": 30}),
    ("tlevel", {"horizon": 2, "node_budget": 7})]


@pytest.mark.parametrize("config, overrides", CASES, ids=[f"{c}-{'-'.join(f'{k}{v}' for k, v in o.items())}"
                                                          for c, o in CASES])
def test_c_equals_reference(config: str, overrides: dict[str, object]):
    m = mpcc_model(config, **overrides)
    r = verify_strategy(m, 12_000, log=lambda s: None, closed_loop=False)
    assert r.mismatches == 0, r.first_mismatch
    assert r.states == 12_000 and r.faulted_states < r.states // 4

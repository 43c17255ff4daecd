"""The two-level adversarial states that put the stator flux on a sector border do put it there: the
flux the step takes its sector from (psi(k), or psi(k+1) with delay compensation)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.config import load_config
from codegen.teststates import in_format
from codegen.topologies.twolevel import states
from codegen.topology import topology_of

from conftest import EXAMPLES, SPMSM


@pytest.mark.parametrize("path,over", [
    (SPMSM, {}),
    (SPMSM, {"controller.delay_compensation": True}),
    (EXAMPLES / "servo400w.toml", {}),
], ids=["spmsm", "spmsm-compensated", "servo400w"])
def test_flux_lands_on_a_sector_border(path, over):
    m = load_config(path, {"controller.strategy": "s3", "controller.tables": "published", **over})
    topo = topology_of(m)
    t = topo.derive(m)
    rng = np.random.default_rng(4)
    x = states.random_states(m, 5000, seed=5)
    x["udc_v"] = m.inverter.udc_v
    x["prev_sw"] = rng.integers(0, 8, len(x))
    x["theta_e_rad"] = rng.uniform(0, 2 * math.pi, len(x))
    states.place_flux_on_border(m, x, 0.1, rng)
    out = topo.step_batch(t, in_format(x, states.INPUT.bind(t.nf)))
    ang = np.arctan2(out["psi_beta_wb"].astype(np.float64), out["psi_alpha_wb"].astype(np.float64))
    dist = np.abs((ang + math.pi / 12) % (math.pi / 6) - math.pi / 12)
    ok = out["fault"] == 0
    assert ok.sum() > 1000  # (flux at psi_ref +- 10 % may need currents beyond the trip limit)
    assert np.mean(dist[ok] < 1e-5) > 0.9, np.median(dist[ok])

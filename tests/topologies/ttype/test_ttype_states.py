"""The T-type adversarial states that put u* on a sector border do put it there (both formats)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.config import load_config
from codegen.teststates import in_format
from codegen.topologies.ttype import states
from codegen.topology import topology_of

from conftest import TTYPE


@pytest.mark.parametrize("fmt", ["float32", "fixed"])
def test_u_ref_lands_on_a_sector_border(fmt):
    m = load_config(TTYPE, {"controller.strategy": "mpdtc63", "controller.number_format": fmt})
    topo = topology_of(m)
    t = topo.derive(m)
    rng = np.random.default_rng(3)
    x = states._nominal(m, 5000, rng)
    states._on_sector_border(m, x, rng)
    out = topo.step_batch(t, in_format(x, states.INPUT.bind(t.nf)))
    lay = topo.output_record(m).bind(t.nf)
    ang = np.arctan2(lay.decode("u_ref_beta_v", out["u_ref_beta_v"]), lay.decode("u_ref_alpha_v", out["u_ref_alpha_v"]))
    dist = np.abs((ang + math.pi / 12) % (math.pi / 6) - math.pi / 12)  # to the nearest 30-degree border
    ok = out["fault"] == 0
    assert ok.mean() > 0.9
    assert np.mean(dist[ok] < 1e-5) > 0.9 and np.median(dist[ok]) < 2e-6

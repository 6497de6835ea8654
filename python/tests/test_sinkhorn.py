"""penumbra's entropic optimal transport (src/core/sinkhorn.h) against POT's log-domain Sinkhorn on a small
5-D problem at the same eps: both converged, the plans and the barycentric matches agree to the float precision
of penumbra's exponentials (measured: plan L1 difference 1e-7 at 16^2, docs/losses.md)."""
import numpy as np
import pytest

import penumbra
from penumbra import _penumbra

ot = pytest.importorskip("ot")


def test_plan_and_matching_agree_with_pot():
    rng = np.random.default_rng(16)
    x, y = rng.random((60, 5)), rng.random((50, 5))
    a, b = rng.uniform(0.5, 2, 60), rng.uniform(0.5, 2, 50)
    blur = 0.1
    r = _penumbra.sinkhorn(x, a, y, b, blur=blur, tolerance=1e-7, max_iterations=10000, threads=2, plan=True)
    assert r["marginal_error"] < 1e-7  # the float-exp floor of this problem: 3e-8 (measured)
    cost = 0.5 * ot.dist(x, y, metric="sqeuclidean")
    plan = ot.bregman.sinkhorn_log(a / a.sum(), b / b.sum(), cost, blur**2, numItermax=10000, stopThr=1e-12)
    assert np.abs(r["plan"] - plan).sum() < 1e-6
    match = (plan @ y) / plan.sum(1)[:, None]
    assert np.abs(r["matched"] - match).max() < 1e-6


def test_bad_input_raises_penumbra_error():
    x = np.zeros((4, 5))
    with pytest.raises(penumbra.Error, match="blur must be positive"):
        _penumbra.sinkhorn(x, np.ones(4), x, np.ones(4), blur=0.0)
    with pytest.raises(penumbra.Error, match="4 points but 3 weights"):
        _penumbra.sinkhorn(x, np.ones(3), x, np.ones(4))

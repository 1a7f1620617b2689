"""The compiled pre-gate and PDA mixture update give the NumPy reference's numbers exactly (bit for bit),
and the pre-gate drops no validated pair (against a dense evaluation without it)."""

import numpy as np
import pytest

from sonartrack.association import likelihood
from sonartrack.association.jpda import jpda_log_weights
from sonartrack.association.likelihood import position_likelihoods, window_likelihoods
from sonartrack.association.pda import pda_mixture_update, pda_update, pda_weights
from sonartrack.association.pda_kernel import pda_update_fast
from sonartrack.association.pda_mixture_kernel import pda_mixture_update_fast


def _scan(rng, n: int, r: int, m: int, shared_R: bool):
    """n tracks x r modes scattered over 2 km, m measurements near them and in clutter."""
    x = np.zeros((n, r, 4))
    x[:, :, :2] = rng.uniform(-1000, 1000, (n, 1, 2)) + rng.normal(0, 20, (n, r, 2))
    x[:, :, 2:] = rng.normal(0, 3, (n, r, 2))
    A = rng.normal(size=(n, r, 4, 4))
    P = A @ np.swapaxes(A, -1, -2) * 30 + np.diag([900.0, 900.0, 9.0, 9.0])
    near = x[rng.integers(0, n, m // 2), 0, :2] + rng.normal(0, 40, (m // 2, 2))
    z = np.concatenate([near, rng.uniform(-1100, 1100, (m - m // 2, 2))])
    if shared_R:
        return x, P, z, np.array([[400.0, 80.0], [80.0, 250.0]])
    B = rng.normal(size=(m, 2, 2)) * 8
    return x, P, z, B @ np.swapaxes(B, -1, -2) + np.eye(2) * 100


def _assert_same(a, b):
    for name in a.__dataclass_fields__:
        u, v = getattr(a, name), getattr(b, name)
        assert np.array_equal(u, v), name


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("r", [1, 3])
def test_compiled_pregate_equals_numpy_pregate(seed, r):
    rng = np.random.default_rng(seed)
    x, P, z, R = _scan(rng, int(rng.integers(8, 30)), r, int(rng.integers(35, 60)), shared_R=seed % 2 == 0)
    rho = rng.uniform(1e-6, 1e-5, len(z)) if seed % 3 else 2e-6
    kw = dict(pd=0.8, pg=0.99, gamma=9.21, clutter_density=rho)
    assert len(x) * len(z) > likelihood.PREGATE_MIN_PAIRS  # the pre-gated path is the one under test
    compiled, numpy = position_likelihoods(x, P, z, R, **kw), position_likelihoods(x, P, z, R, **kw, compiled=False)
    _assert_same(compiled, numpy)
    assert compiled.gated.sum() > len(x)  # a real test: pairs were validated


@pytest.mark.parametrize("seed", range(4))
def test_pregate_keeps_every_validated_pair(seed, monkeypatch):
    rng = np.random.default_rng(100 + seed)
    x, P, z, R = _scan(rng, 25, 2, 50, shared_R=False)
    kw = dict(pd=0.8, pg=0.99, gamma=9.21, clutter_density=1e-6)
    pregated = position_likelihoods(x, P, z, R, **kw)
    monkeypatch.setattr(likelihood, "PREGATE_MIN_PAIRS", 10**9)  # every pair evaluated
    dense = position_likelihoods(x, P, z, R, **kw)
    assert np.array_equal(pregated.gated, dense.gated)
    assert dense.gated.sum() > 25  # a real test: pairs were validated
    t, j = np.nonzero(dense.gated)
    np.testing.assert_allclose(pregated.log_ratio[t, :, j], dense.log_ratio[t, :, j], rtol=1e-13)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("r", [1, 2, 3])
def test_compiled_mixture_update_equals_numpy(seed, r):
    rng = np.random.default_rng(seed)
    x, P, z, R = _scan(rng, int(rng.integers(1, 25)), r, int(rng.integers(0, 50)), shared_R=seed % 2 == 1)
    lik = position_likelihoods(x, P, z, R, pd=0.8, pg=0.99, gamma=9.21, clutter_density=3e-6)
    w = pda_weights(lik)
    for u, v in zip(pda_mixture_update_fast(x, P, lik, w.beta0, w.beta), pda_mixture_update(x, P, lik, w.beta0, w.beta),
                    strict=True):
        assert np.array_equal(u, v)


@pytest.mark.parametrize("seed", range(4))
def test_compiled_mixture_update_equals_numpy_for_jpda_bearings(seed):
    """One scalar measurement (k = 1) and JPDA weights, as the bearing tracker uses them."""
    rng = np.random.default_rng(seed)
    n, m = 3, int(rng.integers(1, 12))
    x = np.stack([rng.uniform(40, 60, n), rng.normal(0, 0.2, n)], -1)[:, None]  # (n, 1, 2): deg, deg/s
    P = np.broadcast_to(np.array([[2.0, 0.5], [0.5, 0.3]]), (n, 1, 2, 2)).copy()
    z = rng.uniform(35, 65, m)
    lik = window_likelihoods(x, P, z, np.full(n, 1.5), gate_width=10.0, pd_hit=np.full(n, 0.9),
                             pd_miss=np.full(n, 0.9), clutter_density=0.03)
    ll = np.where(lik.gated, np.log(lik.pd)[:, None] + lik.log_ratio[:, 0], -np.inf)
    beta = np.exp(jpda_log_weights(ll, np.log(lik.miss[:, 0])))
    beta0, beta_m = beta[:, :1], beta[:, None, 1:]
    for u, v in zip(pda_mixture_update_fast(x, P, lik, beta0, beta_m), pda_mixture_update(x, P, lik, beta0, beta_m),
                    strict=True):
        assert np.array_equal(u, v)


def test_single_track_kernel_reads_a_shared_R_and_rho_as_the_repeated_ones():
    rng = np.random.default_rng(3)
    x, P, z, R = _scan(rng, 1, 1, 30, shared_R=True)
    x, P = x[0, 0], P[0, 0]
    kw = dict(pd=0.85, pg=0.99, gamma=9.21)
    shared = pda_update_fast(x, P, z, R, **kw, clutter_density=1e-6)
    repeated = pda_update_fast(x, P, z, np.repeat(R[None], len(z), 0), **kw, clutter_density=np.full(len(z), 1e-6))
    for u, v in zip(shared, repeated, strict=True):
        assert np.array_equal(u, v)
    np.testing.assert_allclose(shared[0], pda_update(x, P, z, R, **kw, clutter_density=1e-6)[0], rtol=1e-12)
    with pytest.raises(ValueError):
        pda_update_fast(x, P, z, R, **kw, clutter_density=np.full(len(z) - 1, 1e-6))

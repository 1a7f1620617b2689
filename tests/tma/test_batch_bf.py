"""Bearings + frequency batch ML (tma/batch_bf.py): Jacobian, exact recovery, CRB efficiency, and range
observability without an ownship maneuver."""

import numpy as np
import pytest

from sonartrack.tma.batch_bf import (
    bf_model,
    bf_profile_rise,
    bf_start,
    crb_bf,
    fisher_information_bf,
    ml_bearings_frequency,
)
from sonartrack.tma.batch_ml import fisher_information

C = 1500.0
SIG_B = np.deg2rad(0.5)
SIG_F = 0.05


def _ownship(t, turn_s=None):
    """4 m/s north, turning to east at ``turn_s`` (None: one straight leg)."""
    v = np.where((turn_s is not None) & (t[:, None] >= (turn_s or 0.0)), [4.0, 0.0], [0.0, 4.0])
    dt = np.diff(t, prepend=t[0])
    xy = np.cumsum(v * dt[:, None], axis=0)
    return xy, v.astype(float)


def _record(x_true, t, own, ov, rng=None):
    h_b, h_f, _, _ = bf_model(x_true, t - t[0], own, ov, C)
    if rng is None:
        return h_b, h_f
    return h_b + SIG_B * rng.standard_normal(len(t)), h_f + SIG_F * rng.standard_normal(len(t))


X_TRUE = np.array([3000.0, 5000.0, -3.0, 1.0, 200.0])


def test_jacobian_matches_finite_differences():
    t = np.arange(0.0, 600.0, 10.0)
    own, ov = _ownship(t, turn_s=300.0)
    _, _, H_b, H_f = bf_model(X_TRUE, t, own, ov, C)
    steps = np.array([1e-2, 1e-2, 1e-5, 1e-5, 1e-6])
    num_b, num_f = np.empty_like(H_b), np.empty_like(H_f)
    for k, s in enumerate(steps):
        dx = np.zeros(5)
        dx[k] = s
        bp, fp, _, _ = bf_model(X_TRUE + dx, t, own, ov, C)
        bm, fm, _, _ = bf_model(X_TRUE - dx, t, own, ov, C)
        num_b[:, k], num_f[:, k] = (bp - bm) / (2 * s), (fp - fm) / (2 * s)
    np.testing.assert_allclose(H_b, num_b, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(H_f, num_f, rtol=1e-6, atol=1e-9)


def test_frequency_model_is_the_doppler_of_the_range_rate():
    """h_f = f0 (1 - rdot / c) with rdot the numerical derivative of the range."""
    t = np.arange(0.0, 600.0, 1.0)
    own, ov = _ownship(t)
    _, h_f, _, _ = bf_model(X_TRUE, t, own, ov, C)
    r = np.hypot(X_TRUE[0] + X_TRUE[2] * t - own[:, 0], X_TRUE[1] + X_TRUE[3] * t - own[:, 1])
    rdot = np.gradient(r, t)
    np.testing.assert_allclose(h_f[1:-1], X_TRUE[4] * (1 - rdot[1:-1] / C), atol=1e-6)


@pytest.mark.parametrize("turn_s", [300.0, None])
def test_noise_free_record_recovers_the_truth(turn_s):
    t = np.arange(0.0, 900.0, 5.0)
    own, ov = _ownship(t, turn_s)
    z, f = _record(X_TRUE, t, own, ov)
    start = bf_start(X_TRUE[:4], f, own[0], ov[0], scale=1.6)
    est = ml_bearings_frequency(z, f, t, own, ov, SIG_B, SIG_F, start, c_mps=C)
    assert est.converged
    np.testing.assert_allclose(est.x0, X_TRUE, atol=1e-6)


def test_straight_leg_bearings_only_is_singular_but_bearings_frequency_determines_range():
    """One straight leg: the bearings' Fisher information is singular (the scaled track fits as well) while the
    frequencies fix the scale, f = f0 - (f0 k / c) g(t) with g varying (module docstring)."""
    t = np.arange(0.0, 1200.0, 5.0)
    own, ov = _ownship(t)
    J4 = fisher_information(X_TRUE[:4], t, own, SIG_B)
    ev = np.linalg.eigvalsh(J4)
    assert ev[0] / ev[-1] < 1e-12
    # the null direction is the scaling of the relative track about the ownship
    scale_dir = np.concatenate([X_TRUE[:2] - own[0], X_TRUE[2:4] - ov[0]])
    assert np.linalg.norm(J4 @ scale_dir) / (np.linalg.norm(J4) * np.linalg.norm(scale_dir)) < 1e-9
    P = crb_bf(X_TRUE, t, own, ov, SIG_B, SIG_F, C)
    d = X_TRUE[:2] - own[0]
    r0 = np.linalg.norm(d)
    sd_r = float(np.sqrt(d @ P[:2, :2] @ d) / r0)
    assert sd_r < 0.2 * r0


def test_closed_form_scale_from_the_frequency_line():
    """Independent of the ML: on a straight leg, the bearings-only track of scale 1 and a line fitted to
    (g, f) give k and f0; k times the scale-1 track is the ML's (noise-free)."""
    t = np.arange(0.0, 1200.0, 5.0)
    own, ov = _ownship(t)
    z, f = _record(X_TRUE, t, own, ov)
    k_true = 0.37  # a wrong scale of the relative track, as the bearings alone may give
    d1 = X_TRUE[:2] - own[0]
    prime = np.concatenate([own[0] + k_true * d1, ov[0] + k_true * (X_TRUE[2:4] - ov[0])])
    dp = prime[:2] + prime[2:4] * t[:, None] - own
    np.testing.assert_allclose(np.arctan2(dp[:, 0], dp[:, 1]), z, atol=1e-9)  # same bearings
    g = np.gradient(np.hypot(dp[:, 0], dp[:, 1]), t)
    slope, f0 = np.polyfit(g[1:-1], f[1:-1], 1)
    k = -slope * C / f0  # f = f0 (1 - k g / c): the scale from the prime track to the truth
    start = bf_start(prime, f, own[0], ov[0])
    est = ml_bearings_frequency(z, f, t, own, ov, SIG_B, SIG_F, start, c_mps=C)
    assert abs(k * k_true - 1.0) < 1e-3  # the closed form finds the truth
    np.testing.assert_allclose(est.x0[:2], own[0] + k * (prime[:2] - own[0]), rtol=1e-3)
    np.testing.assert_allclose(est.x0[4], f0, rtol=1e-5)


def test_constant_bearing_target_is_not_observable():
    """A target closing on a constant bearing: g is constant, the frequency line has no slope to give k."""
    t = np.arange(0.0, 1200.0, 5.0)
    own, ov = _ownship(t)
    x = np.array([0.0, 8000.0, 0.0, 4.0 - 3.0, 200.0])  # dead ahead, closing along the line of sight
    ev = np.linalg.eigvalsh(fisher_information_bf(x, t, own, ov, SIG_B, SIG_F, C))
    assert ev[0] / ev[-1] < 1e-12


def test_monte_carlo_covariance_agrees_with_the_crb():
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 900.0, 5.0)
    own, ov = _ownship(t, turn_s=450.0)
    P = crb_bf(X_TRUE, t, own, ov, SIG_B, SIG_F, C)
    runs = 200
    err = np.empty((runs, 5))
    for i in range(runs):
        z, f = _record(X_TRUE, t, own, ov, rng)
        est = ml_bearings_frequency(z, f, t, own, ov, SIG_B, SIG_F, bf_start(X_TRUE[:4], f, own[0], ov[0]), c_mps=C)
        err[i] = est.x0 - X_TRUE
    assert np.all(np.abs(err.mean(axis=0)) < 4 * np.sqrt(np.diag(P) / runs))
    # NEES: the sum over runs of e^T P^-1 e is chi-square(5 runs) for an efficient estimator; its 99.9 % interval
    from scipy.stats import chi2

    nees = float(np.einsum("ni,ij,nj->", err, np.linalg.inv(P), err))
    assert chi2.ppf(0.0005, 5 * runs) < nees < chi2.ppf(0.9995, 5 * runs)
    ratio = np.var(err, axis=0) / np.diag(P)
    assert np.all((ratio > 0.7) & (ratio < 1.35))


def test_profile_rise_is_zero_at_the_fit_and_large_where_the_range_is_determined():
    t = np.arange(0.0, 1200.0, 5.0)
    own, ov = _ownship(t)
    z, f = _record(X_TRUE, t, own, ov)
    end = np.concatenate([X_TRUE[:2] + X_TRUE[2:4] * t[-1], X_TRUE[2:]])
    r = float(np.hypot(*(end[:2] - own[-1])))
    assert bf_profile_rise(t, z, f, own, ov, SIG_B, SIG_F, end, r, C) < 1e-6
    P = crb_bf(X_TRUE, t, own, ov, SIG_B, SIG_F, C)
    assert np.sqrt(P[0, 0]) < r  # determined: 2 r is many sd away
    assert bf_profile_rise(t, z, f, own, ov, SIG_B, SIG_F, end, 2 * r, C) > 100

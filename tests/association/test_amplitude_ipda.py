"""Amplitude likelihood ratio for IPDA (association/amplitude_ipda.py): the closed forms against scipy's densities
and Lerro & Bar-Shalom's Rayleigh-envelope form, the clutter law's fit on samples drawn here by inverse CDF, and the
mean of the ratio on clutter (<= 1: what keeps Ville's bound on the false confirmed tracks)."""

import numpy as np
import pytest
from scipy import integrate, stats

from sonartrack.association.amplitude_ipda import (
    AmplitudeModel,
    exponential_excess_log_ratio,
    gpd_log_pdf,
    lomax_log_pdf,
)


def test_swerling1_in_rayleigh_clutter_matches_the_envelope_form():
    # Lerro & Bar-Shalom 1993: envelope A Rayleigh with power 1 (clutter) or 1 + d (target), detected when
    # A > t; the ratio of the truncated envelope densities, by scipy, equals the closed form on the power a = A^2 / 2
    # (the Jacobian dA/da is the same for both and cancels)
    d, t = 10 ** (15 / 10), 4.0  # 15 dB, threshold on the envelope
    A = np.linspace(t, 30.0, 50)
    p1 = stats.rayleigh.pdf(A, scale=np.sqrt(1 + d)) / stats.rayleigh.sf(t, scale=np.sqrt(1 + d))
    p0 = stats.rayleigh.pdf(A, scale=1.0) / stats.rayleigh.sf(t, scale=1.0)
    y = A**2 / 2 - t**2 / 2
    assert exponential_excess_log_ratio(y, 1 + d, 1.0) == pytest.approx(np.log(p1 / p0), rel=1e-9, abs=1e-9)


def test_equal_laws_give_a_ratio_of_one():
    assert exponential_excess_log_ratio([0.0, 3.0, 50.0], 7.0, 7.0) == pytest.approx(0.0)


def test_densities_against_scipy():
    y = np.array([0.0, 0.3, 2.0, 40.0])
    assert gpd_log_pdf(y, 3.0, 0.2) == pytest.approx(stats.genpareto.logpdf(y, 0.2, scale=3.0))
    assert gpd_log_pdf(y, 3.0, 0.0) == pytest.approx(stats.expon.logpdf(y, scale=3.0))
    assert lomax_log_pdf(y, 4.0, 9.0) == pytest.approx(stats.lomax.logpdf(y, 4.0, scale=9.0))


def test_lomax_is_the_exponential_mixed_over_the_inverse_gamma_posterior():
    a, b = 3.5, 20.0
    for y in (0.5, 5.0, 30.0):
        mixed, _ = integrate.quad(lambda m, y=y: stats.expon.pdf(y, scale=m) * stats.invgamma.pdf(m, a, scale=b), 0,
                                  np.inf)
        assert np.exp(lomax_log_pdf(y, a, b)) == pytest.approx(mixed, rel=1e-6)


def gpd_sample(rng, n, scale, shape, floor):
    """Generalised Pareto excesses above ``floor`` by inverse CDF: y = s ((1 - u)^-xi - 1) / xi."""
    u = rng.uniform(size=n)
    return floor + scale * ((1 - u) ** -shape - 1) / shape


def fed(model, rng, scans, per_scan, scale, shape, floor=20.0):
    for _ in range(scans):
        model.add_scan(gpd_sample(rng, per_scan, scale, shape, floor))
    return model


def test_clutter_law_recovers_a_heavy_tail_and_an_exponential_one():
    rng = np.random.default_rng(3)
    m = fed(AmplitudeModel(10.0, 5.0, 200, 2.0, 2.0, 1e9), rng, 200, 100, 8.0, 0.25)
    scale, shape = m.clutter_law()
    assert shape == pytest.approx(0.25, abs=0.06) and scale == pytest.approx(8.0, rel=0.12)
    assert m.floor == pytest.approx(20.0, abs=0.05)
    m = AmplitudeModel(10.0, 5.0, 200, 2.0, 2.0, 1e9)
    for _ in range(200):
        m.add_scan(20.0 + rng.exponential(5.0, 100))
    scale, shape = m.clutter_law()
    assert shape < 0.03 and scale == pytest.approx(5.0, rel=0.1)


def test_the_prior_alone_and_forgetting():
    m = AmplitudeModel(10.0, 20.0, 5, 2.0, 2.0, 30.0)
    assert m.clutter_law() == pytest.approx((10.0, 0.0))  # no scan yet: the exponential prior
    m.add_scan(np.array([20.0]))
    m.add_scan(np.full(1000, 50.0))
    assert m.clutter_law()[0] > 20.0
    for _ in range(5):  # 5 scans kept: after 5 empty ones only the prior is left
        m.add_scan(np.zeros(0))
    assert m.clutter_law() == pytest.approx((10.0, 0.0))


@pytest.mark.parametrize("shape", [0.0, 0.3])
def test_the_mean_ratio_on_clutter_is_at_most_one(shape):
    # Ville's bound on the existence odds needs E_clutter[r] <= 1: clutter drawn from the law the model fitted,
    # the ratio of a new track (prior target law) and of a track that has seen a few strong echoes
    rng = np.random.default_rng(11)
    m = AmplitudeModel(10.0, 20.0, 30, 2.0, 2.0, 30.0)
    for _ in range(100):
        m.add_scan(20.0 + (rng.exponential(6.0, 30) if shape == 0.0 else gpd_sample(rng, 30, 6.0, shape, 0.0)))
    a = 20.0 + (rng.exponential(6.0, 200_000) if shape == 0.0 else gpd_sample(rng, 200_000, 6.0, shape, 0.0))
    for w, s in ((0.0, 0.0), (3.0, 3 * 60.0)):
        r = np.exp(m.log_ratio(a, np.full(len(a), w), np.full(len(a), s)))
        assert r.mean() < 1.03, (w, r.mean())
    # and a strong target's echoes raise it: mean excess 40 against clutter's 6
    y = 20.0 + rng.exponential(40.0, 20_000)
    assert np.mean(m.log_ratio(y, np.full(len(y), 5.0), np.full(len(y), 5 * 60.0))) > 1.0


def test_target_posterior_floor_and_prior():
    m = AmplitudeModel(10.0, 20.0, 30, 2.0, 2.0, 30.0)
    alpha, beta = m.target_posterior(np.array([0.0, 4.0]), np.array([0.0, 4.0 * 1.0]))
    # no data: prior mean 2 x clutter mean (10) = 20; weak echoes (excess ~1): the mean floored at the clutter's 10
    assert beta[0] / (alpha[0] - 1) == pytest.approx(20.0)
    assert beta[1] / (alpha[1] - 1) == pytest.approx(10.0)

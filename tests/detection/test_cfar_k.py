"""OS-CFAR in K-distributed clutter: the closed-form Pfa (detection/cfar.py k_os_pfa) against the Bessel form and
Monte Carlo, the shape fitted to the tail and the mapping onto the exponential law (detection/normalise.py)."""

import numpy as np
import pytest
from scipy.special import gamma as gamma_fn
from scipy.special import kv

from sonartrack.detection.cfar import CfarSettings, cfar_normalise, k_os_pfa, k_os_threshold, os_pfa, os_threshold
from sonartrack.detection.normalise import k_shape_from_exceedance, k_to_exponential

N, K = 32, 24


def k_intensity(rng, nu, shape):
    return rng.exponential(1.0, shape) * rng.gamma(nu, 1.0 / nu, shape)


@pytest.mark.parametrize("nu", [0.5, 1.0, 3.0])
def test_k_survival_matches_the_bessel_form(nu):
    from sonartrack.detection.cfar import _LOG_X, _k_law

    x = np.array([0.1, 1.0, 5.0, 20.0])
    bessel = 2.0 * (nu * x) ** (nu / 2) * kv(nu, 2 * np.sqrt(nu * x)) / gamma_fn(nu)
    sf = np.exp(np.interp(np.log(x), _LOG_X, np.log(_k_law(nu)[1])))
    assert sf == pytest.approx(bessel, rel=5e-3)  # the quadrature is loosest near x = 0, tightest in the tail


def test_large_shape_tends_to_the_exponential_closed_form():
    a = np.array([2.0, 8.0, 15.0])
    assert k_os_pfa(a, 100.0, N, K) == pytest.approx(os_pfa(a, N, K), rel=0.6)  # K -> exponential slowly in nu
    assert k_os_pfa(a[:1], 100.0, N, K) == pytest.approx(os_pfa(a[:1], N, K), rel=0.02)


@pytest.mark.parametrize("nu", [0.5, 1.0])
def test_threshold_holds_its_pfa_on_independent_k_clutter(nu):
    rng = np.random.default_rng(34)
    y = k_intensity(rng, nu, (8, 50_000))
    s = cfar_normalise(y, CfarSettings())
    pfa = 1e-3
    share = float(np.mean(s >= k_os_threshold(pfa, nu, N, K)))
    n = s.size
    assert abs(share - pfa) < 4 * np.sqrt(pfa / n) + 0.1 * pfa  # binomial, plus the tabulation's interpolation
    assert np.mean(s >= os_threshold(pfa, N, K)) > 5 * pfa  # the exponential threshold does not hold it


@pytest.mark.parametrize("nu", [0.3, 1.0, None])
def test_shape_fitted_to_the_tail_and_the_mapped_statistic_keeps_the_rate(nu):
    rng = np.random.default_rng(341)
    y = k_intensity(rng, nu, (4, 100_000)) if nu else rng.exponential(1.0, (4, 100_000))
    s = cfar_normalise(y, CfarSettings())
    fitted = k_shape_from_exceedance(s, N, K)
    if nu is None:
        assert fitted > 20.0
    else:
        assert fitted == pytest.approx(nu, rel=0.15)
    mapped = k_to_exponential(s, fitted, N, K)
    pfa = 1e-4
    assert np.mean(mapped >= os_threshold(pfa, N, K)) == pytest.approx(pfa, rel=0.4)
    order = np.argsort(s.ravel()[:5000])
    assert np.all(np.diff(mapped.ravel()[:5000][order]) >= 0)  # monotone: the cells keep their order


def test_swerling_pd_in_k_clutter_has_the_pfa_and_the_exponential_limits():
    from sonartrack.detection.cfar import k_os_pd

    a = np.array([5.0, 15.0, 40.0])
    assert k_os_pd(a, 0.0, 1.5, N, K) == pytest.approx(k_os_pfa(a, 1.5, N, K), rel=1e-3)  # no echo: the Pfa
    # Rohling's Swerling-1 OS-CFAR: Pd(alpha) = Pfa(alpha / (1 + EBR)); K of shape 100 is within 2 % of it
    assert k_os_pd(a, 56.0, 100.0, N, K) == pytest.approx(os_pfa(a / 57.0, N, K), rel=0.02)
    assert k_os_pd(a, 56.0, np.inf, N, K) == pytest.approx(os_pfa(a / 57.0, N, K), rel=1e-12)


@pytest.mark.parametrize("nu", [0.7, 2.0])
def test_swerling_pd_in_k_clutter_matches_draws_and_needs_more_ebr(nu):
    from sonartrack.detection.cfar import k_os_pd, os_mean_factor

    rng = np.random.default_rng(34)
    draws, ebr = 100_000, 10 ** 1.75  # 17.5 dB, the counted echoes' median on study active-chain trial 2
    alpha = k_os_threshold(1e-5, nu, N, K)
    refs = k_intensity(rng, nu, (draws, N))
    mu = np.partition(refs, K - 1, axis=1)[:, K - 1] / os_mean_factor(N, K)
    y = k_intensity(rng, nu, draws) + ebr * rng.exponential(1.0, draws)  # Swerling 1 on a K cell
    pd = k_os_pd(alpha, ebr, nu, N, K)
    sd = np.sqrt(pd * (1 - pd) / draws)
    assert np.mean(y / mu >= alpha) == pytest.approx(pd, abs=4 * sd + 2e-3)
    # at the same Pfa the K clutter's threshold costs Pd against exponential noise (Watts 1985)
    assert pd < k_os_pd(os_threshold(1e-5, N, K), ebr, np.inf, N, K) - 0.1

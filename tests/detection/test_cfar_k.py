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

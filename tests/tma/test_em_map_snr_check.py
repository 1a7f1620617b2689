"""em-map's check of its SNR residuals against the propagation model: the statistics on hand-worked residuals, and
on a scene whose SNR follows spherical spreading solved with the right model and with a cylindrical one."""

import numpy as np
import pytest
from scipy.stats import chi2

from sonartrack.core.units import KNOT_MPS
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma.em_map import make_problem, solve_em_map
from sonartrack.tma.em_snr_check import snr_residual_check


def test_statistics_of_hand_worked_residuals():
    # w = a + b (l - l_bar) exactly: chi2 = n a^2 + b^2 Sxx, trend chi2 = b^2 Sxx (the slope's z^2)
    r = np.array([1000.0, 2000.0, 4000.0, 8000.0, 16000.0, 32000.0])
    l_c = np.log(r) - np.log(r).mean()
    sxx = float(l_c @ l_c)  # (ln 2)^2 (2.5^2 + 1.5^2 + 0.5^2) x 2 = 17.5 (ln 2)^2
    assert sxx == pytest.approx(17.5 * np.log(2) ** 2)
    a, b, sigma = 0.5, 2.0, 2.0
    predicted = np.full(6, 60.0)
    snr = predicted + sigma * (a + b * l_c)
    c = snr_residual_check(snr, predicted, r, sigma, alpha=0.01, n_params=2)
    assert c.chi2 == pytest.approx(6 * a**2 + b**2 * sxx)
    assert c.trend_chi2 == pytest.approx(b**2 * sxx)
    assert c.dof == 4 and c.n == 6
    assert c.limit == pytest.approx(chi2.ppf(0.99, 4)) and c.trend_limit == pytest.approx(chi2.ppf(0.99, 1))
    # NaN SNRs are skipped; fewer than 5 SNRs explain anything
    snr_nan = snr.copy()
    snr_nan[:2] = np.nan
    assert snr_residual_check(snr_nan, predicted, r, sigma).n == 4
    assert snr_residual_check(snr_nan, predicted, r, sigma).explained


def _scene(seed):
    """A target closing on a straight-running ownship from 12 km to ~2.5 km: its range spans a factor 5, so a model
    with another spreading law cannot be fitted by a range-scaled track (which the bearings alone allow here)."""
    t = np.arange(150) * 8.0
    po, _, _ = ManeuveringTrack(0.0, 0.0, 6 * KNOT_MPS, np.deg2rad(90.0)).state(t)
    pt, _, _ = ManeuveringTrack(12_000.0, 2_000.0, 10 * KNOT_MPS, np.deg2rad(270.0)).state(t)
    d = pt - po
    rng = np.random.default_rng(seed)
    z = np.arctan2(d[:, 0], d[:, 1]) + rng.normal(0, np.deg2rad(0.5), len(t))
    return t, po, z, np.linalg.norm(d, axis=1), rng


def spherical(r):
    return 140.0 - 20.0 * np.log10(r) + 12.5 - 73.0


def cylindrical(r):
    # the same SNR at 1 km, then 10 log r: a shallow-water duct's spreading instead of the open ocean's
    return 140.0 - 60.0 - 10.0 * np.log10(r / 1000.0) + 12.5 - 73.0


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_right_model_explains_the_snr_and_the_wrong_one_does_not(seed):
    t, po, z, r_true, rng = _scene(seed)
    snr = spherical(r_true) + rng.normal(0, 1.0, len(t))
    verdicts = {}
    for name, model in (("right", spherical), ("wrong", cylindrical)):
        prob = make_problem(z, snr, t, po, np.deg2rad(0.5), 1.0, model, 500.0, 60_000.0)
        est = solve_em_map(prob, covariance=False)
        pos = est.x0[:2] + est.x0[2:] * (t - t[0])[:, None]
        r = np.linalg.norm(pos - po, axis=1)
        verdicts[name] = snr_residual_check(snr, model(r), r, 1.0)
    assert verdicts["right"].explained
    assert not verdicts["wrong"].explained
    assert "does not explain the SNR (chi2 = " in verdicts["wrong"].note()

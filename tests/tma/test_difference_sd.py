"""The bearing sd from the bearings alone (tma/record_checks.py :func:`difference_sd_estimate`, no motion model):
its divided differences against hand-worked coefficients, Satterthwaite's degrees of freedom against the closed
form for equal spacing, the estimate and its interval on synthetic bearings (known sd, smooth truth from plain
numpy geometry, uneven times, outliers), and ``sonartrack tma``'s verdict on turning records, where it replaces the
constant-velocity residual scale."""

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import binom

from sonartrack.tma import BearingRecord, OwnshipTrack, TmaSettings, solve_tma
from sonartrack.tma.motion_verdict import judge_record
from sonartrack.tma.record_checks import (
    _difference_correlation,
    _difference_weights,
    difference_sd_estimate,
)

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from worlds.leg_paths import leg_positions  # noqa: E402


def test_equal_spacing_coefficients_and_correlations_by_hand():
    """Equal spacing: second differences (1, -2, 1) / sqrt(6), lag correlations -4/6 and 1/6; third (-1, 3, -3, 1)
    / sqrt(20), lags -15/20, 6/20 and -1/20."""
    t = np.arange(12.0) * 7.0
    for order, coef, lags in ((2, [1, -2, 1], [-4 / 6, 1 / 6]), (3, [-1, 3, -3, 1], [-15 / 20, 6 / 20, -1 / 20])):
        c = _difference_weights(t, order)
        c = c * np.sign(c[:, :1]) * np.sign(coef[0])
        np.testing.assert_allclose(c, np.tile(np.array(coef) / np.linalg.norm(coef), (len(t) - order, 1)), atol=1e-12)
        band = _difference_correlation(c, np.ones(len(t)))
        np.testing.assert_allclose(band[0, 1:], lags, atol=1e-12)


def test_differences_cancel_polynomials_on_uneven_times():
    """An order-k difference is zero on any polynomial of degree < k, and a second difference is the middle
    sample's residual from the line through its neighbours (the independent form of it)."""
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(1.0, 30.0, 40))
    for order in (2, 3):
        c = _difference_weights(t, order)
        idx = np.arange(len(c))[:, None] + np.arange(order + 1)
        poly = np.polyval(rng.normal(size=order), (t - t.mean()) / 100.0)
        assert np.max(np.abs(np.sum(c * poly[idx], axis=1))) < 1e-9
    v = rng.normal(size=len(t))
    c = _difference_weights(t, 2)
    w = (t[2:] - t[1:-1]) / (t[2:] - t[:-2])
    line = v[1:-1] - (w * v[:-2] + (1 - w) * v[2:])  # residual from the line through the neighbours
    d = np.sum(c * v[np.arange(len(c))[:, None] + np.arange(3)], axis=1)
    np.testing.assert_allclose(d * np.sign(c[:, 1]), line / np.sqrt(1 + w**2 + (1 - w) ** 2), rtol=1e-9)


def test_satterthwaite_dof_equal_spacing():
    """nu = m^2 / tr R^2 -> m / (1 + 2 sum rho_l^2): m / 1.944 for second differences, m / 2.31 for third."""
    n = 2001
    t = np.arange(float(n))
    z = np.random.default_rng(0).normal(size=n) * 1e-3
    for order, rho in ((2, [-4 / 6, 1 / 6]), (3, [-15 / 20, 6 / 20, -1 / 20])):
        est = difference_sd_estimate(t, z, order=order)
        m = n - order  # none clipped at 3.5 sds of 2000 but a few
        assert est.dof == pytest.approx(m / (1 + 2 * np.sum(np.square(rho))), rel=0.01)


def _smooth_world(rng, n=300):
    """Uneven times, a constant-velocity target seen from an ownship turning slowly (true bearings, rad), and
    per-bearing relative sds spread as a line array's."""
    t = np.cumsum(rng.uniform(2.0, 20.0, n))
    heading = 0.3 + 2e-4 * t
    own = np.c_[np.cumsum(4.0 * np.sin(heading) * np.gradient(t)), np.cumsum(4.0 * np.cos(heading) * np.gradient(t))]
    tgt = np.array([6000.0, 8000.0]) + np.outer(t, [-3.0, 2.0])
    d = tgt - own
    return t, np.arctan2(d[:, 0], d[:, 1])


@pytest.mark.parametrize("order", [2, 3])
@pytest.mark.parametrize("per_bearing", [False, True])
def test_estimate_and_interval_on_smooth_bearings(order, per_bearing):
    """Known sd 1 deg (or each bearing's own, relative 0.5-3), smooth truth, uneven times, 200 records: the
    estimate's mean within 1.5 % of the truth, its spread that of sigma^2 chi-square(nu) / nu (1 / sqrt(2 nu)) within
    20 %, and the 95 % interval's coverage inside the binomial(200, 0.95) 99.9 % range."""
    rng = np.random.default_rng(11 + order + 10 * per_bearing)
    sigma = np.radians(1.0)
    ratio, cover, dof = [], 0, []
    for _ in range(200):
        t, truth = _smooth_world(rng)
        rel = rng.uniform(0.5, 3.0, len(t)) if per_bearing else np.ones(len(t))
        est = difference_sd_estimate(t, truth + sigma * rel * rng.standard_normal(len(t)), rel, order=order)
        ratio.append(est.sd_rad / sigma)
        cover += est.lo_rad <= sigma <= est.hi_rad
        dof.append(est.dof)
    assert np.mean(ratio) == pytest.approx(1.0, abs=0.015)
    assert np.std(ratio) == pytest.approx(1.0 / np.sqrt(2.0 * np.mean(dof)), rel=0.2)
    lo, hi = binom.ppf([0.0005, 0.9995], 200, 0.95)
    assert lo <= cover <= hi


def test_outliers_are_screened():
    """3 % of the bearings 10-30 deg off: the estimate stays within 10 % of the true 0.5 deg (the plain mean square
    of the differences is several times it)."""
    rng = np.random.default_rng(5)
    t, truth = _smooth_world(rng, 400)
    sigma = np.radians(0.5)
    z = truth + sigma * rng.standard_normal(len(t))
    bad = rng.random(len(t)) < 0.03
    z[bad] += np.radians(rng.uniform(10, 30, bad.sum()) * rng.choice([-1, 1], bad.sum()))
    est = difference_sd_estimate(t, z)
    assert est.sd_rad == pytest.approx(sigma, rel=0.1)
    c = _difference_weights(t, 3)
    d = np.sum(c * z[np.arange(len(c))[:, None] + np.arange(4)], axis=1)
    assert np.sqrt(np.mean(d**2)) > 3 * sigma


def _turning_record(seed: int, sigma_deg: float):
    """A target on three legs (turns of 60-110 deg) 6-12 km from an ownship on three legs, bearings every 5-40 s
    over an hour with white noise of ``sigma_deg``."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(5.0, 40.0, 400))
    t = t[t < 3600.0] - t[0]
    tn = np.arange(0.0, 3601.0, 10.0)
    own_legs = [(1200.0, 0.0, 3.0), (2400.0, 80.0, 3.0), (3600.0, 10.0, 3.0)]
    c0 = rng.uniform(0, 360)
    turns = rng.uniform(60, 110, 2) * rng.choice([-1, 1], 2)
    tgt_legs = [(1100.0, c0, 5.0), (2300.0, c0 + turns[0], 4.0), (3600.0, c0 + turns[0] + turns[1], 6.0)]
    b0, r0 = rng.uniform(0, 2 * np.pi), rng.uniform(6000, 12000)
    d = leg_positions(t, (r0 * np.sin(b0), r0 * np.cos(b0)), tgt_legs) - leg_positions(t, (0, 0), own_legs)
    z = np.arctan2(d[:, 0], d[:, 1]) + np.radians(sigma_deg) * rng.standard_normal(len(t))
    own = leg_positions(tn, (0, 0), own_legs)
    return BearingRecord(time_s=t, bearing_rad=z), OwnshipTrack(time_s=tn, x_m=own[:, 0], y_m=own[:, 1])


def test_turning_records_sd_from_differences():
    """Three-leg targets, true sd 1 deg: the constant-velocity fit is rejected; the differences' estimate is within
    15 % of 1 deg on every record and its interval holds it on at least 4 of 5, where the rejected fit's residual
    scale is above 1.3 deg on at least 3; ``tma`` (ml) uses that sd and says so."""
    held, scale = 0, []
    for seed in range(5):
        record, own = _turning_record(seed, 1.0)
        j = judge_record(record, own, TmaSettings(method="ml"))
        assert j.rejected and j.differences is not None
        assert np.degrees(j.differences.sd_rad) == pytest.approx(1.0, rel=0.15)
        held += j.differences.lo_rad <= np.radians(1.0) <= j.differences.hi_rad
        scale.append(np.degrees(j.noise.sd_rad))
        assert j.sigma_deg(TmaSettings(method="ml")) == pytest.approx(np.degrees(j.differences.sd_rad))
    assert held >= 4 and sum(s > 1.3 for s in scale) >= 3
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = solve_tma(record, own, TmaSettings(method="ml"), unobservable="flag")
    assert "bearing sd estimated from the bearings' differences" in result.summary()
    assert result.settings.sigma_bearing_deg == pytest.approx(np.degrees(j.differences.sd_rad))


def test_given_sd_contradicted_on_turning_record():
    """Stated 0.3 deg on a turning record of 1 deg noise: reported as contradicted by the differences; stated 1 deg:
    consistent."""
    record, own = _turning_record(7, 1.0)
    low = judge_record(record, own, TmaSettings(method="ml", sigma_bearing_deg=0.3))
    assert low.rejected and "is contradicted by the record: measured from the bearings' differences" in low.notes()[0]
    right = judge_record(record, own, TmaSettings(method="ml", sigma_bearing_deg=1.0))
    assert "consistent with the given 1 deg" in right.notes()[0]

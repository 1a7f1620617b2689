"""The current leg's covariance widened for a zig the detector may have missed (tma/missed_zig.py): no zig size
gives the fit's own covariance, any only widens it; the omitted-zig bias K dv against the error of a one-leg fit of
noise-free bearings of a small zig (another path: the nonlinear fit itself); a missed zig's error covered on a
world built here with numpy, where the fit's own sds do not."""

import numpy as np

from sonartrack.tma.legs import fit_legs
from sonartrack.tma.missed_zig import _end_map_and_jacobian, missed_zig_covariance, omitted_zig_bias, with_missed_zig
from sonartrack.tma.zig import detect_zigs, glr_threshold

KN = 1852.0 / 3600.0
SIGMA = np.radians(0.5)


def vel(course_deg, speed_kn):
    c = np.radians(course_deg)
    return speed_kn * KN * np.array([np.sin(c), np.cos(c)])


def world(seed, zig_s=2400.0, turn_deg=30.0):
    """Ownship at 6 kn north then east (turn at 900 s); target from (6, 9) km on 200 deg at 8 kn, turning by
    ``turn_deg`` at ``zig_s``; bearings every 30 s over 3000 s with 0.5 deg noise. Returns (t, z, own, truth at
    the end, [p0, v1, v2], zig time)."""
    t = np.arange(0.0, 3000.0, 30.0) + 5.0
    v_own = np.where((t < 900.0)[:, None], vel(0, 6), vel(90, 6))
    own = np.cumsum(np.r_[[[0.0, 0.0]], v_own[:-1] * np.diff(t)[:, None]], axis=0)
    v1, v2 = vel(200, 8), vel(200 + turn_deg, 8)
    tgt = np.array([6000.0, 9000.0]) + np.minimum(t - t[0], zig_s - t[0])[:, None] * v1 \
        + np.maximum(t - zig_s, 0.0)[:, None] * v2
    z = np.arctan2(tgt[:, 0] - own[:, 0], tgt[:, 1] - own[:, 1])
    z = z + SIGMA * np.random.default_rng(seed).standard_normal(len(t))
    return t, z, own, tgt[-1], np.r_[6000.0, 9000.0, v1, v2]


H = glr_threshold(0.05, 30.0)


def test_no_zig_size_gives_the_fits_covariance_and_any_only_widens_it():
    t, z, own, _, _ = world(0)
    fit = fit_legs(t, z, own, SIGMA, [], motion_alpha=None)  # the zig missed: one leg
    L, _ = _end_map_and_jacobian(fit, t, own, np.full(len(t), SIGMA))
    base = L @ fit.covariance @ L.T
    assert np.allclose(missed_zig_covariance(fit, t, own, SIGMA, H, dv_sd_mps=1e-6), base, rtol=1e-6, atol=1e-9)
    wide = missed_zig_covariance(fit, t, own, SIGMA, H, dv_sd_mps=2.0)
    assert np.linalg.eigvalsh(wide - base).min() > -1e-6 * np.abs(base).max()
    assert np.trace(wide[:2, :2]) > 2.0 * np.trace(base[:2, :2])


def test_the_omitted_zig_bias_is_the_one_leg_fits_error_on_noise_free_bearings():
    """Noise-free bearings of a 3 deg turn at 1800 s, fitted as one leg: the fit's final-state error against the
    truth is K dv to first order (the same fit's K at the fitted track)."""
    t, _, own, truth, params = world(0, zig_s=1800.0, turn_deg=3.0)
    v1, v2 = params[2:4], params[4:6]
    tgt = np.array([6000.0, 9000.0]) + np.minimum(t - t[0], 1800.0 - t[0])[:, None] * v1 \
        + np.maximum(t - 1800.0, 0.0)[:, None] * v2
    z = np.arctan2(tgt[:, 0] - own[:, 0], tgt[:, 1] - own[:, 1])
    fit = fit_legs(t, z, own, SIGMA, [], motion_alpha=None, params_init=np.r_[6000.0, 9000.0, v1])
    L, G = _end_map_and_jacobian(fit, t, own, np.full(len(t), SIGMA))
    K, _ = omitted_zig_bias(L, G, t, 1800.0)
    error = np.r_[fit.legs[-1].state[:2] - truth, fit.legs[-1].state[2:] - v2]
    predicted = K @ (v2 - v1)
    assert np.linalg.norm(error[:2] - predicted[:2]) < 0.1 * np.linalg.norm(predicted[:2])
    assert np.linalg.norm(predicted[:2]) > 50.0  # the premise: a bias worth predicting


def test_a_missed_zig_is_covered_by_the_widened_covariance():
    """A 20 deg turn 300 s before the end (10 bearings), which the test places 200-330 s early or finds late: the
    fit's own sds miss the truth (up to 15), the widened covariance holds it within 3 sds, on each of 5 noise
    draws."""
    own_sds, wide_sds = [], []
    for seed in range(5):
        t, z, own, truth, _ = world(seed, zig_s=2700.0, turn_deg=20.0)
        report = detect_zigs(t, z, own, SIGMA, missed_zig_dv_sd_mps=None)
        fit = report.legs
        e = fit.legs[-1].state[:2] - truth
        own_sds.append(float(np.sqrt(e @ np.linalg.solve(fit.legs[-1].state_cov[:2, :2], e))))
        wide = with_missed_zig(fit, t, own, SIGMA, report.threshold, dv_sd_mps=2.0).legs[-1]
        wide_sds.append(float(np.sqrt(e @ np.linalg.solve(wide.state_cov[:2, :2], e))))
    assert max(own_sds) > 5.0  # the premise
    assert max(wide_sds) < 3.0

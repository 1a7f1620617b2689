"""MFTD (paper P1): pruned vs exhaustive, compiled vs reference, the Kalman prior, closed-form ROCs."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.detection.frames import validate_frames
from sonartrack.detection.mftd import MftdDetector, pruned_detect_fast
from sonartrack.detection.mftd_reference import exhaustive_detect, pruned_detect, track_log_weights
from sonartrack.detection.prior import kalman_prior
from sonartrack.metrics.roc import roc_curve, thresholds
from sonartrack.models.range_doppler import (
    RangeDopplerGrid,
    ar_process_noise,
    ar_transition,
    cw_cell_sizes,
    printed_quantisation_covariance,
)
from sonartrack.models.swerling import clairvoyant_pd, clairvoyant_threshold, single_cell_pd, single_frame_plane_pd
from sonartrack.sim.range_doppler import simulate_frames, simulate_target

TINY = RangeDopplerGrid(2, 3, range_cell_m=20.0, range_rate_cell_mps=1.0, range_min_m=0.0, range_rate_min_mps=-1.5)


@pytest.mark.parametrize("density", ["centre", "smoothed"])
@pytest.mark.parametrize("seed", range(6))
def test_pruned_with_enough_tracks_is_exhaustive_and_never_larger_with_few(density, seed):
    rng = np.random.default_rng(seed)
    K, M = 3, TINY.n_cells
    prior = kalman_prior(TINY, 2.0, 0.7, K, prior_density=density)
    snr = float(rng.uniform(0.5, 5.0))
    y = simulate_frames(rng, TINY, K, snr, cells=np.array([[0, 1], [1, 1], [1, 2]]))
    ex = exhaustive_detect(y, TINY, prior, snr, n_best=4)
    for run in (pruned_detect, pruned_detect_fast):
        full = run(y, TINY, prior, snr, M ** (K - 1), restrict=False, n_best=4)
        assert full.statistic == pytest.approx(ex.statistic, abs=1e-12)
        np.testing.assert_array_equal(full.tracks, ex.tracks)
        np.testing.assert_allclose(full.log_weights, ex.log_weights, atol=1e-12)
        for n in (1, 2, 5, 11):
            assert run(y, TINY, prior, snr, n, restrict=False).statistic <= ex.statistic + 1e-12
            # eq. 20 to the letter (sum over the kept N) is never larger either
            assert run(y, TINY, prior, snr, n, restrict=False, final="kept").statistic <= ex.statistic + 1e-12


def test_best_track_weights_match_the_reference_formula():
    rng = np.random.default_rng(7)
    prior = kalman_prior(TINY, 2.0, 0.7, 3, prior_density="smoothed")
    y = simulate_frames(rng, TINY, 3)
    res = pruned_detect_fast(y, TINY, prior, 2.0, 36, restrict=False, n_best=3)
    np.testing.assert_allclose(res.log_weights, track_log_weights(y, TINY, prior, 2.0, res.tracks), atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_compiled_equals_reference_and_restriction_changes_nothing_measurable(seed):
    rng = np.random.default_rng(100 + seed)
    grid = RangeDopplerGrid.cw(16, 48, 0.125, 30e3, 1500.0)
    K = 5
    track = simulate_target(rng, grid, 2.0, 1.0, K)
    y = simulate_frames(rng, grid, K, 3.0, track.cells)
    prior = kalman_prior(grid, 2.0, 1.0, K, prior_density="smoothed")
    ref = pruned_detect(y, grid, prior, 3.0, 10, restrict=False)
    fast_full = pruned_detect_fast(y, grid, prior, 3.0, 10, restrict=False)
    fast = pruned_detect_fast(y, grid, prior, 3.0, 10, restrict=True)
    ref_r = pruned_detect(y, grid, prior, 3.0, 10, restrict=True)
    assert fast_full.statistic == pytest.approx(ref.statistic, abs=1e-10)
    np.testing.assert_array_equal(fast_full.tracks, ref.tracks)
    for r in (fast, ref_r):
        assert abs(r.statistic - ref.statistic) < 1e-9
        np.testing.assert_array_equal(r.tracks, ref.tracks)
    assert fast.n_branches < 0.7 * fast_full.n_branches  # the restriction does cut work


def test_kalman_prior_hand_worked_two_frames():
    """c_theta of a two-frame track by hand: 1/M * A N(v2; Phi v1, Phi R Phi^T + Q) (B_1 -> inf)."""
    T, sa = 2.0, 1.0
    g = RangeDopplerGrid(4, 5, range_cell_m=30.0, range_rate_cell_mps=0.5, range_rate_min_mps=-1.25)
    prior = kalman_prior(g, T, sa, 2, prior_density="centre")
    R = np.diag([30.0**2 / 12, 0.5**2 / 12])
    Phi = np.array([[1.0, T], [0.0, 1.0]])
    Q = np.array([[T**4 / 4, T**3 / 2], [T**3 / 2, T**2]]) * sa**2
    B2 = Phi @ R @ Phi.T + Q
    np.testing.assert_allclose(prior.B[1], B2, rtol=1e-12)
    tracks = np.array([[[1, 2], [1, 3]], [[2, 0], [3, 1]]])
    got = track_log_weights(np.zeros((2, 4, 5)), g, prior, 0.0, tracks)
    for tr, lw in zip(tracks, got, strict=True):
        v1 = np.array([(tr[0, 0] + 0.5) * 30.0, -1.25 + (tr[0, 1] + 0.5) * 0.5])
        v2 = np.array([(tr[1, 0] + 0.5) * 30.0, -1.25 + (tr[1, 1] + 0.5) * 0.5])
        d = v2 - Phi @ v1
        dens = np.exp(-0.5 * d @ np.linalg.solve(B2, d)) / (2 * np.pi * np.sqrt(np.linalg.det(B2)))
        assert lw == pytest.approx(np.log(1 / 20 * 30.0 * 0.5 * dens), rel=1e-12)


def test_finite_b1_tends_to_the_limit():
    g = RangeDopplerGrid(4, 5, range_cell_m=30.0, range_rate_cell_mps=0.5)
    lim = kalman_prior(g, 2.0, 1.0, 4)
    lit = kalman_prior(g, 2.0, 1.0, 4, b1=np.eye(2) * 1e7, w1=[10.0, 0.1])
    np.testing.assert_allclose(lit.B[1:], lim.B[1:], rtol=1e-4)
    np.testing.assert_allclose(lit.L[1:], lim.L[1:], atol=1e-5)


def test_prior_is_a_proper_distribution_over_cells():
    """From a mid-plane track, the next frame's prior mass sum_m A N(v_m; w, B + R) is ~1 (smoothed)."""
    g = RangeDopplerGrid.cw(40, 160, 0.125, 30e3, 1500.0)
    prior = kalman_prior(g, 2.0, 1.0, 3, prior_density="smoothed")
    centres = g.centres()
    rng = np.random.default_rng(3)
    for _ in range(20):
        v1 = centres[rng.integers(15 * 160 + 60, 15 * 160 + 100)]
        w2 = prior.L[0] @ v1 + prior.F[0] @ prior.w1
        d = centres - w2
        mass = np.exp(prior.log_norm[1] - 0.5 * np.einsum("ni,ij,nj->n", d, prior.S_inv[1], d)).sum()
        assert mass == pytest.approx(1.0, abs=0.1)


def test_cell_sizes_and_the_printed_typo():
    dr, df, dv = cw_cell_sizes(0.125, 30e3, 1500.0)
    assert dr == pytest.approx(0.58 * 0.125 * 750.0)
    assert df == pytest.approx(0.88 / 0.125)
    assert dv == pytest.approx(7.04 * 1500 / 60e3)  # two-way Doppler: v = df c / (2 f_c)
    printed = printed_quantisation_covariance(0.125, 30e3, 1500.0)
    assert printed[0, 0] == pytest.approx(dr**2 / 12)
    assert printed[1, 1] == pytest.approx(16 * dv**2 / 12)  # (2c/f_c)^2 = 16 (c/(2 f_c))^2
    np.testing.assert_allclose(ar_process_noise(2.0, 1.0), np.outer([2.0, 2.0], [2.0, 2.0]))
    np.testing.assert_allclose(ar_transition(2.0), [[1, 2], [0, 1]])


def test_k1_monte_carlo_roc_matches_closed_form():
    rng = np.random.default_rng(5)
    g = RangeDopplerGrid(1, 1, 1.0, 1.0)
    prior = kalman_prior(g, 1.0, 1.0, 1)
    rho = 3.0
    n = 20000
    y0 = rng.exponential(2.0, n)
    y1 = rng.exponential(2.0 * (1 + rho), n)
    s0 = [pruned_detect_fast(np.array([[[v]]]), g, prior, rho, 1, checked=True).statistic for v in y0[:4000]]
    s1 = [pruned_detect_fast(np.array([[[v]]]), g, prior, rho, 1, checked=True).statistic for v in y1[:4000]]
    pfa = np.array([0.01, 0.05, 0.2, 0.5])
    c = roc_curve(s0, s1, pfa)
    assert np.all(c.pd_low <= single_cell_pd(pfa, rho)) and np.all(single_cell_pd(pfa, rho) <= c.pd_high)
    assert single_frame_plane_pd(pfa, rho, 1) == pytest.approx(single_cell_pd(pfa, rho))


@pytest.mark.parametrize("K", [1, 3, 6])
def test_clairvoyant_gamma_roc_against_simulated_sums(K):
    rng = np.random.default_rng(K)
    rho, n = 2.0, 40000
    s0 = rng.exponential(2.0, (n, K)).sum(axis=1)
    s1 = rng.exponential(2.0 * (1 + rho), (n, K)).sum(axis=1)
    pfa = np.array([0.01, 0.1, 0.3])
    t = clairvoyant_threshold(pfa, K)
    assert np.all(np.abs((s0[:, None] > t).mean(axis=0) - pfa) < 4 * np.sqrt(pfa / n) + 1e-3)
    pd = (s1[:, None] > t).mean(axis=0)
    np.testing.assert_allclose(pd, clairvoyant_pd(pfa, rho, K), atol=0.01)
    # the known-track detector beats the single known cell whenever K > 1
    if K > 1:
        assert np.all(clairvoyant_pd(pfa, rho, K) > single_cell_pd(pfa, rho))


def test_thresholds_respect_the_false_alarm_budget():
    rng = np.random.default_rng(0)
    s = rng.normal(size=1000)
    for p in (0.001, 0.01, 0.1, 0.37):
        assert (s > thresholds(s, p)[0]).mean() <= p


@pytest.mark.parametrize("bad, msg", [
    (np.ones((4, 5)), "rank 3"),
    (np.ones((0, 4, 5)), "K = 0"),
    (-np.ones((2, 4, 5)), "negative"),
    (np.full((2, 4, 5), np.nan), "NaN"),
])
def test_bad_frames_one_line_errors(bad, msg):
    with pytest.raises(InputError, match=msg) as e:
        validate_frames(bad)
    assert "\n" not in str(e.value)


def test_detector_rejects_k_below_one_and_wrong_plane():
    det = MftdDetector(TINY)
    with pytest.raises(InputError, match="at least 1"):
        kalman_prior(TINY, 2.0, 1.0, 0)
    with pytest.raises(InputError, match="grid is 2 x 3"):
        det.detect(np.ones((2, 4, 4)))

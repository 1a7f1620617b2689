"""MFTD per narrowband line (systems/passive/line_mftd.py): the cell map against scipy's F and normal laws, a weak
line moving in bearing that the single-period threshold mostly misses, the false rate on noise-only grams against
the stated one, and the merge with the single-period detections."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import f as f_law
from scipy.stats import norm

from sonartrack.acoustics.lofar import LofarGram, LofarSettings, background, detect_lines, line_threshold
from sonartrack.core.errors import InputError
from sonartrack.systems.passive.line_mftd import (
    candidate_bins,
    gaussianised,
    line_mftd,
    noise_count,
    with_line_mftd,
)
from sonartrack.systems.passive.settings import LineMftdSettings, PassiveSettings

L, T, B, F, K0 = 16, 40, 61, 48, 24
LOFAR = LofarSettings(integration=L, normaliser="mean", edge_bins=0)


def _gram(rng, snr_db: float | None):
    """A gram as the mean normaliser gives it: cells the mean of L exponential powers (Gamma(L, 1/L)), z = power
    over the split-window background; a line of bin SNR s on bin K0 moving from beam 20 to 32 (36 deg)."""
    p = rng.gamma(L, 1.0 / L, (T, B, F))
    beam = np.rint(np.linspace(20, 32, T)).astype(int)
    if snr_db is not None:
        p[np.arange(T), beam, K0] = rng.gamma(L, (1.0 + 10 ** (snr_db / 10)) / L, T)
    z = p / background(p, LOFAR)
    g = LofarGram((np.arange(T) + 0.5) * 16.0, LOFAR.cone_deg, np.arange(F, dtype=float), p.astype(np.float32),
                  z.astype(np.float32))
    return g, beam


def test_gaussianised_is_the_probability_integral_transform_of_the_f_law():
    z = np.array([0.5, 1.0, 1.5, 2.0, 2.5, 3.0])
    expected = norm.isf(f_law.sf(z, 2 * L, 2 * L * 2 * LOFAR.reference_bins))
    assert np.allclose(gaussianised(z, LOFAR), expected, rtol=1e-9, atol=1e-9)
    # the line threshold (F quantile at pfa) maps onto the normal quantile at the same pfa
    assert gaussianised(line_threshold(LOFAR), LOFAR) == pytest.approx(norm.isf(LOFAR.pfa), rel=1e-6)
    assert gaussianised(1e9, LOFAR) == 8.0  # tail clipped, finite


def test_noise_cells_map_to_standard_normal():
    g, _ = _gram(np.random.default_rng(3), None)
    x = gaussianised(g.statistic, LOFAR).ravel()
    assert abs(x.mean()) < 0.02 and abs(x.std() - 1.0) < 0.02


def test_weak_moving_line_found_in_most_periods_where_single_period_misses():
    g, beam = _gram(np.random.default_rng(0), -2.0)
    single = detect_lines(g, LOFAR)
    on_line = (single.frequency_hz == K0) & (np.abs(single.beam - beam[np.searchsorted(g.time_s, single.time_s)]) <= 1)
    assert on_line.sum() / T < 0.5  # the single-period threshold finds the line in fewer than half the periods
    d = line_mftd(g, [K0], LOFAR, 1e-4, LineMftdSettings())
    ti = np.searchsorted(g.time_s, d.time_s)
    hit = np.abs(d.beam - beam[ti]) <= 1
    assert len(np.unique(ti[hit])) / T >= 0.7
    assert np.all(d.frequency_hz == K0) and np.allclose(d.statistic, g.statistic[ti, d.beam, K0])


def test_false_rate_on_noise_grams_near_the_stated_one():
    pfa = 1e-3
    g, _ = _gram(np.random.default_rng(7), None)
    d = line_mftd(g, np.arange(F), LOFAR, pfa, LineMftdSettings())
    rate = len(d) / (T * B * F)
    assert pfa / 2 < rate < 2 * pfa, rate


def test_candidate_bins_and_merge_keep_single_detections():
    assert candidate_bins(10, np.array([0, 5, 5]), 1).tolist() == [0, 1, 4, 5, 6]
    assert candidate_bins(10, np.array([0, 5, 5, 7]), 1, min_detections=2).tolist() == [4, 5, 6]
    # the bin gate: 1 + the Poisson(pfa cells) quantile at 1e-3, by the pmf summed by hand
    mu, k = 1e-4 * T * B * 3, 0
    while 1.0 - sum(np.exp(-mu) * mu**j / math.factorial(j) for j in range(k + 1)) >= 1e-3:
        k += 1
    assert noise_count(T * B * 3, 1e-4) == k + 1
    noise, _ = _gram(np.random.default_rng(5), None)
    assert len(with_line_mftd(noise, detect_lines(noise, LOFAR), LOFAR, 1e-4, LineMftdSettings())[1]) == 0
    g, beam = _gram(np.random.default_rng(0), 0.0)
    single = detect_lines(g, LOFAR)
    merged, added = with_line_mftd(g, single, LOFAR, 1e-4, LineMftdSettings())
    assert len(merged) == len(single) + len(added) and np.all(np.diff(merged.time_s) >= 0)
    for t, b, f in zip(added.time_s, added.beam, added.frequency_hz, strict=True):  # none repeats a single one
        same = (single.time_s == t) & (np.abs(single.frequency_hz - f) <= 1)
        assert not np.any(same & (np.abs(single.beam - b) <= 2))
    ti = np.searchsorted(g.time_s, added.time_s)
    assert np.sum((added.frequency_hz == K0) & (np.abs(added.beam - beam[ti]) <= 1)) >= 0.5 * T


def test_option_off_by_default_and_statistic_checked():
    assert PassiveSettings().narrowband.mftd is False
    g, _ = _gram(np.random.default_rng(1), None)
    with pytest.raises(InputError, match="gaussian"):
        line_mftd(g, [K0], LOFAR, 1e-4, LineMftdSettings(statistic="exponential"))

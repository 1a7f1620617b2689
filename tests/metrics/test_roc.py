"""System ROC by Monte Carlo (metrics/roc.py): thresholds, intervals, and the significance of a rise in Pd."""

import numpy as np
import pytest

from sonartrack.metrics.roc import binomial_interval, min_pfa, rise_is_significant, roc_curve, thresholds


def test_thresholds_hand_worked():
    s = np.arange(1.0, 11.0)  # 10 statistics 1..10
    # Pfa 0.2: at most 2 of 10 above -> t = 8; Pfa 0.25 -> floor(2.5) = 2 too; Pfa 0.05 -> none above -> t = 10
    np.testing.assert_array_equal(thresholds(s[::-1], [0.2, 0.25, 0.05]), [8.0, 8.0, 10.0])
    assert min_pfa(1000) == 0.01


def test_roc_of_separated_statistics_is_perfect_and_intervals_bracket():
    h0, h1 = np.arange(100.0), np.arange(100.0) + 1000.0
    c = roc_curve(h0, h1, [0.1, 0.5])
    np.testing.assert_array_equal(c.pd, [1.0, 1.0])
    np.testing.assert_array_equal(c.pfa_achieved, [0.1, 0.5])
    lo, hi = binomial_interval(10, 100)
    assert lo < 0.1 < hi and c.pfa_low[0] == lo and c.pfa_high[0] == hi


def test_rise_is_significant_hand_worked():
    # n = 100: 0.5 -> 0.7, SE = sqrt(0.25/100 + 0.21/100) = 0.06782, 1.96 SE = 0.1329 < 0.2: significant
    assert rise_is_significant(0.5, 0.7, 100)
    # 0.5 -> 0.6: 1.96 sqrt(0.25/100 + 0.24/100) = 0.1372 > 0.1: not significant; a fall never is
    assert not rise_is_significant(0.5, 0.6, 100)
    assert not rise_is_significant(0.7, 0.5, 100)
    assert rise_is_significant(0.5, 0.6, 100, z=1.0)  # 0.07 < 0.1
    # both proportions 0 or 1: the floored variance keeps a zero step from counting
    assert not rise_is_significant(0.0, 0.0, 10) and not rise_is_significant(1.0, 1.0, 10)
    assert rise_is_significant(0.0, 1.0, 10)


@pytest.mark.parametrize("seed", range(3))
def test_rise_is_significant_false_alarm_rate(seed):
    """Equal true Pd: a 'significant rise' shows up in about 2.5 % of paired experiments (one-sided 1.96)."""
    rng = np.random.default_rng(seed)
    n, p = 400, 0.3
    a = rng.binomial(n, p, 4000) / n
    b = rng.binomial(n, p, 4000) / n
    rate = np.mean([rise_is_significant(x, y, n) for x, y in zip(a, b, strict=True)])
    assert 0.01 < rate < 0.045

"""System ROC by Monte Carlo (Im & Kim 1996, paper P1, sec. V: "system ROC curves by simulation").

A detector outputs a scalar statistic S per trial. From n0 target-absent trials the threshold for a
wanted false-alarm probability Pfa is the empirical (1 - Pfa) quantile of S | H0, taken so that at
most Pfa n0 of the H0 statistics exceed it; Pd is then the fraction of n1 target-present trials
whose statistic exceeds that threshold, with a Clopper-Pearson (exact binomial) interval.

The threshold itself is uncertain (it rests on ~Pfa n0 exceedances), so a ROC point is trustworthy
only where Pfa n0 >= ~10: :func:`min_pfa` says how far down a set of H0 trials reaches.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require

#: H0 exceedances needed at the lowest Pfa of a curve (threshold quantile error ~ 1/sqrt(10))
MIN_EXCEEDANCES = 10


@dataclass(frozen=True, slots=True)
class RocCurve:
    """Pd at the wanted Pfa values, with the achieved Pfa, thresholds and 95 % binomial intervals.

    ``pd_low``/``pd_high`` bound Pd at the threshold used (binomial in the H1 trials);
    ``pfa_low``/``pfa_high`` bound the *true* false-alarm probability of that threshold (binomial in
    the H0 exceedances): a ROC point is a box, and a closed-form curve agrees with it if it passes
    through the box.
    """

    pfa: np.ndarray
    pd: np.ndarray
    pd_low: np.ndarray
    pd_high: np.ndarray
    pfa_achieved: np.ndarray
    pfa_low: np.ndarray
    pfa_high: np.ndarray
    threshold: np.ndarray
    n_h0: int
    n_h1: int


def min_pfa(n_h0: int, exceedances: int = MIN_EXCEEDANCES) -> float:
    """Lowest Pfa a set of ``n_h0`` target-absent trials supports: ``exceedances / n_h0``.

    Parameters
    ----------
    n_h0 : int
        Number of target-absent trials.
    exceedances : int, default 10
        H0 exceedances wanted at that Pfa (threshold quantile error ~ 1/sqrt(exceedances)).

    Returns
    -------
    float
        The lowest trustworthy false-alarm probability.
    """
    return exceedances / max(int(n_h0), 1)


def thresholds(h0_stat, pfa) -> np.ndarray:
    """Thresholds t with ``#{S_0 > t} <= Pfa n0``: the order statistic S_(n0 - floor(Pfa n0)) of the H0 sample.

    Parameters
    ----------
    h0_stat : array_like, shape (n0,)
        Detector statistics of the target-absent trials (finite).
    pfa : float or array_like, shape (p,)
        Wanted false-alarm probabilities, in (0, 1).

    Returns
    -------
    ndarray, shape (p,)
        Thresholds, in the unit of the statistic.

    Raises
    ------
    InputError
        If the H0 sample is empty or not finite, or a Pfa is outside (0, 1).
    """
    s = np.sort(np.asarray(h0_stat, dtype=float))
    require(s.size > 0 and np.all(np.isfinite(s)), "the target-absent statistics must be finite and non-empty")
    pfa = np.atleast_1d(np.asarray(pfa, dtype=float))
    require(bool(np.all((pfa > 0) & (pfa < 1))), "false-alarm probabilities must lie in (0, 1)")
    n_exceed = np.floor(pfa * s.size).astype(int)
    return s[np.clip(s.size - 1 - n_exceed, 0, s.size - 1)]


def binomial_interval(successes, trials, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Clopper-Pearson interval of a binomial proportion (exact: never narrower than the truth).

    Parameters
    ----------
    successes : int or array_like
        k, the number of successes.
    trials : int or array_like
        n, the number of trials (broadcast with ``successes``).
    level : float, default 0.95
        Confidence level.

    Returns
    -------
    low, high : ndarray
        Bounds of the proportion (0 for k = 0 and 1 for k = n).
    """
    from scipy.stats import beta

    k = np.asarray(successes, dtype=float)
    n = np.asarray(trials, dtype=float)
    alpha = 1.0 - level
    lo = np.where(k > 0, beta.ppf(alpha / 2, k, n - k + 1), 0.0)
    hi = np.where(k < n, beta.ppf(1 - alpha / 2, k + 1, n - k), 1.0)
    return lo, hi


def roc_curve(h0_stat, h1_stat, pfa) -> RocCurve:
    """System ROC by Monte Carlo (paper P1, sec. V): Pd at the wanted Pfa values, with binomial intervals.

    Non-finite statistics are dropped from both samples. Pd is the share of H1 statistics above the
    threshold of :func:`thresholds`; the achieved Pfa the share of H0 statistics above it.

    Parameters
    ----------
    h0_stat : array_like
        Statistics of the target-absent trials.
    h1_stat : array_like
        Statistics of the target-present trials.
    pfa : float or array_like, shape (p,)
        Wanted false-alarm probabilities, in (0, 1).

    Returns
    -------
    RocCurve
        Pd, its 95 % interval, achieved Pfa and its interval, the thresholds and the sample sizes.

    Raises
    ------
    InputError
        If no H1 statistic is finite (or as :func:`thresholds`).
    """
    h0 = np.asarray(h0_stat, dtype=float).ravel()
    h1 = np.asarray(h1_stat, dtype=float).ravel()
    h0, h1 = h0[np.isfinite(h0)], h1[np.isfinite(h1)]
    require(h1.size > 0, "no finite target-present statistics")
    t = thresholds(h0, pfa)
    k1 = (h1[None, :] > t[:, None]).sum(axis=1)
    k0 = (h0[None, :] > t[:, None]).sum(axis=1)
    lo, hi = binomial_interval(k1, h1.size)
    f_lo, f_hi = binomial_interval(k0, h0.size)
    return RocCurve(np.atleast_1d(np.asarray(pfa, dtype=float)), k1 / h1.size, lo, hi, k0 / h0.size, f_lo, f_hi, t,
                    h0.size, h1.size)


def rise_is_significant(p_before: float, p_after: float, n: int, z: float = 1.96) -> bool:
    """Whether a detection probability rose by more than ``z`` standard errors.

    Tests ``p_after - p_before > z sqrt(p_before (1 - p_before) / n + p_after (1 - p_after) / n)`` for two
    independent binomial proportions of ``n`` trials each, each variance floored at 1e-12 / n so that a
    step between two proportions of 0 (or 1) is not significant by a zero SE. (Curves sharing random
    numbers are positively correlated, so this SE is conservative for them.)

    Parameters
    ----------
    p_before, p_after : float
        The two proportions.
    n : int
        Trials behind each.
    z : float, default 1.96
        Number of standard errors.

    Returns
    -------
    bool
        True if the rise is significant.
    """
    se = np.sqrt(max(p_before * (1 - p_before), 1e-12) / n + max(p_after * (1 - p_after), 1e-12) / n)
    return bool(p_after - p_before > z * se)


def binomial_share(ok) -> dict:
    """The share of successes among the finite values of ``ok`` (1/0; NaN: not counted) with its 95 %
    Clopper-Pearson interval (:func:`binomial_interval`), as the studies report it.

    Parameters
    ----------
    ok : array_like
        1 (success), 0 (failure) or NaN (no case).

    Returns
    -------
    dict
        ``k``, ``n``, ``share`` (NaN when n is 0), ``low``, ``high``.
    """
    x = np.asarray(ok, float)
    x = x[np.isfinite(x)]
    k, n = int(np.sum(x)), int(len(x))
    lo, hi = binomial_interval(k, max(n, 1))
    return {"k": k, "n": n, "share": k / n if n else float("nan"), "low": float(lo), "high": float(hi)}

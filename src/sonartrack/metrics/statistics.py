"""Monte Carlo summaries shared by every study: RMSE over runs, paired differences, mean and SE.

NaN rule (one rule for the whole package): a NaN entry is a run without a value (no confirmed track,
a failed solve). It is skipped, never counted as zero; the number of runs that did have a value is
the sample size. A summary with no values is NaN; a standard error with fewer than two values is inf
(so a claim tested as ``mean > 2 * se`` cannot hold on too little data).
"""

from __future__ import annotations

import numpy as np


def rmse_over_runs(errors, axis: int = 0) -> np.ndarray:
    """Root mean square over runs, ``sqrt(mean over runs of e^2)``, NaN entries skipped (module NaN rule).

    Parameters
    ----------
    errors : array_like
        Errors, runs on ``axis`` (any unit; the RMSE has the same unit).
    axis : int, default 0
        Axis of the runs.

    Returns
    -------
    ndarray
        RMSE with ``axis`` removed; NaN where no run has a value.
    """
    e = np.asarray(errors, dtype=float)
    with np.errstate(invalid="ignore"):
        n = np.sum(np.isfinite(e), axis=axis)
        s = np.nansum(e * e, axis=axis)
        return np.where(n > 0, np.sqrt(s / np.maximum(n, 1)), np.nan)


def mean_and_standard_error(values) -> tuple[float, float]:
    """Mean and standard error (sample sd / sqrt(n)) of the finite ``values``.

    Parameters
    ----------
    values : array_like
        Per-run values; NaN and inf are skipped.

    Returns
    -------
    mean : float
        NaN if no value is finite.
    se : float
        inf with fewer than two finite values.
    """
    v = np.asarray(values, dtype=float).ravel()
    v = v[np.isfinite(v)]
    if len(v) == 0:
        return float("nan"), float("inf")
    if len(v) < 2:
        return float(v.mean()), float("inf")
    return float(v.mean()), float(v.std(ddof=1) / np.sqrt(len(v)))


def paired_difference(a, b) -> tuple[float, float]:
    """Mean and standard error of the per-run difference ``a - b``; runs where either is NaN are dropped.

    Parameters
    ----------
    a, b : array_like, shape (n_runs,)
        Paired per-run values (same unit).

    Returns
    -------
    mean, se : float
        As :func:`mean_and_standard_error` of ``a - b``.
    """
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    return mean_and_standard_error(d)

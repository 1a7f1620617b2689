"""Track-level performance measures for false track discrimination (FTD).

Confirmed true track (CTT), Park, Song, Lee 2017, eq. 23: a confirmed track is a CTT at a scan when

    (x - x_hat)^T P0^-1 (x - x_hat) < threshold

with x the true target state, x_hat the track's combined estimate and P0 the track's covariance at
initiation. ``threshold`` is a chi-square(4) quantile (our choice: 0.99, 13.28) since P0 is the
state uncertainty a fresh track claims. A confirmed track that fails the test is a confirmed false
track (CFT). Per scan and run we record: whether some CTT exists (CTT rate = mean over runs), the
number of CFTs, and the position error of the CTT with the highest existence (range RMSE over runs
with a CTT).
"""

from __future__ import annotations

import numpy as np

CTT_CHI2_4DOF_99 = 13.2767


def ctt_test(x_true, x_hat, P_init, threshold: float = CTT_CHI2_4DOF_99) -> np.ndarray:
    """Confirmed-true-track test, Park, Song, Lee 2017, eq. 23: ``(x - x_hat)^T P_init^-1 (x - x_hat) < threshold``.

    Parameters
    ----------
    x_true : array_like, shape (d,)
        True target state ([x, y, vx, vy] in m and m/s).
    x_hat : array_like, shape (n, d)
        Tracks' combined estimates.
    P_init : array_like, shape (n, d, d)
        Tracks' covariances at initiation.
    threshold : float, default 13.2767
        Chi-square(4) 0.99 quantile.

    Returns
    -------
    ndarray of bool, shape (n,)
        True for each track that passes.
    """
    d = np.asarray(x_true, float)[None, :] - np.asarray(x_hat, float)
    sol = np.linalg.solve(np.asarray(P_init, float), d[..., None])[..., 0]
    return np.einsum("ni,ni->n", d, sol) < threshold


def scan_ctt_measures(x_true, x_hat, P_init, confirmed, existence, threshold: float = CTT_CHI2_4DOF_99):
    """CTT measures of one scan for one target (module docstring).

    Parameters
    ----------
    x_true : array_like, shape (d,)
        True target state (m, m/s).
    x_hat : array_like, shape (n, d)
        Tracks' combined estimates.
    P_init : array_like, shape (n, d, d)
        Tracks' covariances at initiation.
    confirmed : array_like of bool, shape (n,)
        Which tracks are confirmed.
    existence : array_like, shape (n,)
        Tracks' existence probabilities (picks the best CTT).
    threshold : float, default 13.2767
        Threshold of :func:`ctt_test`.

    Returns
    -------
    has_ctt : bool
        Whether some confirmed track is a CTT.
    n_false_confirmed : int
        Confirmed tracks that fail the test.
    position_error_m : float
        Position error of the CTT with the highest existence (m); NaN without a CTT.
    index : int
        That track's index, or -1.
    """
    conf = np.asarray(confirmed, bool)
    if not conf.any():
        return False, 0, np.nan, -1
    idx = np.nonzero(conf)[0]
    ok = ctt_test(x_true, np.asarray(x_hat)[idx], np.asarray(P_init)[idx], threshold)
    n_false = int((~ok).sum())
    if not ok.any():
        return False, n_false, np.nan, -1
    cand = idx[ok]
    best = cand[np.argmax(np.asarray(existence)[cand])]
    err = float(np.hypot(*(np.asarray(x_hat)[best, :2] - np.asarray(x_true)[:2])))
    return True, n_false, err, int(best)


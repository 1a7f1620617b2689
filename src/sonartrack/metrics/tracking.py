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
    """Eq. 23 for each track: ``(x - x_hat)^T P_init^-1 (x - x_hat) < threshold`` (bool (n,))."""
    d = np.asarray(x_true, float)[None, :] - np.asarray(x_hat, float)
    sol = np.linalg.solve(np.asarray(P_init, float), d[..., None])[..., 0]
    return np.einsum("ni,ni->n", d, sol) < threshold


def scan_ctt_measures(x_true, x_hat, P_init, confirmed, existence, threshold: float = CTT_CHI2_4DOF_99):
    """CTT measures of one scan: (has_ctt, n_false_confirmed, position_error_m, index of the CTT or -1)."""
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


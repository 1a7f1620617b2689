"""Compiled single-track PDA update (numba): the hot path for one track and a scan of measurements.

Same equations as association/pda.py (parametric PDA with per-measurement covariances; see there),
written as loops over measurements so that numba compiles them to a few microseconds. The NumPy
``pda_update_batch`` is the reference it is tested against. Compiled lazily on first call (and cached
on disk), so ``import sonartrack`` does not pay for it.
"""

from __future__ import annotations

import numpy as np

_KERNEL = None


def _build():
    from numba import njit

    @njit(cache=True, fastmath=False)
    def kernel(x, P, z, R, pd, pg, gamma, log_rho):  # pragma: no cover - compiled
        n = x.shape[0]
        m = z.shape[0]
        shared_R, shared_rho = R.shape[0] == 1, log_rho.shape[0] == 1  # one R (rho) for every measurement
        miss = 1.0 - pd * pg
        ratio = np.zeros(m)
        Sinv = np.empty((m, 2, 2))
        nu = np.empty((m, 2))
        lam = miss
        for j in range(m):
            jr = 0 if shared_R else j
            a = P[0, 0] + R[jr, 0, 0]
            b = P[0, 1] + R[jr, 0, 1]
            c = P[1, 0] + R[jr, 1, 0]
            d = P[1, 1] + R[jr, 1, 1]
            det = a * d - b * c
            if not det > 0.0:
                raise ValueError("innovation covariance is singular or not positive definite")
            Sinv[j, 0, 0] = d / det
            Sinv[j, 0, 1] = -b / det
            Sinv[j, 1, 0] = -c / det
            Sinv[j, 1, 1] = a / det
            nu0 = z[j, 0] - x[0]
            nu1 = z[j, 1] - x[1]
            nu[j, 0] = nu0
            nu[j, 1] = nu1
            d2 = nu0 * (Sinv[j, 0, 0] * nu0 + Sinv[j, 0, 1] * nu1) + nu1 * (Sinv[j, 1, 0] * nu0 + Sinv[j, 1, 1] * nu1)
            if d2 < gamma:
                lr = -0.5 * (2.0 * np.log(2.0 * np.pi) + np.log(det) + d2) - log_rho[0 if shared_rho else j]
                ratio[j] = np.exp(min(lr, 700.0))
                lam += pd * ratio[j]
        beta0 = miss / lam
        beta = pd * ratio / lam
        acc_x = np.zeros(n)
        acc_P = np.zeros((n, n))
        K = np.empty((n, 2))
        dx = np.empty(n)
        for j in range(m):
            bj = beta[j]
            if bj == 0.0:
                continue
            for r in range(n):
                K[r, 0] = P[r, 0] * Sinv[j, 0, 0] + P[r, 1] * Sinv[j, 1, 0]
                K[r, 1] = P[r, 0] * Sinv[j, 0, 1] + P[r, 1] * Sinv[j, 1, 1]
                dx[r] = K[r, 0] * nu[j, 0] + K[r, 1] * nu[j, 1]
            for r in range(n):
                acc_x[r] += bj * dx[r]
                for s in range(n):
                    # P_j + dx dx^T with P_j = P - K H P (H selects the position rows)
                    acc_P[r, s] += bj * (P[r, s] - K[r, 0] * P[0, s] - K[r, 1] * P[1, s] + dx[r] * dx[s])
        x_upd = x + acc_x
        P_upd = np.empty((n, n))
        for r in range(n):
            for s in range(n):
                P_upd[r, s] = beta0 * P[r, s] + acc_P[r, s] - acc_x[r] * acc_x[s]
        for r in range(n):
            for s in range(r + 1, n):
                v = 0.5 * (P_upd[r, s] + P_upd[s, r])
                P_upd[r, s] = v
                P_upd[s, r] = v
        return x_upd, P_upd, beta0, beta

    return kernel


def pda_update_fast(x_pred, P_pred, z, R, *, pd: float, pg: float, gamma: float, clutter_density):
    """Single-track PDA update, compiled: same arguments and results as :func:`association.pda.pda_update`.

    Parameters
    ----------
    x_pred, P_pred, z, R, pd, pg, gamma, clutter_density
        As :func:`~sonartrack.association.pda.pda_update`: the predicted state (position [x, y] (m) first) and its
        covariance, the measured positions (m) and their covariances (m^2), P_D, P_G, gate, clutter (per m^2).

    Returns
    -------
    x, P, beta0, beta
        As ``pda_update``.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the kernel finds a covariance that is not positive definite.
    """
    global _KERNEL
    if _KERNEL is None:
        _KERNEL = _build()
    z = np.ascontiguousarray(z, dtype=float).reshape(-1, 2)
    m = len(z)
    R = np.asarray(R, float)
    if R.shape == (2, 2):  # shared by every measurement: the kernel reads R[0] (no (m, 2, 2) copy)
        R = R.reshape(1, 2, 2)
    R = np.ascontiguousarray(R if R.shape in ((1, 2, 2), (m, 2, 2)) else np.broadcast_to(R, (m, 2, 2)))
    log_rho = np.log(np.asarray(clutter_density, float).reshape(-1))  # one value (kernel reads [0]) or (m,)
    if len(log_rho) not in (1, m):
        log_rho = np.ascontiguousarray(np.broadcast_to(log_rho, (m,)))
    try:
        return _KERNEL(np.ascontiguousarray(x_pred, dtype=float), np.ascontiguousarray(P_pred, dtype=float), z, R,
                       float(pd), float(pg), float(gamma), log_rho)
    except ValueError as exc:  # numba raises ValueError from the kernel
        raise np.linalg.LinAlgError(str(exc)) from None

"""Compiled single-track IMM-KF step (numba), the same cycle as filters/imm_kf.imm_kf_step.

Mixing, per-mode KF predict and Joseph update, mode probabilities, combination (equations in
filters/imm.py and filters/kalman.py), as one compiled function: one track's IMM step with a few
modes costs microseconds instead of ~100 us of NumPy call overhead. Compiled lazily, cached on disk.
The NumPy ``imm_kf_step`` is the reference it is tested against.
"""

from __future__ import annotations

import numpy as np

_KERNEL = None


def _build():
    from numba import njit

    @njit(cache=True)
    def kernel(x, P, mu, z, F, Q, H, R, Pi):  # pragma: no cover - compiled
        r, n = x.shape
        m = z.shape[0]
        c = np.zeros(r)
        for j in range(r):
            for i in range(r):
                c[j] += Pi[i, j] * mu[i]
        x_out = np.empty((r, n))
        P_out = np.empty((r, n, n))
        loglik = np.empty(r)
        I = np.eye(n)
        for j in range(r):
            # mixing
            x0 = np.zeros(n)
            for i in range(r):
                w = Pi[i, j] * mu[i] / c[j] if c[j] > 0 else 0.0
                x0 += w * x[i]
            P0 = np.zeros((n, n))
            for i in range(r):
                w = Pi[i, j] * mu[i] / c[j] if c[j] > 0 else 0.0
                d = x[i] - x0
                P0 += w * (P[i] + np.outer(d, d))
            # predict
            xp = F[j] @ x0
            Pp = F[j] @ P0 @ F[j].T + Q[j]
            Pp = 0.5 * (Pp + Pp.T)
            # update (Joseph form)
            nu = z - H @ xp
            S = H @ Pp @ H.T + R
            S = 0.5 * (S + S.T)
            Sinv = np.linalg.inv(S)
            K = Pp @ H.T @ Sinv
            A = I - K @ H
            Pu = A @ Pp @ A.T + K @ R @ K.T
            x_out[j] = xp + K @ nu
            P_out[j] = 0.5 * (Pu + Pu.T)
            sign, logdet = np.linalg.slogdet(S)
            loglik[j] = -0.5 * (m * np.log(2.0 * np.pi) + logdet + nu @ Sinv @ nu)
        a = np.log(np.maximum(c, 1e-300)) + loglik
        amax = a.max()
        e = np.exp(a - amax)
        mu_new = e / e.sum()
        xc = np.zeros(n)
        for j in range(r):
            xc += mu_new[j] * x_out[j]
        Pc = np.zeros((n, n))
        for j in range(r):
            d = x_out[j] - xc
            Pc += mu_new[j] * (P_out[j] + np.outer(d, d))
        return x_out, P_out, mu_new, xc, 0.5 * (Pc + Pc.T)

    return kernel


def imm_kf_step_fast(x, P, mu, z, F, Q, H, R, Pi):
    """Compiled IMM-KF step; same arguments and results as ``filters.imm_kf.imm_kf_step``.

    ``F`` may be ``(n, n)`` (shared) or ``(r, n, n)``.
    """
    global _KERNEL
    if _KERNEL is None:
        _KERNEL = _build()
    x = np.ascontiguousarray(x, dtype=float)
    r = x.shape[0]
    F = np.ascontiguousarray(np.broadcast_to(np.asarray(F, float), (r,) + np.shape(F)[-2:]))
    return _KERNEL(x, np.ascontiguousarray(P, dtype=float), np.ascontiguousarray(mu, dtype=float),
                   np.ascontiguousarray(z, dtype=float), F, np.ascontiguousarray(Q, dtype=float),
                   np.ascontiguousarray(H, dtype=float), np.ascontiguousarray(R, dtype=float),
                   np.ascontiguousarray(Pi, dtype=float))

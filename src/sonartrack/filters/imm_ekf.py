"""IMM-EKF and IMM-MGEKF for bearing (+ frequency) passive TMA on the relative state [x, y, vx, vy, f0].

Yoo & Song (paper P2; DIGEST P2): the modes differ only in the target's process-noise intensity q_j
(m^2/s^3); each mode runs an EKF or an MGEKF (filters/ekf.py, filters/mgekf.py) on the relative
constant-velocity model (models/relative_motion.py) with the bearing + frequency measurement
(models/passive.py). One cycle, with the generic IMM pieces of filters/imm.py::

    mixing           c_j = sum_i Pi[i, j] mu_i,  mu_i|j = Pi[i, j] mu_i / c_j
                     x0_j = sum_i mu_i|j x_i,  P0_j = sum_i mu_i|j (P_i + (x_i - x0_j)(x_i - x0_j)^T)
    mode filter j    x-_j = F x0_j - u,  P-_j = F P0_j F^T + Q(q_j)
                     EKF / MGEKF update with z = [bearing, frequency] (or the bearing alone)
    mode likelihood  Lambda_j = N(nu_j; 0, S_j)   (bearing and frequency innovations together)
    mode update      mu_j = c_j Lambda_j / sum_l c_l Lambda_l
    combination      x = sum_j mu_j x_j,  P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T)

A single-model EKF/MGEKF is the one-mode case (Pi = [[1]]): mixing and combination are identities.

Two implementations of the same cycle:

* :func:`imm_bf_step_reference` -- NumPy, built from filters/imm.py, filters/ekf.py and
  filters/mgekf.py; readable, batched over modes; the reference in the tests.
* :func:`imm_bf_step` / :func:`run_imm_bf` -- a numba kernel (jitted on first use and cached on
  disk) of the same equations with R diagonal (bearing and frequency noises independent); one
  3-mode step costs a few microseconds, against ~0.2 ms for the NumPy version, which is what makes
  the Monte Carlo study and the 50 us budget possible. tests/filters/test_imm_ekf.py checks the
  kernel against the reference step by step.
"""

from __future__ import annotations

import math

import numpy as np

from sonartrack.filters.ekf import ekf_predict, ekf_update, gaussian_loglik
from sonartrack.filters.imm import imm_combine, imm_mix, imm_mixing, imm_mode_update, validate_transition_matrix
from sonartrack.filters.mgekf import mgekf_update
from sonartrack.models.passive import MIN_COS_DELTA, SOUND_SPEED_MPS, bf_jacobian, bf_measurement, modified_matrix
from sonartrack.models.relative_motion import relative_process_noise_stack, relative_transition

LOG_2PI = math.log(2.0 * math.pi)


def transition_matrix(n_modes: int, diagonal: float) -> np.ndarray:
    """Markov matrix with ``diagonal`` on the diagonal and the rest spread evenly over each row."""
    if n_modes == 1:
        return np.ones((1, 1))
    Pi = np.full((n_modes, n_modes), (1.0 - diagonal) / (n_modes - 1))
    np.fill_diagonal(Pi, diagonal)
    return validate_transition_matrix(Pi)


# ---------------------------------------------------------------------------------------------
# NumPy reference
# ---------------------------------------------------------------------------------------------
def imm_bf_step_reference(x, P, mu, z, u, dt_s, qs, Pi, R, *, modified: bool, q_f0: float = 0.0,
                          c: float = SOUND_SPEED_MPS):
    """One IMM cycle (NumPy). Returns ``(x_r, P_r, mu, x_comb, P_comb, log_lik_total)``.

    x (r, 5), P (r, 5, 5), mu (r,) at k-1; z (m,) = [bearing] or [bearing, frequency]; u (5,) the
    observer input (models/relative_motion.py); qs (r,) process-noise intensities; Pi (r, r);
    R (m, m); ``modified`` selects the MGEKF covariance update.
    """
    z = np.atleast_1d(np.asarray(z, dtype=float))
    m = z.shape[0]
    c_pred, w = imm_mixing(np.asarray(mu, float), np.asarray(Pi, float))
    x0, P0 = imm_mix(np.asarray(x, float), np.asarray(P, float), w)
    F = relative_transition(dt_s)
    Q = relative_process_noise_stack(dt_s, qs, q_f0)
    x_pred, P_pred = ekf_predict(x0, P0, F, Q, b=-np.asarray(u, float))
    hx = bf_measurement(x_pred, c)[..., :m]
    H = bf_jacobian(x_pred, c)[..., :m, :]
    if modified:
        G = modified_matrix(np.broadcast_to(z, hx.shape), x_pred, H)
        x_upd, P_upd, nu, S, S_inv = mgekf_update(x_pred, P_pred, z, hx, H, G, R)
    else:
        x_upd, P_upd, nu, S, S_inv = ekf_update(x_pred, P_pred, z, hx, H, R)
    log_lik = gaussian_loglik(nu, S, S_inv)
    mu_new, log_total = imm_mode_update(c_pred, log_lik)
    xc, Pc = imm_combine(mu_new, x_upd, P_upd)
    return x_upd, P_upd, mu_new, xc, Pc, float(log_total)


# ---------------------------------------------------------------------------------------------
# numba kernel (plain Python loops: jitted by _kernels() on first use)
# ---------------------------------------------------------------------------------------------
def _step_kernel(x, P, mu, zb, zf, use_f, u, dt, qs, q_f0, Pi, var_b, var_f, modified, c,
                 x_out, P_out, mu_out, xc, Pc):
    """The IMM cycle of the module docstring for one track; writes the outputs, returns
    log sum_j c_j Lambda_j (NaN if a mode's innovation covariance is singular)."""
    r = x.shape[0]
    n = 5
    m = 2 if use_f else 1
    # ---- interaction (mixing)
    cbar = np.zeros(r)
    for j in range(r):
        for i in range(r):
            cbar[j] += Pi[i, j] * mu[i]
    x0 = np.zeros((r, n))
    P0 = np.zeros((r, n, n))
    wij = np.zeros(r)
    for j in range(r):
        cj = cbar[j] if cbar[j] > 0.0 else 1.0
        for i in range(r):
            wij[i] = Pi[i, j] * mu[i] / cj
            for a in range(n):
                x0[j, a] += wij[i] * x[i, a]
        for i in range(r):
            for a in range(n):
                da = x[i, a] - x0[j, a]
                for b in range(n):
                    P0[j, a, b] += wij[i] * (P[i, a, b] + da * (x[i, b] - x0[j, b]))
    loglik = np.zeros(r)
    xp = np.zeros(n)
    Pp = np.zeros((n, n))
    H = np.zeros((2, n))
    G = np.zeros((2, n))
    nu = np.zeros(2)
    PHt = np.zeros((n, 2))
    K = np.zeros((n, 2))
    A = np.zeros((n, n))
    AP = np.zeros((n, n))
    Rd = np.zeros(2)
    Rd[0] = var_b
    Rd[1] = var_f
    for j in range(r):
        # ---- prediction: x- = F x0 - u, P- = F P0 F^T + Q
        for a in range(n):
            xp[a] = x0[j, a] - u[a]
        xp[0] += dt * x0[j, 2]
        xp[1] += dt * x0[j, 3]
        for a in range(n):
            for b in range(n):
                Pp[a, b] = P0[j, a, b]
        for b in range(n):
            Pp[0, b] += dt * Pp[2, b]
            Pp[1, b] += dt * Pp[3, b]
        for a in range(n):
            Pp[a, 0] += dt * Pp[a, 2]
            Pp[a, 1] += dt * Pp[a, 3]
        q = qs[j]
        q3, q2, q1 = q * dt**3 / 3.0, q * dt**2 / 2.0, q * dt
        Pp[0, 0] += q3
        Pp[1, 1] += q3
        Pp[0, 2] += q2
        Pp[2, 0] += q2
        Pp[1, 3] += q2
        Pp[3, 1] += q2
        Pp[2, 2] += q1
        Pp[3, 3] += q1
        Pp[4, 4] += q_f0 * dt
        # ---- measurement prediction and Jacobian
        X, Y, VX, VY, F0 = xp[0], xp[1], xp[2], xp[3], xp[4]
        r2 = X * X + Y * Y
        rr = math.sqrt(r2)
        for a in range(n):
            H[0, a] = 0.0
            H[1, a] = 0.0
        H[0, 0] = Y / r2
        H[0, 1] = -X / r2
        d = zb - math.atan2(X, Y)
        nu[0] = d - 2.0 * math.pi * math.ceil((d - math.pi) / (2.0 * math.pi))
        if use_f:
            rdot = (X * VX + Y * VY) / rr
            k = F0 / c
            wv = Y * VX - X * VY
            r3 = r2 * rr
            H[1, 0] = -k * Y * wv / r3
            H[1, 1] = k * X * wv / r3
            H[1, 2] = -k * X / rr
            H[1, 3] = -k * Y / rr
            H[1, 4] = 1.0 - rdot / c
            nu[1] = zf - F0 * (1.0 - rdot / c)
        # ---- gain: S = H P- H^T + R, K = P- H^T S^-1
        for a in range(n):
            for l in range(m):
                s = 0.0
                for b in range(n):
                    s += Pp[a, b] * H[l, b]
                PHt[a, l] = s
        s00 = var_b
        for b in range(n):
            s00 += H[0, b] * PHt[b, 0]
        if m == 2:
            s01 = 0.0
            s11 = var_f
            for b in range(n):
                s01 += H[0, b] * PHt[b, 1]
                s11 += H[1, b] * PHt[b, 1]
            det = s00 * s11 - s01 * s01
            if not det > 0.0:
                return np.nan
            i00, i01, i11 = s11 / det, -s01 / det, s00 / det
            for a in range(n):
                K[a, 0] = PHt[a, 0] * i00 + PHt[a, 1] * i01
                K[a, 1] = PHt[a, 0] * i01 + PHt[a, 1] * i11
            d2 = nu[0] * nu[0] * i00 + 2.0 * nu[0] * nu[1] * i01 + nu[1] * nu[1] * i11
            logdet = math.log(det)
        else:
            if not s00 > 0.0:
                return np.nan
            for a in range(n):
                K[a, 0] = PHt[a, 0] / s00
            d2 = nu[0] * nu[0] / s00
            logdet = math.log(s00)
        loglik[j] = -0.5 * (m * LOG_2PI + logdet + d2)
        for a in range(n):
            s = xp[a]
            for l in range(m):
                s += K[a, l] * nu[l]
            x_out[j, a] = s
        # ---- covariance: (I - K G) P- (I - K G)^T + K R K^T, G = H or the modified matrix
        for l in range(m):
            for a in range(n):
                G[l, a] = H[l, a]
        if modified:
            sz, cz = math.sin(zb), math.cos(zb)
            den = X * sz + Y * cz
            if den > MIN_COS_DELTA * rr:
                G[0, 0] = cz / den
                G[0, 1] = -sz / den
        for a in range(n):
            for b in range(n):
                s = 1.0 if a == b else 0.0
                for l in range(m):
                    s -= K[a, l] * G[l, b]
                A[a, b] = s
        for a in range(n):
            for b in range(n):
                s = 0.0
                for e in range(n):
                    s += A[a, e] * Pp[e, b]
                AP[a, b] = s
        for a in range(n):
            for b in range(a, n):
                s = 0.0
                for e in range(n):
                    s += AP[a, e] * A[b, e]
                for l in range(m):
                    s += K[a, l] * Rd[l] * K[b, l]
                P_out[j, a, b] = s
                P_out[j, b, a] = s
    # ---- mode probabilities (log space) and combination
    amax = -np.inf
    la = np.zeros(r)
    for j in range(r):
        la[j] = math.log(max(cbar[j], 1e-300)) + loglik[j]
        if la[j] > amax:
            amax = la[j]
    tot = 0.0
    for j in range(r):
        la[j] = math.exp(la[j] - amax)
        tot += la[j]
    for j in range(r):
        mu_out[j] = la[j] / tot
    for a in range(n):
        s = 0.0
        for j in range(r):
            s += mu_out[j] * x_out[j, a]
        xc[a] = s
    for a in range(n):
        for b in range(a, n):
            s = 0.0
            for j in range(r):
                s += mu_out[j] * (P_out[j, a, b] + (x_out[j, a] - xc[a]) * (x_out[j, b] - xc[b]))
            Pc[a, b] = s
            Pc[b, a] = s
    return math.log(tot) + amax


def _run_kernel(times, zb, zf, use_f, u, x0, P0, mu0, qs, q_f0, Pi, var_b, var_f, modified, c,
                xc_hist, Pc_hist, mu_hist):
    """Filter a whole record: initial estimate at times[0], one IMM cycle per later time.
    Returns the index of the first step that failed (NaN estimate or singular S), or -1."""
    r = x0.shape[0]
    n_t = times.shape[0]
    x = x0.copy()
    P = P0.copy()
    mu = mu0.copy()
    x_new = np.zeros_like(x)
    P_new = np.zeros_like(P)
    mu_new = np.zeros(r)
    xc = np.zeros(5)
    Pc = np.zeros((5, 5))
    for a in range(5):
        s = 0.0
        for j in range(r):
            s += mu[j] * x[j, a]
        xc_hist[0, a] = s
    for a in range(5):
        for b in range(5):
            s = 0.0
            for j in range(r):
                s += mu[j] * (P[j, a, b] + (x[j, a] - xc_hist[0, a]) * (x[j, b] - xc_hist[0, b]))
            Pc_hist[0, a, b] = s
    for j in range(r):
        mu_hist[0, j] = mu[j]
    for k in range(1, n_t):
        ll = _step_kernel(x, P, mu, zb[k], zf[k], use_f[k], u[k - 1], times[k] - times[k - 1], qs, q_f0, Pi,
                          var_b, var_f, modified, c, x_new, P_new, mu_new, xc, Pc)
        if not math.isfinite(ll) or not math.isfinite(xc[0] + xc[1] + Pc[0, 0] + Pc[1, 1]):
            return k
        x[:, :] = x_new
        P[:, :, :] = P_new
        mu[:] = mu_new
        xc_hist[k, :] = xc
        Pc_hist[k, :, :] = Pc
        mu_hist[k, :] = mu
    return -1


_JIT: dict = {}


def _kernels():
    """Jit the kernels on first use (numba is a heavy import); cached on disk between processes."""
    if not _JIT:
        import numba

        g = globals()
        # error_model="numpy": a division by zero gives inf/NaN (caught as a failed step), not an
        # exception. _run_kernel calls _step_kernel through the module global, so that name must be the
        # compiled dispatcher before _run_kernel is compiled; the Python source stays in .py_func.
        if not hasattr(g["_step_kernel"], "py_func"):
            g["_step_kernel"] = numba.njit(cache=True, error_model="numpy")(g["_step_kernel"])
        if not hasattr(g["_run_kernel"], "py_func"):
            g["_run_kernel"] = numba.njit(cache=True, error_model="numpy")(g["_run_kernel"])
        _JIT["step"] = g["_step_kernel"]
        _JIT["run"] = g["_run_kernel"]
    return _JIT


def imm_bf_step(x, P, mu, z, u, dt_s, qs, Pi, var_b, var_f, *, modified: bool, q_f0: float = 0.0,
                c: float = SOUND_SPEED_MPS, out=None):
    """One IMM cycle with the numba kernel (same equations and returns as the reference, R diagonal).

    z is [bearing] or [bearing, frequency]. ``out``: optional preallocated
    ``(x_r, P_r, mu, x_comb, P_comb)`` arrays, reused to avoid allocation in a tight loop.
    """
    step = _kernels()["step"]
    r = x.shape[0]
    if out is None:
        out = (np.empty((r, 5)), np.empty((r, 5, 5)), np.empty(r), np.empty(5), np.empty((5, 5)))
    use_f = len(z) > 1
    ll = step(x, P, mu, float(z[0]), float(z[1]) if use_f else 0.0, use_f, u, float(dt_s), qs, float(q_f0), Pi,
              float(var_b), float(var_f), bool(modified), float(c), *out)
    return (*out, ll)


def run_imm_bf(times_s, bearing_rad, frequency_hz, u, x0, P0, *, qs, Pi=None, mu0=None, sigma_bearing_rad: float,
               sigma_freq_hz: float = 1.0, modified: bool = True, q_f0: float = 0.0,
               c: float = SOUND_SPEED_MPS, engine: str = "numba"):
    """Run an IMM (or, with one q, a single) EKF/MGEKF over a record.

    times_s (n,), bearing_rad (n,), frequency_hz (n,) or None (bearings only; NaN entries mean "no
    frequency at that time"), u (n - 1, 5) observer inputs, x0 (5,) and P0 (5, 5) the estimate at
    times_s[0] (given to every mode). Returns ``(x (n, 5), P (n, 5, 5), mu (n, r), failed_at)``;
    after a numerical failure at step k (``failed_at = k``, else -1) the rows from k on are NaN.
    ``engine="reference"`` runs the NumPy reference step instead of the kernel.
    """
    # fresh writeable C arrays: numba compiles one specialisation per layout/readonly flag
    t = _c(times_s)
    n_t = len(t)
    qs = _c(np.atleast_1d(qs))
    r = len(qs)
    Pi = transition_matrix(1, 1.0) if Pi is None and r == 1 else _c(Pi)
    mu0 = np.full(r, 1.0 / r) if mu0 is None else _c(mu0)
    zb = _c(bearing_rad)
    if frequency_hz is None:
        zf = np.zeros(n_t)
        use_f = np.zeros(n_t, dtype=np.bool_)
    else:
        zf = _c(frequency_hz)
        use_f = np.isfinite(zf)
        zf = np.where(use_f, zf, 0.0)
    u = _c(u).reshape(max(n_t - 1, 0), 5)
    xs = _c(np.broadcast_to(np.asarray(x0, float), (r, 5)))
    Ps = _c(np.broadcast_to(np.asarray(P0, float), (r, 5, 5)))
    xh = np.full((n_t, 5), np.nan)
    Ph = np.full((n_t, 5, 5), np.nan)
    mh = np.full((n_t, r), np.nan)
    if engine == "numba":
        failed = int(_kernels()["run"](t, zb, zf, use_f, u, xs, Ps, mu0, qs, float(q_f0), Pi,
                                       float(sigma_bearing_rad) ** 2, float(sigma_freq_hz) ** 2, bool(modified),
                                       float(c), xh, Ph, mh))
    elif engine == "reference":
        failed = _run_reference(t, zb, zf, use_f, u, xs, Ps, mu0, qs, q_f0, Pi, sigma_bearing_rad, sigma_freq_hz,
                                modified, c, xh, Ph, mh)
    else:
        raise ValueError(f"unknown engine {engine!r}")
    return xh, Ph, mh, failed


def _c(a) -> np.ndarray:
    return np.array(a, dtype=float, order="C", copy=True)


def _run_reference(t, zb, zf, use_f, u, x, P, mu, qs, q_f0, Pi, sb, sf, modified, c, xh, Ph, mh) -> int:
    xh[0], Ph[0] = imm_combine(mu, x, P)
    mh[0] = mu
    for k in range(1, len(t)):
        if use_f[k]:
            z, R = np.array([zb[k], zf[k]]), np.diag([sb**2, sf**2])
        else:
            z, R = np.array([zb[k]]), np.array([[sb**2]])
        try:
            with np.errstate(all="ignore"):
                x, P, mu, xc, Pc, ll = imm_bf_step_reference(x, P, mu, z, u[k - 1], t[k] - t[k - 1], qs, Pi, R,
                                                             modified=modified, q_f0=q_f0, c=c)
        except np.linalg.LinAlgError:
            return k
        if not (np.isfinite(ll) and np.all(np.isfinite(xc)) and np.all(np.isfinite(Pc))):
            return k
        xh[k], Ph[k], mh[k] = xc, Pc, mu
    return -1

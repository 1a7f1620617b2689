"""Compiled IMM-EKF / IMM-MGEKF cycle for bearing (+ frequency) TMA (numba), one named step per equation.

The equations are those of tma/imm_mgekf.py (Yoo & Song, paper P2; the IMM of Blom & Bar-Shalom
1988; the MGEKF of Song & Speyer 1985); the NumPy reference ``imm_bf_step_reference`` there is what
these kernels are tested against, step by step (tests/tma/test_imm_mgekf.py). State of each mode:
X = [x, y, vx, vy, f0] (models/relative_motion.py); measurement z = [bearing] or [bearing,
frequency], with R = diag(var_b, var_f) (independent noises).

One cycle (:func:`cycle`; :func:`imm_step` runs one, :func:`run_record` a whole record) is::

    mix                    c_j, mu_i|j, x0_j, P0_j                      (interaction)
    for each mode j:
        predict            x- = F x0_j - u,  P- = F P0_j F^T + Q(q_j)
        innovation         nu = z - h(x-) (bearing wrapped), H = dh/dx at x-
        gain               S = H P- H^T + R,  K = P- H^T S^-1,  log Lambda_j = log N(nu; 0, S)
        update_mean        x+ = x- + K nu
        covariance_rows    G = H, or the MGEKF modified matrix (bearing row g(z, x-))
        joseph_covariance  P+ = (I - K G) P- (I - K G)^T + K R K^T
    mode_probabilities     mu_j = c_j Lambda_j / sum_l c_l Lambda_l  (log space)
    combine                x = sum_j mu_j x_j,  P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T)

The model constants travel in one small float array, ``consts = [var_b, var_f, q_f0, c]`` (indices
:data:`VAR_B`, :data:`VAR_F`, :data:`Q_F0`, :data:`SOUND_SPEED`): fewer arguments make the call from
Python cheaper. ``error_model="numpy"``: a division by zero gives inf/NaN (reported as a failed step),
never an exception. Importing this module imports numba: tma/imm_mgekf.py imports it on first use.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numba
import numpy as np

from sonartrack.models.passive import MIN_COS_DELTA

#: indices of the ``consts`` array: bearing variance (rad^2), frequency variance (Hz^2), f0 random-walk
#: intensity (Hz^2/s), speed of sound (m/s)
VAR_B, VAR_F, Q_F0, SOUND_SPEED = 0, 1, 2, 3
N_STATE = 5
LOG_2PI = math.log(2.0 * math.pi)

_jit = numba.njit(cache=True, error_model="numpy")
#: the steps of the cycle are inlined into their caller at numba IR level: as separate calls they cost
#: ~70 % more per cycle (measured: array views, reference counts, no optimisation across the calls)
_step = numba.njit(cache=True, error_model="numpy", inline="always")


@_step
def mix(x, P, mu, Pi, c_pred, w, x0, P0):
    """Interaction: c_j = sum_i Pi[i, j] mu_i;  w_i = mu_i|j = Pi[i, j] mu_i / c_j;
    x0_j = sum_i w_i x_i;  P0_j = sum_i w_i (P_i + (x_i - x0_j)(x_i - x0_j)^T). Writes c_pred, w, x0, P0.

    Parameters
    ----------
    x, P : ndarray, shape (r, 5), (r, 5, 5)
        Mode estimates at k-1 (m, m/s, Hz).
    mu : ndarray, shape (r,)
        Mode probabilities at k-1.
    Pi : ndarray, shape (r, r)
        Markov matrix, Pi[i, j] = P(mode j at k | mode i at k-1).
    c_pred, w, x0, P0 : ndarray, shapes (r,), (r,), (r, 5), (r, 5, 5)
        Outputs: predicted mode probabilities, scratch mixing weights, mixed means and covariances.
    """
    r, n = x.shape[0], N_STATE
    for j in range(r):
        s = 0.0
        for i in range(r):
            s += Pi[i, j] * mu[i]
        c_pred[j] = s
    for j in range(r):
        cj = c_pred[j] if c_pred[j] > 0.0 else 1.0
        for i in range(r):
            w[i] = Pi[i, j] * mu[i] / cj
        x0[j, :] = 0.0
        P0[j, :, :] = 0.0
        for i in range(r):
            for a in range(n):
                x0[j, a] += w[i] * x[i, a]
        for i in range(r):
            for a in range(n):
                da = x[i, a] - x0[j, a]
                for b in range(n):
                    P0[j, a, b] += w[i] * (P[i, a, b] + da * (x[i, b] - x0[j, b]))


@_step
def predict(x0, P0, j, u, dt, q, q_f0, xp, Pp):
    """Mode j's prediction from its mixed estimate x0[j], P0[j] (P2 eq. 2 discretised, models/relative_motion.py):
    x- = F x0 - u,  P- = F P0 F^T + Q, with F = [[I, dt I, 0], [0, I, 0], [0, 0, 1]] applied as row/column
    operations and Q = [[q dt^3/3 I, q dt^2/2 I, 0], [q dt^2/2 I, q dt I, 0], [0, 0, q_f0 dt]]. Writes xp, Pp.

    Parameters
    ----------
    x0, P0 : ndarray, shape (r, 5), (r, 5, 5)
        Mixed estimates.
    j : int
        The mode.
    u : ndarray, shape (5,)
        Observer input over the step (m, m/s, Hz).
    dt : float
        Step (s).
    q : float
        Mode j's acceleration noise intensity (m^2/s^3).
    q_f0 : float
        Random-walk intensity of f0 (Hz^2/s).
    xp, Pp : ndarray, shape (5,), (5, 5)
        Outputs: predicted mean and covariance.
    """
    n = N_STATE
    for a in range(n):
        xp[a] = x0[j, a] - u[a]
    xp[0] += dt * x0[j, 2]
    xp[1] += dt * x0[j, 3]
    for a in range(n):
        for b in range(n):
            Pp[a, b] = P0[j, a, b]
    for b in range(n):  # F P0: rows 0, 1 gain dt x rows 2, 3
        Pp[0, b] += dt * Pp[2, b]
        Pp[1, b] += dt * Pp[3, b]
    for a in range(n):  # (F P0) F^T: columns 0, 1 gain dt x columns 2, 3
        Pp[a, 0] += dt * Pp[a, 2]
        Pp[a, 1] += dt * Pp[a, 3]
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


@_step
def innovation(xp, z, use_f, c, H, nu):
    """Innovation nu = z - h(x-) and Jacobian H = dh/dx at x- (P2 eq. 3, models/passive.py)::

        bearing    h_b = atan2(x, y),         H_b = [y / r^2, -x / r^2, 0, 0, 0],   nu_b wrapped to (-pi, pi]
        frequency  h_f = f0 (1 - rdot / c),  H_f = [-k y w / r^3, k x w / r^3, -k x / r, -k y / r, 1 - rdot / c]

    with r^2 = x^2 + y^2, rdot = (x vx + y vy) / r, w = y vx - x vy, k = f0 / c. Writes H, nu.

    Parameters
    ----------
    xp : ndarray, shape (5,)
        Predicted state [x, y, vx, vy, f0] (m, m/s, Hz).
    z : ndarray, shape (1,) or (2,)
        Bearing (rad clockwise from north) and frequency (Hz).
    use_f : bool
        Use the frequency row.
    c : float
        Speed of sound (m/s).
    H, nu : ndarray, shape (2, 5), (2,)
        Outputs (only the first 1 or 2 rows/entries are meaningful).
    """
    X, Y, VX, VY, F0 = xp[0], xp[1], xp[2], xp[3], xp[4]
    r2 = X * X + Y * Y
    rr = math.sqrt(r2)
    for a in range(N_STATE):
        H[0, a] = 0.0
        H[1, a] = 0.0
    H[0, 0] = Y / r2
    H[0, 1] = -X / r2
    d = z[0] - math.atan2(X, Y)
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
        nu[1] = z[1] - F0 * (1.0 - rdot / c)


@_step
def gain(Pp, H, nu, m, var_b, var_f, PHt, K):
    """S = H P- H^T + R (R = diag(var_b, var_f)),  K = P- H^T S^-1 (S inverted in closed form, m = 1 or 2).

    Writes PHt, K; returns the mode log-likelihood log N(nu; 0, S) = -(m log 2 pi + log det S + nu^T S^-1 nu) / 2,
    or NaN when S is not positive definite.

    Parameters
    ----------
    Pp : ndarray, shape (5, 5)
        Predicted covariance.
    H : ndarray, shape (2, 5)
        Jacobian (first m rows used).
    nu : ndarray, shape (2,)
        Innovation (first m entries used).
    m : int
        Measured entries, 1 (bearing) or 2 (bearing and frequency).
    var_b, var_f : float
        Bearing (rad^2) and frequency (Hz^2) noise variances.
    PHt, K : ndarray, shape (5, 2)
        Outputs: P- H^T and the gain.

    Returns
    -------
    float
        log N(nu; 0, S), NaN when S is not positive definite.
    """
    n = N_STATE
    for a in range(n):
        for row in range(m):
            s = 0.0
            for b in range(n):
                s += Pp[a, b] * H[row, b]
            PHt[a, row] = s
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
    return -0.5 * (m * LOG_2PI + logdet + d2)


@_step
def update_mean(xp, K, nu, m, x_new, j):
    """x+ = x- + K nu. Writes x_new[j].

    Parameters
    ----------
    xp : ndarray, shape (5,)
        Predicted mean.
    K : ndarray, shape (5, 2)
        Gain (first m columns used).
    nu : ndarray, shape (2,)
        Innovation.
    m : int
        Measured entries (1 or 2).
    x_new : ndarray, shape (r, 5)
        Output: row j is written.
    j : int
        The mode.
    """
    for a in range(N_STATE):
        s = xp[a]
        for row in range(m):
            s += K[a, row] * nu[row]
        x_new[j, a] = s


@_step
def covariance_rows(xp, z_b, H, m, modified, G):
    """The rows G of the covariance update: the Jacobian H (EKF), or for the MGEKF H with its bearing row
    replaced by Song & Speyer's g = [cos z, -sin z, 0, 0, 0] / (x sin z + y cos z) at the measured bearing z
    (models/passive.py; the Jacobian row is kept where the denominator is below MIN_COS_DELTA r). Writes G.

    Parameters
    ----------
    xp : ndarray, shape (5,)
        Predicted state.
    z_b : float
        Measured bearing (rad clockwise from north).
    H : ndarray, shape (2, 5)
        Jacobian.
    m : int
        Measured entries (1 or 2).
    modified : bool
        MGEKF (True) or EKF (False).
    G : ndarray, shape (2, 5)
        Output.
    """
    for row in range(m):
        for a in range(N_STATE):
            G[row, a] = H[row, a]
    if modified:
        sz, cz = math.sin(z_b), math.cos(z_b)
        den = xp[0] * sz + xp[1] * cz
        if den > MIN_COS_DELTA * math.sqrt(xp[0] * xp[0] + xp[1] * xp[1]):
            G[0, 0] = cz / den
            G[0, 1] = -sz / den


@_step
def joseph_covariance(Pp, K, G, m, r_diag, A, AP, P_new, j):
    """P+ = (I - K G) P- (I - K G)^T + K R K^T (Joseph form; symmetric by construction). Writes A, AP, P_new[j].

    Parameters
    ----------
    Pp : ndarray, shape (5, 5)
        Predicted covariance.
    K : ndarray, shape (5, 2)
        Gain.
    G : ndarray, shape (2, 5)
        Rows of the covariance update (:func:`covariance_rows`).
    m : int
        Measured entries (1 or 2).
    r_diag : ndarray, shape (2,)
        Diagonal of R (rad^2, Hz^2).
    A, AP : ndarray, shape (5, 5)
        Scratch.
    P_new : ndarray, shape (r, 5, 5)
        Output: mode j is written.
    j : int
        The mode.
    """
    n = N_STATE
    for a in range(n):
        for b in range(n):
            s = 1.0 if a == b else 0.0
            for row in range(m):
                s -= K[a, row] * G[row, b]
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
            for row in range(m):
                s += K[a, row] * r_diag[row] * K[b, row]
            P_new[j, a, b] = s
            P_new[j, b, a] = s


@_step
def mode_probabilities(c_pred, log_lik, mu_new):
    """mu_j = c_j Lambda_j / sum_l c_l Lambda_l, in log space (largest term factored out).
    Writes mu_new; returns log sum_j c_j Lambda_j (the IMM likelihood of the measurement).

    Parameters
    ----------
    c_pred : ndarray, shape (r,)
        Predicted mode probabilities c_j.
    log_lik : ndarray, shape (r,)
        Mode log-likelihoods log Lambda_j.
    mu_new : ndarray, shape (r,)
        Output: posterior mode probabilities.

    Returns
    -------
    float
        log sum_j c_j Lambda_j.
    """
    r = c_pred.shape[0]
    a_max = -np.inf
    for j in range(r):
        mu_new[j] = math.log(max(c_pred[j], 1e-300)) + log_lik[j]  # log c_j Lambda_j
        if mu_new[j] > a_max:
            a_max = mu_new[j]
    tot = 0.0
    for j in range(r):
        mu_new[j] = math.exp(mu_new[j] - a_max)
        tot += mu_new[j]
    for j in range(r):
        mu_new[j] = mu_new[j] / tot
    return math.log(tot) + a_max


@_step
def combine(mu, x, P, xc, Pc):
    """x = sum_j mu_j x_j,  P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T). Writes xc, Pc.

    Parameters
    ----------
    mu : ndarray, shape (r,)
        Mode probabilities.
    x, P : ndarray, shape (r, 5), (r, 5, 5)
        Mode estimates.
    xc, Pc : ndarray, shape (5,), (5, 5)
        Outputs: the combined estimate.
    """
    r, n = x.shape[0], N_STATE
    for a in range(n):
        s = 0.0
        for j in range(r):
            s += mu[j] * x[j, a]
        xc[a] = s
    for a in range(n):
        for b in range(a, n):
            s = 0.0
            for j in range(r):
                s += mu[j] * (P[j, a, b] + (x[j, a] - xc[a]) * (x[j, b] - xc[b]))
            Pc[a, b] = s
            Pc[b, a] = s


Workspace = namedtuple("Workspace", "c_pred w x0 P0 log_lik xp Pp H G nu PHt K A AP")


@_step
def workspace(r):
    """Scratch arrays of one cycle with r modes (allocated once per record, not once per step).

    Parameters
    ----------
    r : int
        Number of modes.

    Returns
    -------
    Workspace
        The named scratch arrays of :func:`cycle`.
    """
    n = N_STATE
    return Workspace(np.zeros(r), np.zeros(r), np.zeros((r, n)), np.zeros((r, n, n)), np.zeros(r), np.zeros(n),
                     np.zeros((n, n)), np.zeros((2, n)), np.zeros((2, n)), np.zeros(2), np.zeros((n, 2)),
                     np.zeros((n, 2)), np.zeros((n, n)), np.zeros((n, n)))


@_step
def cycle(x, P, mu, z, u, dt, qs, Pi, consts, modified, x_new, P_new, mu_new, xc, Pc, ws):
    """One IMM cycle (module docstring) for one track, in the scratch arrays ``ws``. Arguments and return as
    :func:`imm_step`.

    Parameters
    ----------
    x, P, mu, z, u, dt, qs, Pi, consts, modified, x_new, P_new, mu_new, xc, Pc
        As :func:`imm_step`.
    ws : Workspace
        Scratch arrays from :func:`workspace`.

    Returns
    -------
    float
        log sum_j c_j Lambda_j, NaN if some S is not positive definite.
    """
    r = x.shape[0]
    use_f = z.shape[0] > 1 and math.isfinite(z[1])
    m = 2 if use_f else 1
    mix(x, P, mu, Pi, ws.c_pred, ws.w, ws.x0, ws.P0)
    for j in range(r):
        predict(ws.x0, ws.P0, j, u, dt, qs[j], consts[Q_F0], ws.xp, ws.Pp)
        innovation(ws.xp, z, use_f, consts[SOUND_SPEED], ws.H, ws.nu)
        ws.log_lik[j] = gain(ws.Pp, ws.H, ws.nu, m, consts[VAR_B], consts[VAR_F], ws.PHt, ws.K)
        if math.isnan(ws.log_lik[j]):
            return np.nan
        update_mean(ws.xp, ws.K, ws.nu, m, x_new, j)
        covariance_rows(ws.xp, z[0], ws.H, m, modified, ws.G)
        joseph_covariance(ws.Pp, ws.K, ws.G, m, consts[VAR_B:VAR_F + 1], ws.A, ws.AP, P_new, j)
    total = mode_probabilities(ws.c_pred, ws.log_lik, mu_new)
    combine(mu_new, x_new, P_new, xc, Pc)
    return total


@_jit
def imm_step(x, P, mu, z, u, dt, qs, Pi, consts, modified, x_new, P_new, mu_new, xc, Pc):
    """One IMM cycle (module docstring) for one track. x (r, 5), P (r, 5, 5), mu (r,) at k-1; z (1,) or (2,)
    (a NaN frequency means none at this time); u (5,) observer input; qs (r,); Pi (r, r); consts as in the
    module docstring. Writes the mode estimates x_new, P_new, mu_new (which may be x, P, mu themselves: the
    inputs are read only before the first write) and the combination xc, Pc; returns log sum_j c_j Lambda_j,
    NaN if some S is singular.

    Parameters
    ----------
    x, P, mu : ndarray, shapes (r, 5), (r, 5, 5), (r,)
        Mode estimates [x, y, vx, vy, f0] (m, m/s, Hz) and probabilities at k-1.
    z : ndarray, shape (1,) or (2,)
        Bearing (rad clockwise from north) and frequency (Hz; NaN: none).
    u : ndarray, shape (5,)
        Observer input over the step.
    dt : float
        Step (s).
    qs : ndarray, shape (r,)
        Acceleration noise intensity of each mode (m^2/s^3).
    Pi : ndarray, shape (r, r)
        Mode transition matrix.
    consts : ndarray, shape (4,)
        [var_b (rad^2), var_f (Hz^2), q_f0 (Hz^2/s), c (m/s)].
    modified : bool
        MGEKF covariance rows (True) or EKF (False).
    x_new, P_new, mu_new, xc, Pc : ndarray
        Outputs.

    Returns
    -------
    float
        log sum_j c_j Lambda_j, NaN if some S is singular.
    """
    return cycle(x, P, mu, z, u, dt, qs, Pi, consts, modified, x_new, P_new, mu_new, xc, Pc, workspace(x.shape[0]))


@_jit
def run_record(times, z, u, x, P, mu, qs, Pi, consts, modified, xc_hist, Pc_hist, mu_hist):
    """Filter a whole record: the estimate (x, P, mu, updated in place) holds at times[0]; one IMM cycle per
    later time, z (n, 2) with NaN where a frequency is missing. Writes the combined estimates and mode
    probabilities at every time; returns the index of the first step that failed (NaN), or -1.

    Parameters
    ----------
    times : ndarray, shape (n,)
        Measurement times (s).
    z : ndarray, shape (n, 2)
        Bearings (rad clockwise from north) and frequencies (Hz; NaN: none).
    u : ndarray, shape (n - 1, 5)
        Observer input of each step.
    x, P, mu : ndarray, shapes (r, 5), (r, 5, 5), (r,)
        Mode estimates at times[0]; updated in place.
    qs, Pi, consts, modified
        As :func:`imm_step`.
    xc_hist, Pc_hist, mu_hist : ndarray, shapes (n, 5), (n, 5, 5), (n, r)
        Outputs: combined estimates and mode probabilities per time (NaN from the failed step).

    Returns
    -------
    int
        Index of the first failed step, or -1 when all succeeded.
    """
    combine(mu, x, P, xc_hist[0], Pc_hist[0])
    mu_hist[0, :] = mu
    ws = workspace(x.shape[0])
    for k in range(1, times.shape[0]):
        ll = cycle(x, P, mu, z[k], u[k - 1], times[k] - times[k - 1], qs, Pi, consts, modified,
                   x, P, mu, xc_hist[k], Pc_hist[k], ws)
        if not math.isfinite(ll) or not math.isfinite(xc_hist[k, 0] + xc_hist[k, 1] + Pc_hist[k, 0, 0]
                                                      + Pc_hist[k, 1, 1]):
            xc_hist[k, :] = np.nan
            Pc_hist[k, :, :] = np.nan
            return k
        mu_hist[k, :] = mu
    return -1

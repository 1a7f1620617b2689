"""A range-parameterised bank of sequential bearing (+ frequency) filters: one IMM-(MG)EKF per range subinterval,
weighted by its measurement likelihood (Peach 1995; Ristic, Arulampalam & Gordon 2004, ch. 6, the RPEKF, with
each EKF an IMM of tma/imm_mgekf.py).

Why. One filter started at a range guess with a range sd of half of it (the usual prior, coefficient of variation
C_R = sigma_r / r ~ 0.5) linearises the bearing about a point the truth may be far from; bearings-only, its gain
then shrinks the covariance along the range faster than the estimate converges (the EKF's known range collapse:
Aidala & Hammel, IEEE Trans. AC 28(3), 1983), and its NEES is many times chi-square's: measured on
tests/tma/test_imm_range_bank.py's turns, one IMM-MGEKF's ANEES was 20-40 before, during and after a turn against
[3.05, 5.07]. A filter started with a small C_R does not collapse (Peach), so the range interval
[r_min, r_max] is cut into N_F subintervals in geometric progression, each filter starting at its midpoint with
the sd of a range uniform over it::

    rho    = (r_max / r_min)^(1 / N_F)
    r_i    = r_min (rho^i + rho^(i-1)) / 2,        sd_i = r_min (rho^i - rho^(i-1)) / sqrt(12)
    C_R    = sd_i / r_i = 2 (rho - 1) / (sqrt(12) (rho + 1))      (the same for every i)

(Ristic et al. 2004, eqs. 6.18-6.21; the equal initial weights of a range uniform in log r). After each measurement
z_k each filter's weight is multiplied by its likelihood, the IMM's total p(z_k | Z_k-1, i) = sum_j c_j Lambda_j
(its modes' predicted probabilities c_j times their Gaussian likelihoods; tma/imm_mgekf.py's ``log_lik_total``)::

    w_i <- w_i p(z_k | Z_k-1, i) / sum_l w_l p(z_k | Z_k-1, l)

and the bank's estimate is the mixture's moments, x = sum_i w_i x_i, P = sum_i w_i (P_i + (x_i - x)(x_i - x)^T);
its mode probabilities are sum_i w_i mu_i. A filter whose weight falls below :data:`PRUNE_WEIGHT` is dropped (it
stays dropped: its weight only keeps falling while the data disagree with it; Peach prunes likewise).

Consistency (issue 30; tests/tma/test_range_bank_consistency.py, benchmarks/range_bank_nees.py): on targets drawn
from the bank's prior and its members' motion model the bank's ANEES lies in chi-square's interval (a bank of
constant-velocity MGEKFs on constant-velocity targets: 3.8 over 30 runs), so the mixture's spread between range
filters and the MGEKF's covariance rows do not bias it; with IMM members its NEES is below the interval where the
target has not manoeuvred for a while, a property of the IMM's modes (tma/settings.py ImmSettings), not of the bank.
A target passing within ~1 km of the ownship breaks every member's linearised bearing (NEES in the hundreds after a
28 m pass), turn or not.

The functions here take arrays (the filter's relative state [x, y, vx, vy, f0] of tma/sequential_bf.py) and return
arrays; tma/sequential_bf.py runs the bank for ``sequential.range_filters`` > 1.
"""

from __future__ import annotations

import math

import numpy as np

from sonartrack.core.errors import require
from sonartrack.tma.imm_mgekf import ImmBfModel, imm_bf_step

#: a filter whose weight falls below this is dropped from the bank (module doc)
PRUNE_WEIGHT = 1e-8


def range_subintervals(r_min_m: float, r_max_m: float, n_filters: int) -> tuple[np.ndarray, np.ndarray]:
    """Peach's range subintervals: each filter's initial range and range sd (module doc).

    Parameters
    ----------
    r_min_m, r_max_m : float
        The range interval (m), 0 < r_min < r_max.
    n_filters : int
        N_F >= 1.

    Returns
    -------
    range_m : ndarray, shape (N_F,)
        The subintervals' midpoints r_i (m).
    range_sd_m : ndarray, shape (N_F,)
        sd_i (m): the sd of a range uniform over the subinterval.
    """
    require(0.0 < r_min_m < r_max_m and math.isfinite(r_max_m),
            f"range interval [{r_min_m}, {r_max_m}] m: need 0 < r_min < r_max < inf")
    require(int(n_filters) >= 1, f"n_filters {n_filters}: need at least one range filter")
    rho = (r_max_m / r_min_m) ** (1.0 / n_filters)
    upper = rho ** np.arange(1, n_filters + 1)
    lower = upper / rho
    return r_min_m * (upper + lower) / 2.0, r_min_m * (upper - lower) / math.sqrt(12.0)


def mixture_moments(weight, x, P) -> tuple[np.ndarray, np.ndarray]:
    """The mean and covariance of a Gaussian mixture (moment matching).

    Parameters
    ----------
    weight : ndarray, shape (N,)
        Weights summing to 1.
    x : ndarray, shape (N, d)
        Means.
    P : ndarray, shape (N, d, d)
        Covariances.

    Returns
    -------
    mean : ndarray, shape (d,)
        sum_i w_i x_i.
    cov : ndarray, shape (d, d)
        sum_i w_i (P_i + (x_i - mean)(x_i - mean)^T).
    """
    w = np.asarray(weight, float)
    mean = w @ x
    d = x - mean
    return mean, np.einsum("i,ijk->jk", w, P) + np.einsum("i,ij,ik->jk", w, d, d)


def run_range_bank(times_s, z, u, x0, P0, model: ImmBfModel, *, mu0=None) -> tuple[np.ndarray, ...]:
    """Run the bank over a record (module doc): N_F filters from their own initial estimates.

    Parameters
    ----------
    times_s : ndarray, shape (n,)
        Measurement times (s).
    z : ndarray, shape (n, 2)
        Bearing (rad) and frequency (Hz; NaN: none) per time.
    u : ndarray, shape (n - 1, 5)
        Observer inputs (models/relative_motion.py).
    x0, P0 : ndarray, shapes (N_F, 5), (N_F, 5, 5)
        Each filter's initial relative estimate at times_s[0].
    model : ImmBfModel
        The IMM (or single filter) each member runs.
    mu0 : array_like, shape (r,), optional
        Every filter's initial mode probabilities (default equal; e.g. the Markov matrix's stationary law).

    Returns
    -------
    x : ndarray, shape (n, 5)
        The bank's mean.
    P : ndarray, shape (n, 5, 5)
        Its covariance.
    mu : ndarray, shape (n, r)
        Its mode probabilities.
    weight : ndarray, shape (n, N_F)
        The filters' weights (0 once dropped).
    failed_at : int
        The step at which every filter failed numerically (rows from it on NaN), or -1.
    """
    t = np.asarray(times_s, float)
    n, n_f, r = len(t), len(x0), len(model.qs)
    xs = np.repeat(np.array(x0, float)[:, None], r, axis=1)
    Ps = np.repeat(np.array(P0, float)[:, None], r, axis=1)
    mus = np.full((n_f, r), 1.0 / r) if mu0 is None else np.repeat(np.asarray(mu0, float)[None], n_f, axis=0)
    log_w = np.full(n_f, -np.log(n_f))
    out = (np.full((n, 5), np.nan), np.full((n, 5, 5), np.nan), np.full((n, r), np.nan), np.zeros((n, n_f)))
    _record(out, 0, np.exp(log_w), np.asarray(x0, float), np.asarray(P0, float), mus)
    xc, Pc = np.array(x0, float), np.array(P0, float)
    for k in range(1, n):
        alive = np.flatnonzero(np.isfinite(log_w))
        for i in alive:
            xi, Pi, mui, xci, Pci, ll = imm_bf_step(xs[i], Ps[i], mus[i], z[k], u[k - 1], t[k] - t[k - 1], model)
            ok = np.isfinite(ll) and np.all(np.isfinite(Pci))
            xs[i], Ps[i], mus[i], xc[i], Pc[i] = xi, Pi, mui, xci, Pci
            log_w[i] = log_w[i] + ll if ok else -np.inf
        if not np.isfinite(log_w).any():
            return (*out, k)
        log_w -= np.max(log_w)
        w = np.exp(log_w)
        w /= w.sum()
        log_w = np.where(w >= PRUNE_WEIGHT, np.log(np.maximum(w, 1e-300)), -np.inf)
        _record(out, k, np.where(np.isfinite(log_w), w, 0.0), xc, Pc, mus)
    return (*out, -1)


def _record(out, k: int, w, xc, Pc, mus) -> None:
    """Row k of the bank's output: the moments of its live filters (weights renormalised) and mode probabilities."""
    live = w > 0
    wl = w[live] / w[live].sum()
    out[0][k], out[1][k] = mixture_moments(wl, xc[live], Pc[live])
    out[2][k] = wl @ mus[live]
    out[3][k] = np.where(live, w / w[live].sum(), 0.0)

"""Measurement likelihoods of n tracks x r modes against m measurements: the input of every associator.

A measurement z (k entries) observes the first k entries of the state (H = [I_k 0]: position in the
position tracker, bearing in the bearing tracker). For track n, mode r, measurement m:

    nu = z_m - H x-_r,   S = H P-_r H^T + R,   d2 = nu^T S^-1 nu
    log p_rm / rho_m = -(k log 2 pi + log det S + d2) / 2 - log rho_m       (Gaussian over clutter)

and with P_D the detection probability and P_G the gate probability the association weights are
(Bar-Shalom, Daum, Huang 2009, eqs. 36-41; paper P0, appendix A):

    hit   w_rm = P_D p_rm / rho_m        miss   w_r0 = 1 - P_D P_G

Two gates: the chi-square gate d2 < gamma of any mode (P_G = F_chi2(gamma; k), association/gating.py)
and the bearing tracker's window |nu| <= V / 2 (P_G = erf(V / (2 sqrt(2 S))), paper P0).

The chi-square gate is evaluated in full only for the pairs that pass a cheap necessary test: since
nu^T S^-1 nu >= nu_i^2 / S_ii for every axis i of an SPD S, a pair with nu_i^2 > gamma S_ii on some axis
(in every mode) cannot be validated. With many tracks and a clutter-filled scan this skips most pairs;
the pairs it keeps are computed with exactly the same arithmetic as a dense evaluation would use.
The pre-gate, the kept pairs' innovations and the gate run compiled (association/likelihood_kernel.py:
a loop that stops at the first failing axis, over each track's window of the measurements sorted by
position), with the NumPy evaluation's results bit for bit; only the gated pairs leave it.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from sonartrack.core.gaussian import LOG_2PI, inv_and_logdet


@dataclass(frozen=True)
class Likelihoods:
    """Everything an associator and the PDA update need (n tracks, r modes, m measurements, k dims, G gated pairs).

    The log ratios are kept at the gated pairs (``pair_log_ratio``); the dense (n, r, m) array
    :attr:`log_ratio` is built on first use (the JPDA associator wants it; the PDA path never does, which
    spares it n x r x m work on a scan with thousands of contacts and tracks)."""

    pair_log_ratio: np.ndarray  # (G, r) log p_rm / rho_m (+ the amplitude log ratio for JPDA_A) of the gated pairs
    gated: np.ndarray  # (n, m) bool: measurement m validated by track n (union over modes)
    pd: np.ndarray | float  # (n,) P_D in the hit weight (or one value for every track)
    miss: np.ndarray | float  # (n, r) 1 - P_D P_G, the weight of "no measurement is the target's" (or one value)
    pair_track: np.ndarray  # (G,) the gated pairs (track, measurement), in the row-major order of ``gated``
    pair_meas: np.ndarray  # (G,)
    nu: np.ndarray  # (G, r, k) innovations of the gated pairs
    S_inv: np.ndarray  # (G, r, k, k) their inverse innovation covariances
    dense_log_ratio: np.ndarray | None = None  # (n, r, m) where the measurement model evaluated every pair anyway

    @property
    def shape(self) -> tuple[int, int, int]:
        """(n tracks, r modes, m measurements)."""
        return self.gated.shape[0], self.pair_log_ratio.shape[1], self.gated.shape[1]

    @cached_property
    def log_ratio(self) -> np.ndarray:
        """(n, r, m) log p_rm / rho_m, valid where gated (-inf elsewhere unless every pair was evaluated)."""
        if self.dense_log_ratio is not None:
            return self.dense_log_ratio
        out = np.full(self.shape, -np.inf)
        out[self.pair_track, :, self.pair_meas] = self.pair_log_ratio
        return out


def mahalanobis2(nu, S_inv):
    """Squared Mahalanobis distance ``d2 = nu^T S^-1 nu`` over the last axes.

    Written out for k = 1 and for large batches with k = 2 (the same sums, in the same order, as
    ``einsum("...i,...ij,...j", ...)``, several times faster there).

    Parameters
    ----------
    nu, S_inv : ndarray, shapes (..., k) and (..., k, k)
        Innovations and inverse innovation covariances.

    Returns
    -------
    ndarray, shape (...)
        d2 (dimensionless).
    """
    k = nu.shape[-1]
    if k == 1:
        return nu[..., 0] * S_inv[..., 0, 0] * nu[..., 0]
    if k == 2 and nu.size > 200:  # einsum's call overhead is smaller below ~100 pairs
        n0, n1 = nu[..., 0], nu[..., 1]
        return n0 * S_inv[..., 0, 0] * n0 + n0 * S_inv[..., 0, 1] * n1 + n1 * S_inv[..., 1, 0] * n0 \
            + n1 * S_inv[..., 1, 1] * n1
    return np.einsum("...i,...ij,...j->...", nu, S_inv, nu)


def gaussian_log_ratio(logdet, d2, k: int, log_rho):
    """Log likelihood ratio of a measurement against clutter: ``log N(nu; 0, S) - log rho``.

    ``-(k log 2 pi + log det S + d2) / 2 - log rho`` (module docstring).

    Parameters
    ----------
    logdet : float or ndarray
        ``log det S``.
    d2 : float or ndarray
        Squared Mahalanobis distance of the innovation.
    k : int
        Measurement dimension.
    log_rho : float or ndarray
        Log clutter density (per unit measurement volume: per m^2 for positions, per rad for bearings).

    Returns
    -------
    float or ndarray
        ``log p / rho``, broadcast over the inputs.
    """
    return -0.5 * (k * LOG_2PI + logdet + d2) - log_rho


#: below this many (track, measurement) pairs the pre-gate costs more than it saves
PREGATE_MIN_PAIRS = 256


def _chi_square_candidates(x_pos, P_pos, z, R, gamma: float):
    """(track, measurement) pairs that may pass the chi-square gate of some mode: nu_i^2 <= gamma S_ii on
    both axes (module doc), with a relative margin of 1e-6 so that round-off cannot drop a validated pair.

    ``x_pos (n, r, k)``, ``P_pos (n, r, k, k)``: the predicted measurement and its covariance H P H^T."""
    bound = gamma * (1.0 + 1e-6)
    ok = None
    for i in range(z.shape[1]):
        h = z[:, i] - x_pos[:, :, i, None]  # (n, r, m)
        h *= h
        ok_i = h <= (bound * P_pos[:, :, i, i])[..., None] + bound * R[:, i, i]
        ok = ok_i if ok is None else np.logical_and(ok, ok_i, out=ok)
    return np.nonzero(ok.any(axis=1))


def _rows(a, shape) -> np.ndarray:
    """``a`` as a float array of ``shape``: itself, one row repeated, or a broadcast view."""
    a = np.asarray(a, float)
    if a.shape == shape:
        return a
    if a.shape == shape[1:]:  # one row for all: a copy is cheaper than np.broadcast_to on small arrays
        return np.repeat(a[None], shape[0], axis=0)
    return np.broadcast_to(a, shape)


def _gated_pairs(x_pos, P_pos, z, R, gamma: float, compiled: bool):
    """The pairs that pass the pre-gate and then the chi-square gate, in row-major order: (ti, mi) and their
    nu (G, r, 2), S^-1 (G, r, 2, 2), log det S (G, r), d2 (G, r); compiled (association/likelihood_kernel.py)
    or in NumPy, with identical results."""
    if compiled:
        from sonartrack.association import likelihood_kernel as kernel

        R = np.ascontiguousarray(R)
        ti, mi, nu, S_inv, det, d2, all_positive = kernel.gated_pairs(x_pos, P_pos, z, R, gamma * (1.0 + 1e-6), gamma)
        if not all_positive:
            raise np.linalg.LinAlgError("covariance is singular or not positive definite")
        return ti, mi, nu, S_inv, np.log(det), d2
    ci, cj = _chi_square_candidates(x_pos, P_pos, z, R, gamma)
    S_inv, logdet = inv_and_logdet(P_pos[ci] + R[cj][:, None])
    nu = z[cj][:, None, :] - x_pos[ci]
    d2 = mahalanobis2(nu, S_inv)
    g = (d2 < gamma).any(axis=1)
    return ci[g], cj[g], nu[g], S_inv[g], logdet[g], d2[g]


def position_likelihoods(x_pred, P_pred, z, R, *, pd: float, pg: float, gamma: float, clutter_density,
                         compiled: bool = True) -> Likelihoods:
    """Likelihood ratios of position measurements for n tracks x r modes, with a chi-square gate (module docstring).

    The measurement observes the state's first two entries, [x, y] (m, x east, y north).

    Parameters
    ----------
    x_pred, P_pred : ndarray, shapes (n, r, d) and (n, r, d, d)
        Predicted mode-conditioned states (first two entries x, y in m) and their covariances.
    z : array_like, shape (m, 2)
        Measured positions [x, y] (m).
    R : array_like, shape (m, 2, 2) or (2, 2)
        Measurement covariances (m^2).
    pd, pg : float
        Detection probability P_D, and the gate probability P_G that goes with ``gamma``.
    gamma : float
        Chi-square gate size (association/gating.py).
    clutter_density : float or array_like, shape (m,)
        Clutter density at each measurement (per m^2).
    compiled : bool, default True
        Pre-gate large scans with the compiled kernel (identical results); False: NumPy only.

    Returns
    -------
    Likelihoods
        Gated pairs, log ratios ``log p_rm / rho_m``, innovations, inverse covariances, P_D, ``1 - P_D P_G``.

    Raises
    ------
    numpy.linalg.LinAlgError
        If an innovation covariance is not positive definite.
    """
    x_pred = np.asarray(x_pred, float)
    n, r, _ = x_pred.shape
    z = np.asarray(z, float).reshape(-1, 2)
    m = len(z)
    R = _rows(R, (m, 2, 2))
    log_rho = np.log(np.asarray(clutter_density, float))  # one value, or (m,)
    if log_rho.ndim:
        log_rho = np.broadcast_to(log_rho, (m,))
    x_pos = np.ascontiguousarray(x_pred[:, :, :2])  # (n, r, 2), (n, r, 2, 2): H x-, H P- H^T
    P_pos = np.ascontiguousarray(np.asarray(P_pred, float)[:, :, :2, :2])
    if n * m > PREGATE_MIN_PAIRS:
        ti, mi, nu, S_inv, logdet, d2 = _gated_pairs(x_pos, P_pos, z, R, gamma, compiled)
        gated = np.zeros((n, m), bool)
        gated[ti, mi] = True
        pair_log_ratio = gaussian_log_ratio(logdet, d2, 2, log_rho if log_rho.ndim == 0 else log_rho[mi, None])
    else:  # every pair, in (track, mode, measurement) order: the same values as the pre-gated path, no gathering
        nu = z - x_pos[:, :, None]  # (n, r, m, 2)
        S_inv, logdet = inv_and_logdet(P_pos[:, :, None] + R)  # (n, r, m, 2, 2)
        d2 = mahalanobis2(nu, S_inv)
        gated = (d2 < gamma).any(axis=1)
        ti, mi = np.nonzero(gated)
        log_ratio = gaussian_log_ratio(logdet, d2, 2, log_rho)
        return Likelihoods(log_ratio[ti, :, mi], gated, float(pd), 1.0 - pd * pg, ti, mi, nu[ti, :, mi],
                           S_inv[ti, :, mi], log_ratio)
    return Likelihoods(pair_log_ratio, gated, float(pd), 1.0 - pd * pg, ti, mi, nu, S_inv)


@functools.cache
def _erf():
    """scipy.special.erf, imported on first use (``import sonartrack`` stays fast) and then looked up once."""
    from scipy.special import erf

    return erf


def window_likelihoods(x_pred, P_pred, z, sigma, *, gate_width: float, pd_hit, pd_miss, clutter_density,
                       log_ratio_extra=None) -> Likelihoods:
    """Likelihood ratios of scalar (bearing) measurements with a window gate |nu| <= V / 2 (paper P0).

    Per track and mode ``S = P-[0, 0] + sigma^2`` and ``P_G = erf(V / (2 sqrt(2 S)))``.

    Parameters
    ----------
    x_pred : ndarray, shape (n, r, d)
        Predicted mode-conditioned states; entry 0 is the measured quantity (bearing, rad).
    P_pred : ndarray, shape (n, r, d, d)
        Their covariances.
    z : array_like, shape (m,)
        Measurements (rad for bearings).
    sigma : array_like, shape (n,)
        Per-track measurement standard deviation (same unit as z).
    gate_width : float
        Window width V (same unit as z).
    pd_hit : array_like, shape (n,)
        P_D in the hit weight.
    pd_miss : array_like, shape (n,)
        P_D in the miss weight ``1 - P_D P_G`` (differs from ``pd_hit`` for JPDA_A, association/amplitude.py).
    clutter_density : float
        Clutter density (per unit of z, e.g. per rad).
    log_ratio_extra : array_like, shape (n, m), optional
        Added to every mode's log ratio (the amplitude log ratio of JPDA_A).

    Returns
    -------
    Likelihoods
        Gated pairs and every pair's log ratio (``dense_log_ratio`` is filled).
    """
    erf = _erf()
    z = np.asarray(z, float).reshape(-1)
    S = P_pred[:, :, 0, 0] + np.asarray(sigma, float)[:, None] ** 2  # (n, r): the same for every peak
    nu = z[None, None, :] - x_pred[:, :, None, 0]  # (n, r, m)
    half = gate_width / 2
    inside = np.abs(nu) <= half
    gated = inside[:, 0] if inside.shape[1] == 1 else inside.any(axis=1)  # one mode: the reduction is that mode
    S_inv = 1.0 / S
    log_ratio = gaussian_log_ratio(np.log(S)[..., None], nu * S_inv[..., None] * nu, 1, np.log(clutter_density))
    if log_ratio_extra is not None:
        log_ratio = log_ratio + np.asarray(log_ratio_extra, float)[:, None, :]
    ti, mi = np.nonzero(gated)
    return Likelihoods(log_ratio[ti, :, mi], gated, np.asarray(pd_hit, float),
                       1.0 - np.asarray(pd_miss, float)[:, None] * erf(half / np.sqrt(2 * S)),
                       ti, mi, nu[ti, :, mi][..., None], S_inv[ti][..., None, None], log_ratio)

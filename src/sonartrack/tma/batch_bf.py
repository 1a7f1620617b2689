"""Batch TMA on bearings + frequency: maximum likelihood by Gauss-Newton with Levenberg-Marquardt damping, its
covariance and the Cramer-Rao bound.

Target at constant velocity emitting a tonal of constant frequency f0; the state at the reference time t0 (the
first measurement's) is X0 = [x0, y0, vx, vy, f0]. At time t_n (tau_n = t_n - t0), with the sensor at o_n moving
at u_n (its velocity), the relative position and velocity are

    d_n = (x0 + vx tau_n - ox_n, y0 + vy tau_n - oy_n),   w_n = (vx - ux_n, vy - uy_n),   r_n = |d_n|,
    rdot_n = d_n . w_n / r_n                                                    (range rate)

and the measurements (paper P2, Yoo & Song, eq. 3: bearing and Doppler-shifted frequency)

    h_b,n = atan2(dx_n, dy_n),          h_f,n = f0 (1 - rdot_n / c)

with noise of standard deviations sigma_b and sigma_f. With a_n = (w_n - rdot_n d_n / r_n) / r_n (the gradient
of rdot_n in d_n) and e_n = d_n / r_n (its gradient in w_n), the Jacobian rows are

    dh_b,n/dX0 = [dy_n, -dx_n, tau_n dy_n, -tau_n dx_n, 0] / r_n^2              (paper P3, eq. 16)
    dh_f,n/dX0 = [-f0/c a_n,  -f0/c (tau_n a_n + e_n),  1 - rdot_n / c].

ML minimises C = sum_n wrap(z_n - h_b,n)^2 / sigma_b^2 + (f_n - h_f,n)^2 / sigma_f^2 by the damped Gauss-Newton
of tma/batch_ml.py (Marquardt 1963); covariance the inverse Fisher information (J^T J)^-1 at the solution, the
CRB the same at the true state.

Why the frequency determines range where the bearings cannot (Jauffret & Pillon 1996, IEEE Trans. AES 32(4),
"Observability in passive target motion analysis"; Passerieux et al. 1988 for bearings + frequency): with the
sensor on one straight leg at constant velocity, the bearings fix the relative track only up to a scale k,
d_n = k d'_n; the range rate scales alike, rdot_n = k g_n with g_n = d/dt |d'_n| known, so the frequencies lie on
the line f_n = f0 - (f0 k / c) g_n. When g_n varies over the record (the bearing changes), that line gives f0 and
f0 k / c, hence the scale k: range is observable without an ownship maneuver. It is not when g_n is constant (a
target on a constant bearing).

Arguments the functions here share (their docstrings refer to this list):

- ``tau_s``, array_like (n,): times since t0 (s);
- ``own_xy``, ``own_v``, ndarray (n, 2): the sensor's positions (m; x east, y north) and velocities (m/s) then;
- ``sigma_b_rad``, ``sigma_f_hz``, float or array_like (n,): bearing (rad) and frequency (Hz) noise standard
  deviations;
- ``c_mps``, float: speed of sound (m/s), default :data:`SOUND_SPEED_MPS`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.errors import InputError, require
from sonartrack.tma.batch_ml import BatchEstimate, LmFit, _damped_step, bearing_model

#: speed of sound of the Doppler model (m/s) when none is given (paper P2)
SOUND_SPEED_MPS = 1500.0


@dataclass(frozen=True, slots=True)
class BfEstimate(LmFit):
    """A bearings + frequency ML solution: X0 = [x0, y0, vx, vy, f0] (m, m/s, Hz) at ``t0_s`` and its 5 x 5
    covariance, with how the solver ended (the fields of :class:`~sonartrack.tma.batch_ml.LmFit`)."""

    def track(self) -> BatchEstimate:
        """The kinematic part (x0, y0, vx, vy and its 4 x 4 covariance) as a :class:`BatchEstimate` (method "ml").

        Returns
        -------
        BatchEstimate
            The constant-velocity track, propagated by its ``state_at``.
        """
        return BatchEstimate(x0=np.asarray(self.x0[:4], float).copy(), covariance=np.asarray(self.covariance)[:4, :4],
                             t0_s=self.t0_s, iterations=self.iterations, converged=self.converged,
                             objective=self.objective, method="ml")


def bf_model(x0, tau_s, own_xy, own_v, c_mps: float = SOUND_SPEED_MPS):
    """Predicted bearings and frequencies of X0 and their Jacobians (module docstring).

    Parameters
    ----------
    x0 : array_like, shape (5,)
        [x0, y0, vx, vy, f0] at t0 (m, m/s, Hz).
    tau_s, own_xy, own_v, c_mps
        The times, the sensor's motion then, the speed of sound (module docstring).

    Returns
    -------
    h_b : ndarray, shape (n,)
        Bearings (rad, clockwise from north).
    h_f : ndarray, shape (n,)
        Received frequencies (Hz).
    H_b, H_f : ndarray, shape (n, 5)
        Their derivatives in X0.
    """
    x0 = np.asarray(x0, dtype=float)
    tau = np.asarray(tau_s, dtype=float)
    h_b, Hb4, r = bearing_model(x0[:4], tau, own_xy)
    d = np.stack([x0[0] + x0[2] * tau - own_xy[:, 0], x0[1] + x0[3] * tau - own_xy[:, 1]], axis=-1)
    w = x0[2:4] - own_v
    e = d / r[:, None]
    rdot = np.sum(e * w, axis=1)
    a = (w - rdot[:, None] * e) / r[:, None]
    g = -x0[4] / c_mps
    H_f = np.column_stack([g * a, g * (tau[:, None] * a + e), 1.0 - rdot / c_mps])
    H_b = np.column_stack([Hb4, np.zeros(len(tau))])
    return h_b, x0[4] * (1.0 - rdot / c_mps), H_b, H_f


def fisher_information_bf(x0, tau_s, own_xy, own_v, sigma_b_rad, sigma_f_hz, c_mps: float = SOUND_SPEED_MPS
                          ) -> np.ndarray:
    """J = sum_n (H_b,n^T H_b,n / sigma_b^2 + H_f,n^T H_f,n / sigma_f^2): the Fisher information about X0.

    Parameters
    ----------
    x0 : array_like, shape (5,)
        The state [x0, y0, vx, vy, f0] at t0 (m, m/s, Hz) where J is taken.
    tau_s, own_xy, own_v, sigma_b_rad, sigma_f_hz, c_mps
        As in the module docstring.

    Returns
    -------
    ndarray, shape (5, 5)
        J.
    """
    _, _, H_b, H_f = bf_model(x0, tau_s, own_xy, own_v, c_mps)
    n = len(H_b)
    wb = 1.0 / np.broadcast_to(np.asarray(sigma_b_rad, float), (n,)) ** 2
    wf = 1.0 / np.broadcast_to(np.asarray(sigma_f_hz, float), (n,)) ** 2
    return (H_b * wb[:, None]).T @ H_b + (H_f * wf[:, None]).T @ H_f


def crb_bf(x0_true, tau_s, own_xy, own_v, sigma_b_rad, sigma_f_hz, c_mps: float = SOUND_SPEED_MPS) -> np.ndarray:
    """Cramer-Rao bound on X0 = [x0, y0, vx, vy, f0]: the inverse Fisher information at the true state.

    Parameters
    ----------
    x0_true : array_like, shape (5,)
        The true X0 (m, m/s, Hz).
    tau_s, own_xy, own_v, sigma_b_rad, sigma_f_hz, c_mps
        Geometry, noise and sound speed (module docstring).

    Returns
    -------
    ndarray, shape (5, 5)
        J^-1.
    """
    return np.linalg.inv(fisher_information_bf(x0_true, tau_s, own_xy, own_v, sigma_b_rad, sigma_f_hz, c_mps))


def bf_start(track_x0, freq_hz, own_xy0, own_v0, scale: float = 1.0) -> np.ndarray:
    """A start for the B+F ML: a bearings-only track, scaled about the sensor's first leg, and the mean frequency.

    The bearings alone fix the relative track only up to a scale k (no maneuver): the track
    x0' = o_0 + k (x0 - o_0), v' = u_0 + k (v - u_0) fits them as well on the sensor's first straight leg. f0 starts
    at the mean received frequency (within f0 |rdot| / c of the truth, 0.1 % at 1.5 m/s).

    Parameters
    ----------
    track_x0 : array_like, shape (4,)
        A bearings-only solution [x0, y0, vx, vy] at t0 (m, m/s).
    freq_hz : array_like, shape (n,)
        The received frequencies (Hz).
    own_xy0, own_v0 : array_like, shape (2,)
        The sensor's position (m) and velocity (m/s) at t0.
    scale : float
        k.

    Returns
    -------
    ndarray, shape (5,)
        [x0, y0, vx, vy, f0] (m, m/s, Hz).
    """
    x = np.asarray(track_x0, float)
    o, u = np.asarray(own_xy0, float), np.asarray(own_v0, float)
    return np.concatenate([o + scale * (x[:2] - o), u + scale * (x[2:4] - u), [float(np.mean(freq_hz))]])


def ml_bearings_frequency(z_rad, freq_hz, time_s, own_xy, own_v, sigma_b_rad, sigma_f_hz, x_init, *,
                          c_mps: float = SOUND_SPEED_MPS, max_iter: int = 200, tol: float = 1e-12) -> BfEstimate:
    """ML X0 = [x0, y0, vx, vy, f0] from bearings and frequencies (module docstring), from ``x_init``.

    Parameters
    ----------
    z_rad, freq_hz, time_s : array_like, shape (n,)
        Bearings (rad, clockwise from north), received frequencies (Hz) and their strictly increasing times (s);
        n >= 6.
    own_xy, own_v, sigma_b_rad, sigma_f_hz
        The sensor's motion at those times and the noise (module docstring).
    x_init : array_like, shape (5,)
        The start (:func:`bf_start`).
    c_mps, max_iter, tol : float, int, float
        Speed of sound (m/s), iteration limit, relative cost decrease that ends the search.

    Returns
    -------
    BfEstimate
        X0 at the first time, its covariance (J^T J)^-1 (infinite when singular), iterations, convergence, cost C.
    """
    z, f, t = (np.asarray(a, dtype=float) for a in (z_rad, freq_hz, time_s))
    own, ov = np.asarray(own_xy, float), np.asarray(own_v, float)
    require(z.ndim == 1 and len(z) == len(f) == len(t) == len(own) == len(ov),
            "bearings, frequencies, times and sensor positions and velocities must have the same length")
    require(len(z) >= 6, f"bearings + frequency ML needs at least 6 measurements, got {len(z)}")
    require(bool(np.all(np.diff(t) > 0)), "measurement times must increase strictly: sort them and drop duplicates")
    tau = t - t[0]
    sb = np.broadcast_to(np.asarray(sigma_b_rad, float), z.shape)
    sf = np.broadcast_to(np.asarray(sigma_f_hz, float), z.shape)

    def residual(x):
        h_b, h_f, H_b, H_f = bf_model(x, tau, own, ov, c_mps)
        e = np.concatenate([wrap_angle(z - h_b) / sb, (f - h_f) / sf])
        return e, np.concatenate([H_b / sb[:, None], H_f / sf[:, None]])

    x = np.asarray(x_init, dtype=float).copy()
    e, J = residual(x)
    cost = float(e @ e)
    lam, it, converged = 1e-3, 0, False
    while it < max_iter:
        it += 1
        x, e, J, c_new, lam, improved = _damped_step(residual, x, e, J, cost, lam)
        rel = (cost - c_new) / max(cost, 1e-300) if improved else 0.0
        cost = c_new
        if not improved or rel < tol:
            converged = True
            break
    try:
        cov = np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        cov = np.full((5, 5), np.inf)
    return BfEstimate(x0=x, covariance=cov, t0_s=float(t[0]), iterations=it, converged=converged, objective=cost)


def bf_profile_rise(time_s, bearing_rad, freq_hz, own_xy, own_v, sigma_b_rad: float, sigma_f_hz: float, end_state,
                    range_m: float, c_mps: float = SOUND_SPEED_MPS) -> float:
    """How much worse bearings + frequencies fit a constant-velocity target held at ``range_m`` at the last time.

    The profile likelihood of the final range (Pawitan, In All Likelihood, 2001, sec. 3.4) with f0 free: the target
    at the last time t_n at bearing b and range r from the sensor, velocity (vx, vy), emitting f0,

        C(b, r, vx, vy, f0) = the ML cost (module docstring) of that track,

    and the rise is min_{b, vx, vy, f0} C(b, range_m, vx, vy, f0) - C(end_state): 1 at one standard deviation when
    the likelihood is Gaussian in r, much less where it is flat.

    Parameters
    ----------
    time_s, bearing_rad, freq_hz : ndarray (n,)
        Times (s), bearings (rad, clockwise from north) and received frequencies (Hz).
    own_xy, own_v : ndarray (n, 2)
        The sensor's positions (m) and velocities (m/s) at those times.
    sigma_b_rad, sigma_f_hz : float
        The bearing (rad) and frequency (Hz) noise.
    end_state : array_like (5,)
        The fit's state at the last time: x, y (m), vx, vy (m/s), f0 (Hz).
    range_m : float
        The range held (m).
    c_mps : float
        Speed of sound (m/s).

    Returns
    -------
    float
        The rise of C (>= 0 up to the optimiser's tolerance).
    """
    from scipy.optimize import least_squares

    t, z, f = (np.asarray(a, float) for a in (time_s, bearing_rad, freq_hz))
    own, ov = np.asarray(own_xy, float), np.asarray(own_v, float)
    tau = t - t[-1]
    xe = np.asarray(end_state, float)
    b0 = float(np.arctan2(xe[0] - own[-1, 0], xe[1] - own[-1, 1]))

    def residual(p, r):
        x0 = [own[-1, 0] + r * np.sin(p[0]), own[-1, 1] + r * np.cos(p[0]), p[1], p[2], p[3]]
        h_b, h_f, _, _ = bf_model(x0, tau, own, ov, c_mps)
        return np.concatenate([wrap_angle(z - h_b) / sigma_b_rad, (f - h_f) / sigma_f_hz])

    r_fit = float(np.hypot(xe[0] - own[-1, 0], xe[1] - own[-1, 1]))
    c_fit = float(np.sum(residual([b0, xe[2], xe[3], xe[4]], r_fit) ** 2))
    starts = ([b0, xe[2], xe[3], xe[4]], [b0, ov[-1, 0], ov[-1, 1], xe[4]])
    c_held = min(2.0 * least_squares(residual, s, args=(float(range_m),), method="lm").cost for s in starts)
    return max(c_held - c_fit, 0.0)


def bf_jackknife(time_s, bearing_rad, freq_hz, own_xy, own_v, sigma_b_rad: float, sigma_f_hz: float,
                 est: BfEstimate, *, c_mps: float = SOUND_SPEED_MPS, blocks: int | None = None):
    """The bearings + frequency ML's final state recomputed with each block of the record left out: the
    delete-a-block jackknife (Kunsch, Ann. Statist. 17(3), 1989, 1217-1241, eq. 2.2 with non-overlapping blocks;
    Shao & Tu, The Jackknife and Bootstrap, 1995, sec. 5.2), as tma/side_jackknife.py
    :func:`~sonartrack.tma.side_jackknife.side_jackknife` does for the bearings-only fit.

    The record's span is cut into g equal stretches of time (:func:`~sonartrack.tma.side_jackknife.time_blocks`);
    replicate j leaves block j out and refits X0 by :func:`ml_bearings_frequency` from ``est`` moved to the first kept
    time, giving the state x_j at the last time t_n. The jackknife covariance

        P_J = (g - 1) / g  sum_j (x_j - x_bar)(x_j - x_bar)^T,      x_bar = mean_j x_j

    estimates the final state's covariance without assuming the errors white or the model right (a bias in the
    bearings or the frequency over part of the record, or another source's stretch, moves the replicates as much as
    the estimate). Each replicate also predicts the bearings it left out: their rms difference and the prediction's
    standard deviation (H_b P_j H_b^T at the replicate's residual scale C_j / (2 n_j - 5), where C_j is its cost and
    n_j its measurements), the predictive test of Chow (Econometrica 28(3), 1960, sec. 3).

    Parameters
    ----------
    time_s, bearing_rad, freq_hz : ndarray (n,)
        Times (s, increasing), bearings (rad, clockwise from north) and received frequencies (Hz).
    own_xy, own_v : ndarray (n, 2)
        The sensor's positions (m) and velocities (m/s) at those times.
    sigma_b_rad, sigma_f_hz : float
        The bearing (rad) and frequency (Hz) noise the fit was made with.
    est : BfEstimate
        The whole record's fit.
    c_mps : float
        Speed of sound (m/s).
    blocks : int or None
        g, the stretches of time (None: :data:`~sonartrack.tma.side_jackknife.JACKKNIFE_BLOCKS`).

    Returns
    -------
    SideJackknife
        ``log_lr`` NaN (no side is decided here), each replicate's final state (NaN where its fit failed) and its
        prediction of its block's bearings, and P_J.
    """
    from sonartrack.tma.side_jackknife import JACKKNIFE_BLOCKS, SideJackknife, time_blocks

    t, z, f = (np.asarray(a, float) for a in (time_s, bearing_rad, freq_hz))
    own, ov = np.asarray(own_xy, float), np.asarray(own_v, float)
    edges = time_blocks(t, JACKKNIFE_BLOCKS if blocks is None else blocks)
    g = len(edges) - 1
    require(g >= 2, f"bf_jackknife: {len(t)} measurements over {t[-1] - t[0]:g} s make fewer than 2 blocks")
    i = np.arange(len(t))
    reps = np.full((g, 6), np.nan)
    for j in range(g):
        keep = (i < edges[j]) | (i >= edges[j + 1])
        if keep.sum() >= 6:
            reps[j] = _bf_replicate(t, z, f, own, ov, (sigma_b_rad, sigma_f_hz), est, keep, c_mps)
    state = reps[:, :4]
    d = state - state.mean(axis=0)
    return SideJackknife(np.full(g, np.nan), state, (g - 1) / g * d.T @ d, reps[:, 4], reps[:, 5])


def _bf_replicate(t, z, f, own, ov, sigma, est: BfEstimate, keep, c_mps: float) -> np.ndarray:
    """One replicate of :func:`bf_jackknife`: [final state (4), rms of its prediction of the left-out bearings,
    the prediction's rms sd] (NaNs when the fit fails)."""
    x_init = np.asarray(est.x0, float).copy()
    x_init[:2] += x_init[2:4] * (t[keep][0] - est.t0_s)
    with np.errstate(all="ignore"):
        try:
            fit = ml_bearings_frequency(z[keep], f[keep], t[keep], own[keep], ov[keep], sigma[0], sigma[1], x_init,
                                        c_mps=c_mps)
        except (InputError, np.linalg.LinAlgError, ValueError):
            return np.full(6, np.nan)
        if not (np.isfinite(fit.objective) and np.all(np.isfinite(fit.x0)) and np.all(np.isfinite(fit.covariance))):
            return np.full(6, np.nan)
        out = ~keep
        h_b, _, H_b, _ = bf_model(fit.x0, t[out] - fit.t0_s, own[out], ov[out], c_mps)
        s2 = fit.objective / max(2 * int(keep.sum()) - 5, 1)
        v = np.einsum("ni,ij,nj->n", H_b, fit.covariance * s2, H_b)
        end = fit.x0[:4] + np.r_[fit.x0[2:4], 0.0, 0.0] * (t[-1] - fit.t0_s)
        return np.r_[end, np.sqrt(np.mean(wrap_angle(z[out] - h_b) ** 2)), np.sqrt(np.mean(v))]

"""IMM-EKF and IMM-MGEKF for bearing (+ frequency) passive TMA on the relative state [x, y, vx, vy, f0].

Yoo & Song (paper P2; DIGEST P2): the modes differ only in the target's process-noise intensity q_j
(m^2/s^3); each mode runs an EKF or an MGEKF (filters/ekf.py, filters/mgekf.py) on the relative
constant-velocity model (models/relative_motion.py, P2 eq. 2) with the bearing + frequency measurement
(models/passive.py, P2 eq. 3). One cycle, with the generic IMM pieces of filters/imm.py::

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
* :func:`imm_bf_step` / :func:`run_imm_bf` -- the numba kernels of tma/imm_mgekf_kernel.py (jitted on
  first use and cached on disk), one named function per step of the cycle, with R diagonal (bearing and
  frequency noises independent); one 3-mode step costs a few microseconds, against ~0.2 ms for the
  NumPy version, which is what makes the Monte Carlo study possible.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sonartrack.core.errors import require
from sonartrack.filters.ekf import ekf_predict, ekf_update, gaussian_loglik
from sonartrack.filters.imm import imm_combine, imm_mix, imm_mixing, imm_mode_update, validate_transition_matrix
from sonartrack.filters.mgekf import mgekf_update
from sonartrack.models.passive import SOUND_SPEED_MPS, bf_jacobian, bf_measurement, modified_matrix
from sonartrack.models.relative_motion import relative_process_noise, relative_process_noise_stack, relative_transition
from sonartrack.tma.records import ModeProbabilities


def transition_matrix(n_modes: int, diagonal: float) -> np.ndarray:
    """Markov matrix with ``diagonal`` on the diagonal and the rest spread evenly over each row.

    Parameters
    ----------
    n_modes : int
        Number of modes r.
    diagonal : float
        Probability of staying in a mode.

    Returns
    -------
    ndarray, shape (r, r)
        Rows sum to 1 ([[1]] for one mode).
    """
    if n_modes == 1:
        return np.ones((1, 1))
    Pi = np.full((n_modes, n_modes), (1.0 - diagonal) / (n_modes - 1))
    np.fill_diagonal(Pi, diagonal)
    return validate_transition_matrix(Pi)


def mode_names(qs) -> tuple[str, ...]:
    """A name per mode for the output columns: ``cv`` for the quietest (smallest q), ``q<q:g>`` for the others.

    Parameters
    ----------
    qs : array_like, shape (r,)
        The modes' process-noise intensities (m^2/s^3).

    Returns
    -------
    tuple of str
        One name per mode, in the bank's order (a repeated q gets its index appended).
    """
    q = np.asarray(qs, float)
    quiet = int(np.argmin(q))
    names = ["cv" if j == quiet else f"q{v:g}" for j, v in enumerate(q)]
    return tuple(n if names.count(n) == 1 else f"{n}_{j}" for j, n in enumerate(names))


def mode_probabilities(qs, mu, *, manoeuvre_q_min: float, level: float) -> ModeProbabilities:
    """An IMM's mode probabilities as the solution carries them (tma/records.py, solution table's columns).

    Parameters
    ----------
    qs : array_like, shape (r,)
        The modes' intensities (m^2/s^3).
    mu : array_like, shape (n, r)
        Mode probabilities per time (:func:`run_imm_bf`).
    manoeuvre_q_min : float
        The modes with q at least this are manoeuvre modes (m^2/s^3).
    level : float
        Manoeuvre-probability level above which a row is flagged as manoeuvring.

    Returns
    -------
    ModeProbabilities
        Names, probabilities, manoeuvre-mode mask and level.
    """
    q = np.asarray(qs, float)
    return ModeProbabilities(names=mode_names(q), prob=np.asarray(mu, float), manoeuvre_mode=q >= manoeuvre_q_min,
                             level=float(level))


def imm_bf_step_reference(x, P, mu, z, u, dt_s, qs, Pi, R, *, modified: bool, q_f0: float = 0.0,
                          c: float = SOUND_SPEED_MPS):
    """One IMM cycle (NumPy). Returns ``(x_r, P_r, mu, x_comb, P_comb, log_lik_total)``.

    x (r, 5), P (r, 5, 5), mu (r,) at k-1; z (m,) = [bearing] or [bearing, frequency]; u (5,) the
    observer input (models/relative_motion.py); qs (r,) process-noise intensities; Pi (r, r);
    R (m, m); ``modified`` selects the MGEKF covariance update.

    Parameters
    ----------
    x, P, mu : array_like
        Mode estimates [x, y, vx, vy, f0] (m, m/s, Hz) and mode probabilities at k-1.
    z : array_like, shape (m,)
        Bearing (rad, clockwise from north), then frequency (Hz) when m = 2.
    u : array_like, shape (5,)
        Observer input over the step.
    dt_s : float
        Step (s).
    qs, Pi, R : array_like
        Mode intensities (m^2/s^3), transition matrix, measurement covariance (rad^2, Hz^2).
    modified : bool
        MGEKF (True) or EKF (False) covariance update.
    q_f0 : float
        Random-walk intensity of f0 (Hz^2/s).
    c : float
        Sound speed (m/s).

    Returns
    -------
    tuple
        Mode means (r, 5), covariances (r, 5, 5), probabilities (r,), combined mean (5,) and covariance (5, 5),
        log sum_j c_j Lambda_j.
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


@dataclass(frozen=True, slots=True, eq=False)
class ImmBfModel:
    """What an IMM-EKF / IMM-MGEKF assumes, built once per record: one process-noise intensity per mode
    ``qs`` (m^2/s^3; one value = a single EKF/MGEKF), the Markov matrix ``Pi`` (None with one mode), the
    bearing and frequency noise standard deviations, the f0 random-walk intensity ``q_f0`` (Hz^2/s), the
    speed of sound (m/s), and ``modified``: the MGEKF covariance update (else the EKF's)."""

    qs: np.ndarray
    Pi: np.ndarray | None
    sigma_bearing_rad: float
    sigma_freq_hz: float = 1.0
    q_f0: float = 0.0
    sound_speed_mps: float = SOUND_SPEED_MPS
    modified: bool = True
    #: the kernels' constants [var_b, var_f, q_f0, c] (tma/imm_mgekf_kernel.py), derived
    consts: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        # fresh writeable C arrays: numba compiles one specialisation per layout/readonly flag
        qs = _c(np.atleast_1d(self.qs))
        require(qs.ndim == 1 and len(qs) >= 1 and bool(np.all(qs >= 0)),
                "qs must be one or more non-negative process-noise intensities (m^2/s^3)")
        Pi = np.ones((1, 1)) if self.Pi is None and len(qs) == 1 else _c(validate_transition_matrix(self.Pi))
        require(Pi.shape == (len(qs), len(qs)), f"the Markov matrix must be {len(qs)} x {len(qs)} (one row per q)")
        require(self.sigma_bearing_rad > 0 and self.sigma_freq_hz > 0, "noise standard deviations must be positive")
        object.__setattr__(self, "qs", qs)
        object.__setattr__(self, "Pi", Pi)
        object.__setattr__(self, "modified", bool(self.modified))
        consts = np.array([self.sigma_bearing_rad**2, self.sigma_freq_hz**2, self.q_f0, self.sound_speed_mps], float)
        object.__setattr__(self, "consts", consts)

    @property
    def R(self) -> np.ndarray:
        """Measurement noise covariance diag(sigma_b^2, sigma_f^2) (rad^2, Hz^2)."""
        return np.diag(self.consts[:2])


_KERNEL: list = []


def _kernel():
    """The compiled kernels' module (importing it imports numba: done on first use only)."""
    if not _KERNEL:
        from sonartrack.tma import imm_mgekf_kernel

        _KERNEL.append(imm_mgekf_kernel)
    return _KERNEL[0]


def imm_bf_step(x, P, mu, z, u, dt_s: float, model: ImmBfModel, out=None):
    """One IMM cycle with the numba kernel (same equations and returns as :func:`imm_bf_step_reference`).

    z: float array [bearing] or [bearing, frequency] (a NaN frequency: bearing only). ``out``: optional
    preallocated ``(x_r, P_r, mu, x_comb, P_comb)`` arrays, reused to avoid allocation in a tight loop.
    Returns ``(x_r, P_r, mu, x_comb, P_comb, log_lik_total)``.

    Parameters
    ----------
    x, P, mu : ndarray
        Mode estimates (r, 5), (r, 5, 5) and probabilities (r,) at k-1.
    z : array_like, shape (1,) or (2,)
        Bearing (rad), frequency (Hz).
    u : ndarray, shape (5,)
        Observer input over the step.
    dt_s : float
        Step (s).
    model : ImmBfModel
        Modes, transition matrix, noises, sound speed.
    out : tuple of ndarray, optional
        Output arrays.

    Returns
    -------
    tuple
        As :func:`imm_bf_step_reference` (log-likelihood NaN when some S is singular).
    """
    if out is None:
        r = x.shape[0]
        out = (np.empty((r, 5)), np.empty((r, 5, 5)), np.empty(r), np.empty(5), np.empty((5, 5)))
    ll = _kernel().imm_step(x, P, mu, np.asarray(z, dtype=float), u, float(dt_s), model.qs, model.Pi, model.consts,
                            model.modified, *out)
    return (*out, ll)


def run_imm_bf(times_s, bearing_rad, frequency_hz, u, x0, P0, model: ImmBfModel, *, mu0=None,
               engine: str = "numba"):
    """Run an IMM (or, with one q, a single) EKF/MGEKF over a record.

    times_s (n,), bearing_rad (n,), frequency_hz (n,) or None (bearings only; NaN entries mean "no
    frequency at that time"), u (n - 1, 5) observer inputs, x0 (5,) and P0 (5, 5) the estimate at
    times_s[0] (given to every mode), mu0 the initial mode probabilities (default equal). Returns
    ``(x (n, 5), P (n, 5, 5), mu (n, r), failed_at)``; after a numerical failure at step k
    (``failed_at = k``, else -1) the rows from k on are NaN. ``engine="reference"`` runs the NumPy
    reference step instead of the kernel.

    Parameters
    ----------
    times_s, bearing_rad, frequency_hz, u, x0, P0, mu0
        As above (s, rad clockwise from north, Hz; states in m, m/s, Hz).
    model : ImmBfModel
        Modes, transition matrix, noises, sound speed.
    engine : str
        "numba" or "reference".

    Returns
    -------
    tuple
        Combined means (n, 5), covariances (n, 5, 5), mode probabilities (n, r), index of the failed step or -1.
    """
    t = _c(times_s)
    n_t, r = len(t), len(model.qs)
    mu = np.full(r, 1.0 / r) if mu0 is None else _c(mu0)
    z = np.full((n_t, 2), np.nan)
    z[:, 0] = bearing_rad
    if frequency_hz is not None:
        z[:, 1] = np.where(np.isfinite(frequency_hz), frequency_hz, np.nan)
    u = _c(u).reshape(max(n_t - 1, 0), 5)
    xs = _c(np.broadcast_to(np.asarray(x0, float), (r, 5)))
    Ps = _c(np.broadcast_to(np.asarray(P0, float), (r, 5, 5)))
    hist = (np.full((n_t, 5), np.nan), np.full((n_t, 5, 5), np.nan), np.full((n_t, r), np.nan))
    if engine == "numba":
        failed = int(_kernel().run_record(t, z, u, xs, Ps, mu, model.qs, model.Pi, model.consts, model.modified,
                                          *hist))
    elif engine == "reference":
        failed = _run_reference(t, z, u, (xs, Ps, mu), model, hist)
    else:
        raise ValueError(f"unknown engine {engine!r}")
    return (*hist, failed)


def _c(a) -> np.ndarray:
    return np.array(a, dtype=float, order="C", copy=True)


def _run_reference(t, z, u, estimate, model: ImmBfModel, hist) -> int:
    """:func:`run_imm_bf` with the NumPy reference step (same outputs, written into ``hist``)."""
    x, P, mu = estimate
    xh, Ph, mh = hist
    xh[0], Ph[0] = imm_combine(mu, x, P)
    mh[0] = mu
    for k in range(1, len(t)):
        m = 2 if np.isfinite(z[k, 1]) else 1
        try:
            with np.errstate(all="ignore"):
                x, P, mu, xc, Pc, ll = imm_bf_step_reference(x, P, mu, z[k, :m], u[k - 1], t[k] - t[k - 1],
                                                             model.qs, model.Pi, model.R[:m, :m],
                                                             modified=model.modified, q_f0=model.q_f0,
                                                             c=model.sound_speed_mps)
        except np.linalg.LinAlgError:
            return k
        if not (np.isfinite(ll) and np.all(np.isfinite(xc)) and np.all(np.isfinite(Pc))):
            return k
        xh[k], Ph[k], mh[k] = xc, Pc, mu
    return -1


def combined_nis(times_s, bearing_rad, frequency_hz, u, x, P, mu, model: ImmBfModel) -> tuple[np.ndarray, np.ndarray]:
    """Normalised innovation squared (NIS) of the combined IMM estimate at each measurement (Bar-Shalom, Li &
    Kirubarajan, Estimation with Applications to Tracking and Navigation, 2001, sec. 5.4.2 and 11.6.6).

    From the combined estimate (x_{k-1}, P_{k-1}) and the mode probabilities mu_{k-1} of :func:`run_imm_bf`, the
    predicted mixture of the modes has mean and covariance (the mixing step keeps the mixture's first two moments,
    and Q is linear in the intensity q)

        x-_k = F x_{k-1} - u_{k-1},   P-_k = F P_{k-1} F^T + Q(sum_j c_j q_j),   c_j = sum_i Pi[i, j] mu_{k-1, i}

    and the measurement z_k = [bearing(, frequency)] gives

        nu_k = z_k - h(x-_k)  (bearing wrapped),   S_k = H P-_k H^T + R,   eps_k = nu_k^T S_k^-1 nu_k,

    chi-square with m_k degrees of freedom (m_k = 1 or 2 measurements) when the filter is consistent.

    Parameters
    ----------
    times_s, bearing_rad, frequency_hz, u
        As :func:`run_imm_bf` (s, rad, Hz or None, observer inputs (n - 1, 5)).
    x, P, mu : ndarray
        Its combined means (n, 5), covariances (n, 5, 5) and mode probabilities (n, r).
    model : ImmBfModel
        The filter's modes, transition matrix and noises.

    Returns
    -------
    nis : ndarray (n,)
        eps_k (NaN at the first time, which has no innovation, and where the estimate is not finite).
    dof : ndarray of int (n,)
        m_k (0 where ``nis`` is NaN).
    """
    from sonartrack.core.angles import wrap_angle

    t, n = np.asarray(times_s, float), len(times_s)
    z = np.full((n, 2), np.nan)
    z[:, 0] = bearing_rad
    if frequency_hz is not None:
        z[:, 1] = frequency_hz
    nis, dof = np.full(n, np.nan), np.zeros(n, int)
    c_mode = np.asarray(mu, float) @ np.asarray(model.Pi, float)  # c_j of each step, from mu_{k-1}
    for k in range(1, n):
        dt = float(t[k] - t[k - 1])
        F = relative_transition(dt)
        q = float(c_mode[k - 1] @ model.qs) if np.all(np.isfinite(c_mode[k - 1])) else np.nan
        xp = F @ x[k - 1] - np.asarray(u[k - 1], float)
        Pp = F @ P[k - 1] @ F.T + relative_process_noise(dt, q, model.q_f0)
        m = 2 if np.isfinite(z[k, 1]) else 1
        if not (np.all(np.isfinite(xp)) and np.all(np.isfinite(Pp))):
            continue
        nu = z[k, :m] - bf_measurement(xp, model.sound_speed_mps)[:m]
        nu[0] = wrap_angle(nu[0])
        H = bf_jacobian(xp, model.sound_speed_mps)[:m]
        S = H @ Pp @ H.T + model.R[:m, :m]
        try:
            nis[k], dof[k] = float(nu @ np.linalg.solve(S, nu)), m
        except np.linalg.LinAlgError:
            continue
    return nis, dof

"""Observer advice: the next ownship leg that most reduces the predicted range uncertainty of the target(s).

Criterion (the expected Fisher information of observer trajectory optimisation for bearings-only TMA: Hammel,
Liu, Hilliard & Gong 1989, "Optimal observer motion for localization with bearing measurements", Computers &
Mathematics with Applications 18(1-3):171-180; Oshman & Davidson 1999, "Optimization of observer trajectories for
bearings-only target localization", IEEE Trans. AES 35(3):892-902; Passerieux & Van Cappel 1998, "Optimal observer
maneuver for bearings-only tracking", IEEE Trans. AES 34(3):777-788, for a target at constant velocity). For a
target of current state X = [x, y, vx, vy] (m, m/s) at time t0 with covariance P, and a candidate ownship path
o(tau), the information about X after the bearings at tau_k = dt, 2 dt, ..., <= T (the horizon) is

    J = P^-1 + sum_k H_k^T H_k / sigma^2,   H_k = [dy_k, -dx_k, tau_k dy_k, -tau_k dx_k] / r_k^2

(batch_ml.py eq. 16) at the predicted positions d_k = (x + vx tau_k, y + vy tau_k) - o(tau_k), r_k = |d_k|. The
predicted covariance at the horizon is P_T = F J^-1 F^T with F the constant-velocity transition over T, and the
predicted range sd is sqrt(u^T P_T[:2, :2] u), u the unit vector from the ownship to the target at T.

Candidates: the ownship keeps its present velocity until the turn (now, +5 or +10 min by default), then steers a
new course (every 10 deg) at the same speed until the horizon (25 min by default: new legs of 25, 20 and 15 min,
so every candidate is judged at the same time, on the same number of bearings); the turn itself is taken as
instantaneous (a 90 deg turn at 3 deg/s takes 30 s of a 15-25 min leg). The advice minimises the predicted range
sd at the horizon of one target, or the largest (``objective="max"``) or mean one over several. Everything is
vectorised over targets x candidates x bearings: 36 courses x 3 turn times x 150 bearings take milliseconds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import InputError, require

#: candidate times to turn (s from now)
TURN_DELAYS_S = (0.0, 300.0, 600.0)
#: time at which every candidate's range sd is judged (s from now)
HORIZON_S = 1500.0
#: spacing of the candidate courses (deg)
COURSE_STEP_DEG = 10.0
#: alternatives differ from the advice and from each other by at least this course (deg)
MIN_ALTERNATIVE_SEPARATION_DEG = 30.0


@dataclass(frozen=True, slots=True)
class ObserverAdvice:
    """The advised leg, every candidate's predicted range sd, and the references (now, holding course).

    ``course_deg``, ``turn_delay_s`` and ``range_sd_m`` (m,) describe the candidates (the objective over the
    targets), ``range_sd_per_target_m`` (m, n_targets) each target's; ``best`` indexes the advice and
    ``alternatives`` 2-3 others whose courses differ from it and from each other. ``now_range_sd_m`` and
    ``hold_range_sd_m`` are the objective now and at the horizon when holding the present course and speed.
    """

    time_s: float
    horizon_s: float
    own_xy_m: np.ndarray
    own_velocity_mps: np.ndarray
    course_deg: np.ndarray
    turn_delay_s: np.ndarray
    range_sd_m: np.ndarray
    range_sd_per_target_m: np.ndarray
    best: int
    alternatives: np.ndarray
    now_range_sd_m: float
    hold_range_sd_m: float
    objective: str

    def ownship_path(self, index: int | None, tau_s) -> np.ndarray:
        """Ownship positions (n, 2) (m) at times ``tau_s`` after now on candidate ``index`` (None: holding course).

        Parameters
        ----------
        index : int or None
            Candidate index.
        tau_s : array_like, shape (n,)
            Times from now (s).

        Returns
        -------
        ndarray, shape (n, 2)
            Positions (m; x east, y north).
        """
        v = np.asarray(self.own_velocity_mps, float)
        if index is None:
            return candidate_paths(self.own_xy_m, v, np.array([np.arctan2(v[0], v[1])]), np.zeros(1), tau_s)[0]
        c = np.array([np.radians(self.course_deg[index])])
        return candidate_paths(self.own_xy_m, v, c, np.array([self.turn_delay_s[index]]), tau_s)[0]

    def line(self) -> str:
        """The advice in one line: the course and time to turn, the predicted range sd, the alternatives.

        Returns
        -------
        str
            E.g. ``advice: turn to 045 deg at t = 1740 s (in 5 min); predicted range sd 0.42 km after 25 min
            (now 2.10 km; holding course 1.90 km); alternatives: 090 deg now 0.55 km, ...``.
        """
        def when(i):
            d = float(self.turn_delay_s[i])
            return "now" if d == 0 else f"at t = {self.time_s + d:.0f} s (in {d / 60:.0f} min)"

        b = self.best
        what = "" if self.objective == "single" else f" ({self.objective} over {self.range_sd_per_target_m.shape[1]} " \
                                                     "targets)"
        alts = ", ".join(f"{self.course_deg[i]:03.0f} deg "
                         f"{'now' if self.turn_delay_s[i] == 0 else f'in {self.turn_delay_s[i] / 60:.0f} min'} "
                         f"{self.range_sd_m[i] / 1e3:.2f} km" for i in self.alternatives)
        return (f"advice: turn to {self.course_deg[b]:03.0f} deg {when(b)}; predicted range sd{what} "
                f"{self.range_sd_m[b] / 1e3:.2f} km after {self.horizon_s / 60:.0f} min (now "
                f"{self.now_range_sd_m / 1e3:.2f} km; holding course {self.hold_range_sd_m / 1e3:.2f} km); "
                f"alternatives: {alts}")


def candidate_paths(own_xy, own_velocity, course_rad, turn_delay_s, tau_s) -> np.ndarray:
    """Ownship positions on each candidate leg: present velocity until the turn, then the new course at the same
    speed (an instantaneous turn).

    Parameters
    ----------
    own_xy, own_velocity : array_like, shape (2,)
        Position now (m) and velocity (m/s), x east, y north.
    course_rad, turn_delay_s : ndarray, shape (m,)
        Each candidate's new course (rad, clockwise from north) and time to turn (s from now).
    tau_s : array_like, shape (k,)
        Times from now (s).

    Returns
    -------
    ndarray, shape (m, k, 2)
        Positions (m).
    """
    p0, v0 = np.asarray(own_xy, float), np.asarray(own_velocity, float)
    speed = float(np.hypot(*v0))
    tau = np.asarray(tau_s, float)[None, :, None]
    d = np.asarray(turn_delay_s, float)[:, None, None]
    v_new = speed * np.stack([np.sin(course_rad), np.cos(course_rad)], -1)[:, None, :]
    return p0 + v0 * np.minimum(tau, d) + v_new * np.maximum(tau - d, 0.0)


def bearing_information(states, tau_s, own_paths, sigma_rad: float) -> np.ndarray:
    """sum_k H_k^T H_k / sigma^2 (module doc) for every target and candidate path.

    Parameters
    ----------
    states : array_like, shape (n_t, 4)
        Target states [x, y, vx, vy] now (m, m/s).
    tau_s : array_like, shape (k,)
        Bearing times from now (s).
    own_paths : ndarray, shape (m, k, 2)
        Ownship positions at those times on each candidate (m).
    sigma_rad : float
        Bearing noise sd (rad).

    Returns
    -------
    ndarray, shape (n_t, m, 4, 4)
        The information the future bearings carry about each target's state now.
    """
    X = np.asarray(states, float)[:, None, None, :]
    tau = np.asarray(tau_s, float)
    dx = X[..., 0] + X[..., 2] * tau - own_paths[None, ..., 0]
    dy = X[..., 1] + X[..., 3] * tau - own_paths[None, ..., 1]
    r2 = dx * dx + dy * dy
    H = np.stack([dy, -dx, tau * dy, -tau * dx], -1) / r2[..., None]
    return np.einsum("tmki,tmkj->tmij", H, H) / sigma_rad**2


def range_sd_m(states, covariances, own_xy) -> np.ndarray:
    """Range sd sqrt(u^T P_pos u) (m), u the unit vector from the ownship to the target.

    Parameters
    ----------
    states : ndarray, shape (..., 4)
        Target states (m, m/s).
    covariances : ndarray, shape (..., 4, 4)
        Their covariances.
    own_xy : ndarray, shape (..., 2)
        Ownship positions (m).

    Returns
    -------
    ndarray, shape (...)
        Range sds (m).
    """
    d = np.asarray(states, float)[..., :2] - own_xy
    u = d / np.linalg.norm(d, axis=-1, keepdims=True)
    return np.sqrt(np.maximum(np.einsum("...i,...ij,...j->...", u, np.asarray(covariances)[..., :2, :2], u), 0.0))


def _past_information(covariances) -> np.ndarray:
    """P^-1 of each target's covariance, refused when P is not finite and positive definite."""
    P = np.asarray(covariances, float)
    require(bool(np.all(np.isfinite(P))), "the target covariance holds non-finite values (range not determined): "
                                          "advice needs a solution with a finite covariance")
    P = 0.5 * (P + np.swapaxes(P, -1, -2))
    try:
        np.linalg.cholesky(P)
    except np.linalg.LinAlgError:
        raise InputError("the target covariance is not positive definite: give the solution's full "
                         "covariance") from None
    return np.linalg.inv(P)


def predicted_range_sd(states, covariances, own_paths_at_horizon, info_future, horizon_s: float) -> np.ndarray:
    """Predicted range sd (m) at the horizon: P_T = F (P^-1 + J_future)^-1 F^T (module doc).

    Parameters
    ----------
    states, covariances : ndarray, shapes (n_t, 4), (n_t, 4, 4)
        Targets now.
    own_paths_at_horizon : ndarray, shape (m, 2)
        Ownship at the horizon on each candidate (m).
    info_future : ndarray, shape (n_t, m, 4, 4)
        :func:`bearing_information`.
    horizon_s : float
        Horizon (s from now).

    Returns
    -------
    ndarray, shape (n_t, m)
        Range sds (m).
    """
    J = _past_information(covariances)[:, None] + info_future
    F = np.eye(4)
    F[0, 2] = F[1, 3] = horizon_s
    P_T = F @ np.linalg.inv(J) @ F.T
    X_T = np.asarray(states, float) @ F.T
    return range_sd_m(X_T[:, None, :], P_T, own_paths_at_horizon[None])


def _alternatives(order, course_deg, n: int) -> np.ndarray:
    """Up to ``n`` candidates after the best, in order of merit, each course at least
    :data:`MIN_ALTERNATIVE_SEPARATION_DEG` from the advice's and from each other's."""
    chosen = [int(order[0])]
    for i in order[1:]:
        sep = np.abs((course_deg[i] - course_deg[chosen] + 180.0) % 360.0 - 180.0)
        if np.all(sep >= MIN_ALTERNATIVE_SEPARATION_DEG - 1e-9):
            chosen.append(int(i))
        if len(chosen) > n:
            break
    return np.array(chosen[1:], int)


def advise(states, covariances, own_xy, own_velocity, sigma_rad: float, interval_s: float, *, time_s: float = 0.0,
           horizon_s: float = HORIZON_S, turn_delays_s=TURN_DELAYS_S, course_step_deg: float = COURSE_STEP_DEG,
           objective: str = "max", n_alternatives: int = 3) -> ObserverAdvice:
    """The candidate leg of least predicted range sd at the horizon (module doc).

    Parameters
    ----------
    states : array_like, shape (4,) or (n_t, 4)
        Target state(s) [x, y, vx, vy] now (m, m/s).
    covariances : array_like, shape (4, 4) or (n_t, 4, 4)
        Their covariances (finite, positive definite).
    own_xy, own_velocity : array_like, shape (2,)
        Ownship position (m) and velocity (m/s) now; the speed is kept on every candidate.
    sigma_rad : float
        Bearing noise sd (rad).
    interval_s : float
        Time between bearings (s).
    time_s : float
        The time now (s; for the printed turn time).
    horizon_s, turn_delays_s, course_step_deg : float, sequence of float, float
        Candidate grid (module doc); every delay must be below the horizon.
    objective : str
        "max" or "mean" of the targets' range sds (one target: either).
    n_alternatives : int
        How many alternatives to name.

    Returns
    -------
    ObserverAdvice
        The advice and every candidate's predicted range sd.
    """
    X = np.atleast_2d(np.asarray(states, float))
    P = np.asarray(covariances, float).reshape(len(X), 4, 4)
    p0, v0 = np.asarray(own_xy, float), np.asarray(own_velocity, float)
    delays = np.asarray(turn_delays_s, float)
    require(objective in ("max", "mean"), f"objective must be 'max' or 'mean', got {objective!r}")
    require(np.isfinite(sigma_rad) and sigma_rad > 0, f"the bearing sd must be positive, got {sigma_rad}")
    require(np.isfinite(interval_s) and 0 < interval_s < horizon_s,
            f"the bearing interval must be positive and shorter than the horizon ({horizon_s:g} s), got {interval_s}")
    require(bool(np.all(np.isfinite(X))) and bool(np.all(np.isfinite(np.r_[p0, v0]))),
            "target states and the ownship position and velocity must be finite")
    require(bool(np.all((delays >= 0) & (delays < horizon_s))), "turn times must lie in [0, horizon)")
    courses = np.arange(0.0, 360.0, course_step_deg)
    c_deg, d_s = np.repeat(courses, len(delays)), np.tile(delays, len(courses))
    tau = np.arange(1, int(np.floor(horizon_s / interval_s)) + 1) * interval_s
    hold = np.arctan2(v0[0], v0[1])  # holding course: the present course, turning now to itself
    c_all = np.r_[np.radians(c_deg), hold]
    paths = candidate_paths(p0, v0, c_all, np.r_[d_s, 0.0], np.r_[tau, horizon_s])
    sd = predicted_range_sd(X, P, paths[:, -1], bearing_information(X, tau, paths[:, :-1], sigma_rad), horizon_s)
    reduce = np.max if objective == "max" or len(X) == 1 else np.mean
    score = reduce(sd, axis=0)
    order = np.argsort(score[:-1], kind="stable")
    now = reduce(range_sd_m(X, P, p0[None]))
    return ObserverAdvice(time_s=float(time_s), horizon_s=float(horizon_s), own_xy_m=p0, own_velocity_mps=v0,
                          course_deg=c_deg, turn_delay_s=d_s, range_sd_m=score[:-1], range_sd_per_target_m=sd[:, :-1].T,
                          best=int(order[0]), alternatives=_alternatives(order, c_deg, n_alternatives),
                          now_range_sd_m=float(now), hold_range_sd_m=float(score[-1]),
                          objective="single" if len(X) == 1 else objective)


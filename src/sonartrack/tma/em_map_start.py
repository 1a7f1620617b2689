"""em-map's starting points: a grid search over tracks through a point on the first bearing line and one on the
last, scored by the direct bearing + SNR log-likelihood (tma/em_map.py's initialisation, moved out of it; robust to
the multimodal SNR of convergence zones: the best few starts in distinct range basins).
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.tma.em_map import EmProblem


def direct_log_likelihood(prob: EmProblem, x0s) -> np.ndarray:
    """log p(bearings, SNRs | X0) for many X0 (m, 4): the initial grid search's score.

    Parameters
    ----------
    prob : EmProblem
        The data and model (:func:`make_problem`).
    x0s : array_like, shape (m, 4) or (4,)
        Candidate X0s (m, m/s).

    Returns
    -------
    ndarray, shape (m,)
        The scores; -inf for a candidate whose ranges leave the grid.
    """
    x0s = np.atleast_2d(x0s)
    bearing_term, j, outside = _candidate_geometry(prob, x0s)
    ll_snr = prob.log_snr_lik[prob.terms.rows[:, 0], j]  # log p(xi_n | r_j) at each candidate's range
    out = bearing_term + ll_snr.sum(axis=1)
    return np.where(outside, -np.inf, out)


#: [(key, geometry)] of the last :func:`_candidate_geometry`. The geometry of the grid search depends on
#: the bearings, times, ownship and range grid only, not on the SNR model, so solves of the same data
#: under several SNR models (a source-level sweep) share it.
_GEOMETRY_MEMO: list = [None]


def _candidate_geometry(prob: EmProblem, x0s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For candidates X0 (m, 4): the bearing log-likelihood term (m,), each frame's grid index of the
    candidate's range (m, n), and whether any frame's range falls off the grid (m,)."""
    key = b"|".join(np.ascontiguousarray(a).tobytes() + str(np.asarray(a).dtype).encode() + str(np.shape(a)).encode()
                    for a in (x0s, prob.tau_s, prob.own_xy, prob.theta_rad, prob.sigma_rad, prob.r_grid))
    last = _GEOMETRY_MEMO[0]  # read once (see tma/em_map.py _e_step)
    if last is not None and last[0] == key:
        return last[1]
    dx = x0s[:, None, 0] + x0s[:, None, 2] * prob.tau_s - prob.own_xy[:, 0]
    dy = x0s[:, None, 1] + x0s[:, None, 3] * prob.tau_s - prob.own_xy[:, 1]
    rng = np.hypot(dx, dy)
    e_b = wrap_angle(prob.theta_rad - np.arctan2(dx, dy)) / prob.sigma_rad
    lr = np.log(prob.r_grid)
    j = np.clip(np.searchsorted(lr, np.log(np.maximum(rng, 1e-9))), 0, len(lr) - 1)
    out = (-0.5 * np.sum(e_b**2, axis=1), j, ((rng < prob.r_grid[0]) | (rng > prob.r_grid[-1])).any(axis=1))
    _GEOMETRY_MEMO[0] = (key, out)
    return out


def grid_initialisation(prob: EmProblem, n: int = 64, n_starts: int = 4) -> np.ndarray:
    """Starting X0s: tracks through (first bearing, range r_a) and (last bearing, range r_b) over an
    n x n log grid, scored by the direct bearing + SNR log-likelihood; the best ``n_starts`` whose
    initial ranges differ by more than 20 % (distinct basins: direct path, convergence zones), best first.

    Parameters
    ----------
    prob : EmProblem
        The data and model (:func:`make_problem`).
    n : int
        Ranges per bearing line.
    n_starts : int
        Most starts returned.

    Returns
    -------
    ndarray, shape (k, 4)
        Starts [x0, y0, vx, vy] (m, m/s), 1 <= k <= n_starts.
    """
    r = np.geomspace(prob.r_grid[0] * 1.01, prob.r_grid[-1] * 0.99, n)
    u0 = np.array([np.sin(prob.theta_rad[0]), np.cos(prob.theta_rad[0])])
    u1 = np.array([np.sin(prob.theta_rad[-1]), np.cos(prob.theta_rad[-1])])
    ra, rb = np.meshgrid(r, r, indexing="ij")
    p0 = prob.own_xy[0] + ra.ravel()[:, None] * u0
    p1 = prob.own_xy[-1] + rb.ravel()[:, None] * u1
    v = (p1 - p0) / prob.tau_s[-1]
    cands = np.column_stack([p0, v])
    score = direct_log_likelihood(prob, cands)
    order = np.argsort(-score, kind="stable")
    chosen: list[int] = []
    for i in order:
        if not np.isfinite(score[i]):
            break
        if all(abs(np.log(ra.ravel()[i] / ra.ravel()[j])) > 0.2 for j in chosen):
            chosen.append(int(i))
            if len(chosen) == n_starts:
                break
    if not chosen:
        chosen = [int(order[0])]
    return cands[chosen]

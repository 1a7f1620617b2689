"""The capped constant-velocity fit of one contact sequence, the likelihood sides.py compares its two hypotheses by.

z_k = p0 + (t_k - t_0) v with each contact's covariance R_k, by weighted least squares with each contact's
chi-square capped at c (a stray contact costs c): ln L = -(min_p sum_k min(r_k, c) + sum ln det(2 pi R_k)) / 2
(sides.py's module doc: the equations, the cap and why; Hampel et al., Robust Statistics, 1986, the truncated
quadratic). Beside it: whether a joined segment's contacts can be the same object's (``reachable``), and the CV
prediction and Kalman update the retrodiction runs back with.
"""

from __future__ import annotations

import numpy as np

#: refits of the capped CV fit beyond two per contact (it stops when the kept set repeats)
MAX_REFITS = 10


class CvFit:
    """One contact sequence and its CV fit with each contact's chi-square capped at ``cap`` (module doc); each
    contact's ping time ``at`` (s) and the array's heading ``h`` (rad) then are kept beside, for carrying it over a
    join (:meth:`SideTracker.carry`)."""

    __slots__ = ("cap", "t", "z", "W", "logdet", "live", "at", "h")

    def __init__(self, cap: float = np.inf):
        self.cap, self.t, self.z, self.W, self.logdet, self.live = float(cap), [], [], [], 0.0, []
        self.at, self.h = [], []

    @property
    def n(self) -> int:
        """The number of contacts."""
        return len(self.t)

    def add(self, dt_s: float, z, R, live: bool = True, t_s: float = np.nan, heading_rad: float = np.nan) -> None:
        """Add a contact: its time ``dt_s`` (s, from the sequence's origin), position ``z`` (2,) m, covariance ``R``
        (2, 2) m^2, whether the track itself took it (``live``; False: found by retrodiction), its ping time ``t_s``
        (s) and the array's heading then (rad)."""
        self.t.append(float(dt_s))
        self.z.append(np.asarray(z, float))
        self.W.append(np.linalg.inv(R))
        self.logdet += float(np.log(np.linalg.det(2.0 * np.pi * R)))
        self.live.append(bool(live))
        self.at.append(float(t_s))
        self.h.append(float(heading_rad))

    def subset(self, keep) -> CvFit:
        """The fit of the contacts ``keep`` (indices) alone."""
        out = CvFit(self.cap)
        for k in keep:
            out.add(self.t[k], self.z[k], np.linalg.inv(self.W[k]), self.live[k], self.at[k], self.h[k])
        return out

    @staticmethod
    def joined(fits) -> CvFit:
        """One fit of the contacts of ``fits`` (their times from their ping times ``at``)."""
        out = CvFit(fits[0].cap)
        t0 = min(min(f.at) for f in fits)
        for f in fits:
            for k in range(f.n):
                out.add(f.at[k] - t0, f.z[k], np.linalg.inv(f.W[k]), f.live[k], f.at[k], f.h[k])
        return out

    def turn_rad(self) -> float:
        """The change of the array's heading over the contacts (rad; 0 when any heading is unknown)."""
        h = np.array(self.h, float)
        return float(h.max() - h.min()) if len(h) and np.isfinite(h).all() else 0.0

    def log_likelihood(self) -> float:
        """ln L = -(sum_k min(r_k, cap) + sum ln det(2 pi R_k)) / 2 at the CV motion that minimises it (r_k the
        contact's chi-square against it), searched from two starts, the track's own (live) contacts and all of
        them, keeping the smaller sum (:func:`capped_chi2`)."""
        t, z, W = np.array(self.t), np.array(self.z), np.array(self.W)
        A = np.zeros((len(t), 2, 4))
        A[:, [0, 1], [0, 1]] = 1.0
        A[:, [0, 1], [2, 3]] = t[:, None]
        AtW = np.swapaxes(A, 1, 2) @ W
        info, b = AtW @ A, np.einsum("kij,kj->ki", AtW, z)
        starts = [np.ones(len(t), bool)] + ([np.array(self.live)] if 2 <= sum(self.live) < len(t) else [])
        chi2 = min(capped_chi2(t, z, W, info, b, keep, self.cap) for keep in starts)
        return -0.5 * (chi2 + self.logdet)


def capped_chi2(t, z, W, info, b, keep, cap: float) -> float:
    """sum_k min(r_k, cap) at a local minimum over the CV motion, from the fit of the contacts ``keep``: the kept
    contact of the largest r_k >= cap is left out and the rest refitted, one at a time; then every contact under
    the cap is taken back, until the kept set repeats (t (n,) s, z (n, 2), W = R^-1, info = A^T W A and
    b = A^T W z per contact, A = [I, t I])."""
    keep = np.array(keep, bool)
    info_sum, b_sum = info[keep].sum(0), b[keep].sum(0)
    for _ in range(2 * len(z) + MAX_REFITS):
        try:  # two contacts at different times make info_sum regular
            p = np.linalg.solve(info_sum, b_sum)
        except np.linalg.LinAlgError:
            p = np.linalg.lstsq(info_sum, b_sum, rcond=None)[0]
        nu = z - p[:2] - t[:, None] * p[2:]
        r = np.einsum("ki,kij,kj->k", nu, W, nu)
        worst = int(np.argmax(np.where(keep, r, -np.inf)))
        if r[worst] >= cap and keep.sum() > 2:
            keep[worst] = False
            info_sum, b_sum = info_sum - info[worst], b_sum - b[worst]
        elif np.array_equal(r < cap, keep) or (r < cap).sum() < 2:
            break
        else:
            keep = r < cap
            info_sum, b_sum = info[keep].sum(0), b[keep].sum(0)
    return float(np.minimum(r, cap).sum())

#: a joined segment's contacts are carried only when they can be the same target's: a target moves at most this fast
#: (m/s; 40 kn), and a piece whose contact nearest in time to the track's lies farther than MAX_SPEED_MPS |dt| plus
#: CARRY_SIGMAS standard deviations from it is another object's (a false track merged into a ghost: trial 15)
MAX_SPEED_MPS = 20.0
#: standard deviations of the two contacts' position errors allowed beyond the reach at MAX_SPEED_MPS
CARRY_SIGMAS = 4.0


def reachable(piece: CvFit, ref: list[CvFit]) -> bool:
    """Whether ``piece``'s contacts can be the target of the contact sequences ``ref``: of the pairs (one of the piece,
    one of ``ref``), the one nearest in time lies within MAX_SPEED_MPS |dt| + CARRY_SIGMAS sqrt(lambda_max(R_i + R_j))
    (True when ``ref`` holds no contact)."""
    t_ref = np.array([t for f in ref for t in f.at], float)
    if not len(t_ref) or not piece.n:
        return True
    z_ref = np.array([z for f in ref for z in f.z], float)
    W_ref = [w for f in ref for w in f.W]
    gap = np.abs(np.array(piece.at, float)[:, None] - t_ref[None, :])
    i, j = np.unravel_index(int(np.argmin(gap)), gap.shape)
    spread = np.linalg.inv(piece.W[i]) + np.linalg.inv(W_ref[j])
    reach = MAX_SPEED_MPS * gap[i, j] + CARRY_SIGMAS * np.sqrt(np.linalg.eigvalsh(spread)[-1])
    return bool(np.hypot(*(piece.z[i] - z_ref[j])) <= reach)


def _predict(x, P, dt_s: float, q: float):
    """CV prediction over ``dt_s`` (negative: backwards), white-noise acceleration q over |dt|."""
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt_s
    a = abs(dt_s)
    Q = q * np.kron(np.array([[a**3 / 3, a**2 / 2 * np.sign(dt_s)], [a**2 / 2 * np.sign(dt_s), a]]), np.eye(2))
    return F @ x, F @ P @ F.T + Q


def _kalman_update(x, P, z, R):
    """Kalman update of a CV state with a position contact z (covariance R)."""
    S = P[:2, :2] + R
    K = np.linalg.solve(S, P[:2, :]).T
    return x + K @ (z - x[:2]), P - K @ S @ K.T

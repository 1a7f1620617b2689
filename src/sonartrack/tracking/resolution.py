"""Two bearing tracks closer than the array's resolution share one peak: a merged-measurement model.

Where two ships cross in cone angle the beamformer shows one peak, at about the power-weighted centroid of the two
cone angles, for as long as they lie within about a beamwidth of each other. Plain JPDA lets both tracks take that
one peak (each with beta ~ 1/2), pulls both onto it and they leave the crossing as one: track coalescence
(Blom & Bloem, "Probabilistic data association avoiding track coalescence", IEEE Trans. Automatic Control 45(2),
2000). With a resolution model (Koch & van Keuk, "Multiple hypothesis track maintenance with possibly unresolved
measurements", IEEE Trans. AES 33(3), 1997; Daum & Fitzgerald, "Importance of resolution in multiple-target
tracking", Proc. SPIE 2235, 1994) a pair of tracks a, b whose predicted cone angles lie within ``resolution_deg``
is one group measured by one peak of the centroid

    z = w phi_a + (1 - w) phi_b + v,     w = s_a / (s_a + s_b)   (s: the tracks' amplitude strengths, P0 eq. 9)

with var v = sigma_p^2 + d^2 / 12 (d = theta_a - theta_b): where between the two the one peak lies depends on the
levels and the beam pattern (a louder ship can mask the other), so it is taken uniform over the pair's separation.

The group enters the association as one track (state w x_a + (1 - w) x_b, covariance w^2 P_a + (1 - w)^2 P_b, the
two tracks independent before the update), so it competes for the peaks with the other tracks as one target does,
and its PDA update (combined innovation nu_c, covariance reduction gamma = (1 - beta_0) S - spread, S the group's
innovation variance) is split onto the members by the joint Kalman gain of that measurement (H = [w, 0, 1 - w, 0]):

    K_a = w P_a[:, 0] / S,   K_b = (1 - w) P_b[:, 0] / S,    x_i += K_i nu_c,    P_i -= gamma K_i K_i^T

(the members' cross-covariance the update creates is dropped: each track keeps its marginal). Both members move
with the shared peak while their difference - set by their own bearing rates - is left as predicted, so each
leaves the crossing on its own side. DEVIATION from Koch & van Keuk: the pair is unresolved when its predictions
lie within ``resolution_deg`` (a hard resolution cell, about a beamwidth) instead of with a resolution probability
that falls off with their distance, and a pair whose gates hold two or more peaks in a scan is resolved in that
scan (ordinary JPDA then; each peak is one ship's).

Why not JPDA* (Blom & Bloem 2000): it keeps, of the joint events that share out the same peaks among the same
detected tracks, only the likeliest permutation, so two tracks do not average over two peaks; but where two ships
cross in cone angle the array shows one peak, and {a takes it, b missed} and {b takes it, a missed} are not
permutations of one another (different tracks detected), so JPDA* is JPDA there and both tracks still move onto
the one peak. The group model is the one that describes that peak.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.tracking.measurements import fold_cone_deg


@dataclass(frozen=True, slots=True)
class Groups:
    """The tracks as the association sees them: the singles, then one merged track per unresolved pair.

    ``rows`` (n,): each track's row in the reduced arrays; ``pairs`` (k, 2): member indices a, b; ``w`` (k,):
    member a's centroid weight; ``flip`` (k,): +1 or -1, b's unfolded angle in a's branch is ``flip`` times b's."""

    x: np.ndarray
    P: np.ndarray
    attrs: dict
    rows: np.ndarray
    pairs: np.ndarray
    w: np.ndarray
    flip: np.ndarray


@dataclass(frozen=True)
class UnresolvedPairs:
    """Pairs of confirmed tracks whose predicted cone angles lie within ``resolution_deg`` (deg), with at most one
    peak within ``gate_deg`` / 2 of them, are one group (module docstring)."""

    resolution_deg: float
    gate_deg: float

    def pairs(self, x_pred, confirmed, z) -> np.ndarray:
        """The unresolved pairs, closest first, each track in at most one.

        Parameters
        ----------
        x_pred : ndarray, shape (n, 1, 2)
            Predicted [phi (deg), rate] (unfolded cone angle).
        confirmed : ndarray of bool, shape (n,)
            Only confirmed tracks form pairs.
        z : ndarray, shape (m,)
            The scan's peaks (deg): a pair with two or more peaks within half a gate of its two predictions is
            resolved in this scan.

        Returns
        -------
        ndarray of int, shape (k, 2)
            Track indices a < b of each pair.
        """
        theta = fold_cone_deg(x_pred[:, 0, 0])[0]
        idx = np.nonzero(np.asarray(confirmed, bool))[0]
        d = np.abs(theta[idx, None] - theta[None, idx])
        ia, ib = np.nonzero(np.triu(d < self.resolution_deg, 1))
        taken, out = set(), []
        z = np.asarray(z, float)
        for k in np.argsort(d[ia, ib], kind="stable"):
            a, b = int(idx[ia[k]]), int(idx[ib[k]])
            lo, hi = min(theta[a], theta[b]) - self.gate_deg / 2, max(theta[a], theta[b]) + self.gate_deg / 2
            if np.count_nonzero((z >= lo) & (z <= hi)) >= 2:
                continue
            if a not in taken and b not in taken:
                taken.update((a, b))
                out.append((a, b))
        return np.array(out, np.int64).reshape(-1, 2)

    def group(self, x_pred, P_pred, attrs: dict, pairs: np.ndarray) -> Groups:
        """The reduced tracks: singles in order, then the pairs' merged tracks (module docstring).

        Parameters
        ----------
        x_pred, P_pred : ndarray, shapes (n, 1, 2) and (n, 1, 2, 2)
            Predicted states and covariances.
        attrs : dict
            Per-track quantities (``sigma_p``, ``strength``, ``sigma_a`` among them).
        pairs : ndarray of int, shape (k, 2)
            From :meth:`pairs`.

        Returns
        -------
        Groups
            Reduced arrays and the map back to the tracks.
        """
        n = len(x_pred)
        a, b = pairs[:, 0], pairs[:, 1]
        singles = np.setdiff1d(np.arange(n), pairs.ravel())
        rows = np.empty(n, np.int64)
        rows[singles] = np.arange(len(singles))
        rows[a] = rows[b] = len(singles) + np.arange(len(pairs))
        s = np.maximum(attrs["strength"], 1e-9)
        w = s[a] / (s[a] + s[b])
        (theta, sign) = fold_cone_deg(x_pred[:, 0, 0])
        flip = sign[a] * sign[b]
        xb = np.stack([x_pred[a, 0, 0] + sign[a] * (theta[b] - theta[a]), flip * x_pred[b, 0, 1]], -1)
        wc = w[:, None]
        xm = wc * x_pred[a, 0] + (1.0 - wc) * xb
        Pm = wc[..., None] ** 2 * P_pred[a, 0] + (1.0 - wc[..., None]) ** 2 * P_pred[b, 0]
        merged = {k: v[a] for k, v in attrs.items()}
        spread = (theta[a] - theta[b]) ** 2 / 12.0  # where between the two the one peak lies: uniform over them
        merged["sigma_p"] = np.sqrt((w * attrs["sigma_p"][a] + (1.0 - w) * attrs["sigma_p"][b]) ** 2 + spread)
        merged["strength"] = attrs["strength"][a] + attrs["strength"][b]
        merged["sigma_a"] = np.hypot(attrs["sigma_a"][a], attrs["sigma_a"][b])
        red = {k: np.concatenate([v[singles], merged[k]]) for k, v in attrs.items()}
        x = np.concatenate([x_pred[singles], xm[:, None]])
        P = np.concatenate([P_pred[singles], Pm[:, None]])
        return Groups(x, P, red, rows, pairs, w, flip)

    def split(self, g: Groups, x_upd, P_upd, x_pred, P_pred, sigma_p) -> tuple[np.ndarray, np.ndarray]:
        """Every track's update: the singles' from the reduced update, the members' by the joint gain.

        Parameters
        ----------
        g : Groups
            From :meth:`group`.
        x_upd, P_upd : ndarray, shapes (n', 1, 2) and (n', 1, 2, 2)
            The reduced tracks after their PDA update.
        x_pred, P_pred : ndarray, shapes (n, 1, 2) and (n, 1, 2, 2)
            Every track's prediction.
        sigma_p : ndarray, shape (n',)
            The reduced tracks' peak spreads (deg).

        Returns
        -------
        x, P : ndarray, shapes (n, 1, 2) and (n, 1, 2, 2)
            Every track after the scan.
        """
        x, P = x_pred.copy(), P_pred.copy()
        single = np.ones(len(x), bool)
        single[g.pairs.ravel()] = False
        x[single], P[single] = x_upd[g.rows[single]], P_upd[g.rows[single]]
        m = g.rows[g.pairs[:, 0]]
        S = g.P[m, 0, 0, 0] + sigma_p[m] ** 2
        K_m = g.P[m, 0, :, 0] / S[:, None]
        nu_c = (x_upd[m, 0, 0] - g.x[m, 0, 0]) / K_m[:, 0]
        gamma = (g.P[m, 0, 0, 0] - P_upd[m, 0, 0, 0]) / K_m[:, 0] ** 2
        for col, share, sgn in ((0, g.w, np.ones(len(m))), (1, 1.0 - g.w, g.flip)):
            i = g.pairs[:, col]
            K = share[:, None] * P_pred[i, 0, :, 0] / S[:, None]
            x[i, 0] += sgn[:, None] * K * nu_c[:, None]
            P[i, 0] -= gamma[:, None, None] * K[:, :, None] * K[:, None, :]
        return x, P

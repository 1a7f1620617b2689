"""Associator parts: association weights of all tracks at once from their likelihoods (association/).

* :class:`PDA` -- each track on its own (PDA; with an existence model, IPDA; with modes, IMM-IPDA):
  beta_r0 = (1 - P_D P_G) / Lambda_r, beta_rm = P_D (p_rm / rho_m) / Lambda_r (association/pda.py).
* :class:`JPDA` -- the exact joint marginals: a measurement is shared out among the tracks that gate
  it, so that sum_t beta_tj <= 1 (association/jpda.py, paper P0). JPDA_A is JPDA on likelihoods that
  include the amplitude ratio (tracking/measurements.py). Where the maths of this package stops:
  JPDA needs one mode (IMM-JPDA needs mode-mixed event likelihoods) and no existence model (JIPDA's
  existence update differs from IPDA's), and the tracker refuses those combinations.

The update that follows is the same for both (Gaussian-mixture reduction, association/pda.py).
"""

from __future__ import annotations

import numpy as np

from sonartrack.association.jpda import jpda_log_weights
from sonartrack.association.likelihood import Likelihoods
from sonartrack.association.pda import AssociationWeights, pda_pair_weights


class _Associator:
    """What the tracker asks of an associator part (tracking/multi_target.py): whether it takes one mode only and
    whether it takes an existence model; its repr is its class's name."""

    single_mode_only = False
    supports_existence = True

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class PDA(_Associator):
    """Probabilistic data association, every track and mode independently."""

    def weights(self, lik: Likelihoods) -> AssociationWeights:
        """PDA weights of every track and mode, each on its own (association/pda.py; module docstring).

        Parameters
        ----------
        lik : Likelihoods
            Gated pairs and their log likelihood ratios (association/likelihood.py).

        Returns
        -------
        AssociationWeights
            beta_r0, beta at the gated pairs only (``beta_pair``), and log Lambda_r.
        """
        return pda_pair_weights(lik)  # pda_weights' numbers at the gated pairs only


class JPDA(_Associator):
    """Exact joint probabilistic data association (one mode, no existence)."""

    single_mode_only = True
    supports_existence = False

    def weights(self, lik: Likelihoods) -> AssociationWeights:
        """Exact JPDA marginals (association/jpda.py, paper P0) of single-mode tracks from their likelihoods
        ``lik`` (:class:`~sonartrack.association.likelihood.Likelihoods` with one mode, r = 1).

        Returns
        -------
        AssociationWeights
            beta0 (n, 1), beta (n, 1, m), and no log Lambda (None).
        """
        n, r, _ = lik.shape
        # the same values as broadcasting P_D and the miss weight to (n,) and np.clip, without their call overhead
        # (a few tracks a scan: the per-call cost is most of the time here)
        log_pd = np.log(np.asarray(lik.pd, float))
        ll = np.where(lik.gated, (log_pd[:, None] if log_pd.ndim else log_pd) + lik.log_ratio[:, 0], -np.inf)
        miss = np.asarray(lik.miss, float)
        # one value, or (n, r) (the measurement parts' shapes), or anything that broadcasts to (n, r): mode 0
        miss = np.full(n, miss) if miss.ndim == 0 else miss[:, 0] if miss.shape == (n, r) else \
            np.broadcast_to(miss, (n, r))[:, 0]
        log_miss = np.log(np.minimum(np.maximum(miss, 1e-12), 1.0))
        beta = np.exp(jpda_log_weights(ll, log_miss))
        return AssociationWeights(beta[:, :1], beta[:, None, 1:], None)


class ClaimedPDA(PDA):
    """PDA in which a track is given a measurement only as far as no track ranked above it claims it (a
    sequential, linear-cost stand-in for JIPDA's sharing of a measurement among the tracks that gate it).

    Why. IPDA runs each track on its own (:class:`PDA`): a measurement in two tracks' gates counts in full as
    each one's detection. A young track started beside a confirmed one on the same target then gains existence
    on that target's echoes and is confirmed too (the duplicate merger's work afterwards). JIPDA (Musicki & Evans
    2004, IEEE TAES 40(3), sec. IV) would weigh each joint event: the measurement is the established track's
    or the young one's, not both. Here, as in LMIPDA (Musicki & La Scala 2008, IEEE TAES 44(3), which folds the
    other tracks' detections into each track's clutter density), the rest of the tracks act on a track through its
    measurement likelihood ratios, but in one pass ordered by rank: for track t and measurement m,

        r'_tm = r_tm (1 - min(sum_{s ranked above t} chi_s beta_sm, 1 - eps)),

    with r_tm = p_tm / rho_m its likelihood ratio, chi_s the existence of track s before the scan and beta_sm the
    probability that m is s's detection from s's own PDA (association/pda.py, mode-averaged by s's mode
    probabilities): ``chi_s beta_sm`` is the probability that m is s's target's echo, and a track's ratio keeps
    the share left for "not s's". The highest-ranked track is not changed (its PDA is IPDA's), so no track is
    weakened by a track below it; the ranks are set before each scan with :meth:`set_tracks`. Deviation from
    JIPDA: one pass, the claims of the ranked-above tracks from their own PDA (not reduced by the tracks above
    them), and only tracks marked as claimers claim (e.g. the confirmed ones).
    """

    eps: float = 1e-3

    def __init__(self, linear_multitarget: bool = False) -> None:
        self.existence = self.rank = self.mu = self.claims = None
        self.linear_multitarget = bool(linear_multitarget)

    def set_tracks(self, existence, rank, mu, claims) -> None:
        """The live tracks before the scan, in the tracker's order: existence (n,), rank (n,) (higher first),
        mode probabilities (n, r) and which may claim (n,) bool."""
        self.existence, self.rank = np.asarray(existence, float), np.asarray(rank, float)
        self.mu, self.claims = np.asarray(mu, float), np.asarray(claims, bool)

    def weights(self, lik: Likelihoods) -> AssociationWeights:
        """Weights of every track and mode with the ranked claims folded in (class doc)."""
        from dataclasses import replace

        n, _, m = lik.shape
        own = pda_pair_weights(lik)
        if self.existence is None or len(self.existence) != n or not len(lik.pair_track) or not self.claims.any():
            return own
        t, j = lik.pair_track, lik.pair_meas
        if self.linear_multitarget:
            return pda_pair_weights(replace(lik, pair_log_ratio=lik.pair_log_ratio + self._lm_log_factor(lik)[:, None],
                                            dense_log_ratio=None))
        claim = (self.existence * self.claims)[t] * np.sum(own.beta_pair * self.mu[t], axis=1)  # (G,) chi_s beta_sm
        keep = 1.0 - np.minimum(_claimed_above(j, self.rank[t], claim), 1.0 - self.eps)
        return pda_pair_weights(replace(lik, pair_log_ratio=lik.pair_log_ratio + np.log(keep)[:, None],
                                        dense_log_ratio=None))

    def _lm_log_factor(self, lik: Likelihoods) -> np.ndarray:
        """LMIPDA's (Musicki & La Scala 2008) change of each gated pair's ratio, log rho_m / Omega_tm, in odds
        form: Omega_tm = rho_m (1 + sum_{s != t} P_sm / (1 - P_sm)), P_sm = chi_s P_D P_G r_sm / sum_j r_sj the
        prior probability that m is track s's detection (mode-averaged r), claimers only; ranks unused."""
        n, _, m = lik.shape
        t, j = lik.pair_track, lik.pair_meas
        r = np.sum(np.exp(np.minimum(lik.pair_log_ratio, 700.0)) * self.mu[t], axis=1)  # (G,)
        total = np.bincount(t, weights=r, minlength=n)
        pdpg = 1.0 - np.asarray(lik.miss, float)
        pdpg = np.broadcast_to(pdpg if pdpg.ndim == 0 else pdpg.reshape(n, -1)[:, 0], (n,))
        p = np.minimum((self.existence * self.claims * pdpg)[t] * r / np.maximum(total[t], 1e-300), 1.0 - self.eps)
        odds = p / (1.0 - p)
        others = np.bincount(j, weights=odds, minlength=m)[j] - odds
        return -np.log1p(others)


def _claimed_above(meas, rank, claim) -> np.ndarray:
    """For each gated pair (track, measurement ``meas``) with its track's ``rank``, the sum of ``claim`` over the
    pairs of the same measurement whose tracks rank strictly higher (O(G log G) in the gated pairs G)."""
    order = np.lexsort((-rank, meas))
    j, r, c = meas[order], rank[order], claim[order]
    before = np.cumsum(c) - c  # exclusive running sum over the sorted pairs
    new_j = np.r_[True, j[1:] != j[:-1]]
    new_run = new_j | np.r_[True, r[1:] != r[:-1]]  # a run: one measurement's pairs of one rank (ties claim not)
    idx = np.arange(len(j))
    j_start = np.maximum.accumulate(np.where(new_j, idx, 0))
    run_start = np.maximum.accumulate(np.where(new_run, idx, 0))
    out = np.empty(len(j))
    out[order] = before[run_start] - before[j_start]
    return out

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

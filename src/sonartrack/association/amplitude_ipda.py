"""Amplitude feature of a position contact for IPDA: the ratio p1(a | target, above tau) / p0(a | clutter, above tau).

Lerro & Bar-Shalom (IEEE TAES 29(4), 1993, "Interacting multiple model tracking with target amplitude feature",
eq. 12) multiply each measurement's likelihood ratio p_j / rho in the PDA weights by the ratio of its amplitude's
density under "target" to its density under "clutter", both conditioned on the detection (a above the detector's
threshold tau); Musicki & Evans carry the same factor into IPDA's existence update, which is Lambda = 1 - P_D P_G +
P_D P_G sum_j (p_j / rho_j) (association/ipda.py): the factor enters both through the pair log ratio.

Swerling 1 target in exponential (Rayleigh-envelope) clutter, on the square-law (power) scale: the clutter power
above tau is tau + Exp(mean m0) and the target's tau + Exp(mean m1) (memoryless: Lerro & Bar-Shalom's
p^tau = p / P_FA and p / P_D in power units), so with the excess y = a - tau

    log r(y) = log(m0 / m1) + y (1 / m0 - 1 / m1)            (:func:`exponential_excess_log_ratio`)

The active chain's clutter is not Rayleigh (K, spiky K, persistent points, the MFTD's log statistic beside the
single-ping one), so here (:class:`AmplitudeModel`):

* clutter: the excess above the lowest amplitude seen, tau0, follows a generalised Pareto law (the peaks-over-
  threshold law of a tail; shape xi = 0 is the exponential, xi > 0 heavier, a K tail), fitted by probability-
  weighted moments (Hosking & Wallis 1987, Technometrics 29(3), sec. 3) to the amplitudes of the last
  ``clutter_scans`` scans' contacts, with ``clutter_prior_n`` pseudo-contacts of an exponential law of mean excess
  ``clutter_prior_mean``; xi is clipped to [0, 0.45] (never lighter than exponential; a finite variance).
  DEVIATION: every contact of a scan enters the sample, targets' too (the measurement part does not know which
  are confirmed tracks'): the fitted law is then the mixture (1 - eps) p0 + eps p1 and the ratio r / (1 - eps +
  eps r), a concave function of r, whose mean on clutter is <= f(E r) = f(1) = 1 (Jensen): conservative for the
  false-track rate (Ville's bound on the existence odds needs E_clutter[r] <= 1, tracking/existence.py).
* target: the track's mean excess m1 is unknown; with an inverse-gamma prior IG(alpha0, beta0) on it and the
  track's amplitudes (weighted by their association probabilities, forgotten by ``target_memory`` per scan) the
  predictive law of the next excess is Lomax: p(y) = alpha beta^alpha / (beta + y)^(alpha + 1), alpha =
  alpha0 + sum w, beta = beta0 + sum w y (conjugate exponential-gamma; Bernardo & Smith 1994, app. A), its mean
  beta / (alpha - 1) floored at the clutter's mean excess (a target is at least as strong as clutter).

The log ratio is capped at log ``max_ratio`` (a single contact far out in a tail the fit does not describe cannot
confirm a track on its own).
"""

from __future__ import annotations

import numpy as np

#: xi range of the clutter law: never lighter than exponential, finite variance
SHAPE_MAX = 0.45


def exponential_excess_log_ratio(excess, target_mean, clutter_mean) -> np.ndarray:
    """log p1(y) / p0(y) of an exponential target excess (mean m1) against an exponential clutter excess (mean m0).

    Swerling 1 target in Rayleigh clutter on the power scale above the threshold (module doc; Lerro & Bar-Shalom
    1993, eq. 12 with the Rayleigh densities): ``log(m0 / m1) + y (1 / m0 - 1 / m1)``.

    Parameters
    ----------
    excess : array_like
        y = a - tau (the statistic's unit).
    target_mean, clutter_mean : float or array_like
        m1 = 1 + SNR and m0 = 1 for a noise-normalised power (same unit as y).

    Returns
    -------
    ndarray
        log r, broadcast shape.
    """
    y, m1, m0 = (np.asarray(v, float) for v in (excess, target_mean, clutter_mean))
    return np.log(m0 / m1) + y * (1.0 / m0 - 1.0 / m1)


def gpd_log_pdf(excess, scale, shape) -> np.ndarray:
    """log density of the generalised Pareto law at y >= 0: ``-log s - (1 / xi + 1) log(1 + xi y / s)`` (xi > 0),
    ``-log s - y / s`` (xi = 0)."""
    y, s, xi = np.asarray(excess, float), float(scale), float(shape)
    if xi < 1e-9:
        return -np.log(s) - y / s
    return -np.log(s) - (1.0 / xi + 1.0) * np.log1p(xi * y / s)


def lomax_log_pdf(excess, alpha, beta) -> np.ndarray:
    """log of the Lomax (Pareto II) density ``alpha beta^alpha / (beta + y)^(alpha + 1)``: the predictive law of an
    exponential excess whose mean has the inverse-gamma posterior IG(alpha, beta)."""
    y, a, b = (np.asarray(v, float) for v in (excess, alpha, beta))
    return np.log(a) + a * np.log(b) - (a + 1.0) * np.log(b + y)


class AmplitudeModel:
    """The clutter amplitude law of recent scans and the target law of each track (module doc); mutable: one
    instance is shared by the measurement part (the ratios) and the initiator (which feeds it each scan).

    Parameters
    ----------
    clutter_prior_mean, clutter_prior_n : float
        The prior's exponential mean excess (the statistic's unit) and its weight in pseudo-contacts.
    clutter_scans : int
        Scans whose contacts make the clutter sample (the last ones).
    target_prior_ratio, target_prior_n : float
        A new track's prior mean excess as a multiple of the clutter's, and its weight alpha0 - 1 (> 0).
    max_ratio : float
        Cap on the amplitude likelihood ratio.
    """

    def __init__(self, clutter_prior_mean: float, clutter_prior_n: float, clutter_scans: int,
                 target_prior_ratio: float, target_prior_n: float, max_ratio: float):
        from collections import deque

        self.prior_mean, self.prior_n = float(clutter_prior_mean), float(clutter_prior_n)
        self.target_ratio, self.target_n, self.log_cap = float(target_prior_ratio), float(target_prior_n), \
            float(np.log(max_ratio))
        self.floor = np.inf  # tau0: the lowest amplitude seen
        self.scans: deque = deque(maxlen=int(clutter_scans))
        self._law: tuple[float, float] | None = None

    def add_scan(self, amplitudes) -> None:
        """Add a scan's amplitudes (every contact: module doc); the oldest scan beyond ``clutter_scans`` goes."""
        a = np.asarray(amplitudes, float).ravel()
        if len(a):
            self.floor = min(self.floor, float(a.min()))
        self.scans.append(a)
        self._law = None

    def clutter_law(self) -> tuple[float, float]:
        """(scale, shape) of the clutter excess's generalised Pareto law by probability-weighted moments of the
        sample and the prior (Hosking & Wallis 1987: a_s = E[Y (1 - F(Y))^s]; xi = 2 - a0 / (a0 - 2 a1),
        scale = 2 a0 a1 / (a0 - 2 a1); an exponential of mean m has a0 = m, a1 = m / 4). Moments of the variance
        fail for xi >= 0.25 (the sample variance's own variance is infinite); these hold for xi < 1."""
        if self._law is None:
            y = np.sort(self.excess(np.concatenate(list(self.scans)) if self.scans else np.zeros(0)))
            n, n0, m0 = len(y), self.prior_n, self.prior_mean
            a0 = (y.sum() + n0 * m0) / (n + n0)
            a1 = ((y @ ((n - 1 - np.arange(n)) / max(n - 1, 1)) if n > 1 else 0.0) + n0 * m0 / 4.0) / (n + n0)
            a0, a1 = max(a0, 1e-9), min(max(a1, 1e-12), 0.5 * a0 * (1.0 - 1e-9))
            shape = float(np.clip(2.0 - a0 / (a0 - 2.0 * a1), 0.0, SHAPE_MAX))
            self._law = (a0 * (1.0 - shape), shape)  # the scale that keeps the fitted mean a0 at the clipped shape
        return self._law

    def excess(self, amplitudes) -> np.ndarray:
        """y = a - tau0 (0 where a is below tau0 or before any scan)."""
        t0 = self.floor if np.isfinite(self.floor) else 0.0
        return np.maximum(np.asarray(amplitudes, float) - t0, 0.0)

    def target_posterior(self, weight, amplitude_sum) -> tuple[np.ndarray, np.ndarray]:
        """(alpha, beta) of each track's inverse-gamma posterior on its mean excess from its weighted amplitudes
        (``weight`` sum w, ``amplitude_sum`` sum w a, raw), the prior mean the clutter's times ``target_prior_ratio``
        and the posterior mean floored at the clutter's."""
        scale, shape = self.clutter_law()
        clutter_mean = scale / (1.0 - shape)
        t0 = self.floor if np.isfinite(self.floor) else 0.0
        w = np.asarray(weight, float)
        alpha = 1.0 + self.target_n + w
        beta = self.target_n * self.target_ratio * clutter_mean + np.maximum(np.asarray(amplitude_sum, float)
                                                                             - w * t0, 0.0)
        return alpha, np.maximum(beta, (alpha - 1.0) * clutter_mean)

    def log_ratio(self, amplitudes, weight, amplitude_sum) -> np.ndarray:
        """Capped ``log p1(y) / p0(y)`` of amplitudes (G,) under their tracks' laws (``weight``, ``amplitude_sum``
        (G,) each: the track of each pair) against the clutter's (module doc)."""
        y = self.excess(amplitudes)
        alpha, beta = self.target_posterior(weight, amplitude_sum)
        scale, shape = self.clutter_law()
        return np.minimum(lomax_log_pdf(y, alpha, beta) - gpd_log_pdf(y, scale, shape), self.log_cap)

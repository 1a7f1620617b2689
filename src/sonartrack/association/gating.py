"""Chi-square (ellipsoidal) validation gates.

A measurement z is in the gate of a prediction with innovation covariance S when
``(z - z_hat)^T S^-1 (z - z_hat) < gamma``; for an m-dimensional Gaussian innovation the gate
probability is ``P_G = F_chi2(gamma; m)`` (Bar-Shalom, Li, Kirubarajan 2001, sec. 2.6).
For m = 2 both directions are closed form: ``P_G = 1 - exp(-gamma / 2)``.
"""

from __future__ import annotations

import math

from sonartrack.core.gaussian import chi2_quantile


def gate_threshold(gate_probability: float, dim: int = 2) -> float:
    """Chi-square gate size gamma with ``F_chi2(gamma; dim) = gate_probability`` (Bar-Shalom et al. 2001, sec. 2.6).

    Closed form for dim = 2: ``gamma = -2 log(1 - P_G)``; scipy's chi2.ppf otherwise.

    Parameters
    ----------
    gate_probability : float
        P_G, the probability that a Gaussian innovation falls in the gate, in (0, 1).
    dim : int, default 2
        Measurement dimension.

    Returns
    -------
    float
        gamma, the threshold on the squared Mahalanobis distance.

    Raises
    ------
    ValueError
        If ``gate_probability`` is not in (0, 1).
    """
    if not 0.0 < gate_probability < 1.0:
        raise ValueError("gate probability must be in (0, 1)")
    if dim == 2:
        return -2.0 * math.log1p(-gate_probability)
    return chi2_quantile(gate_probability, dim)


def gate_probability(gamma: float, dim: int = 2) -> float:
    """Gate probability ``P_G = F_chi2(gamma; dim)`` of a chi-square gate of size gamma.

    Closed form for dim = 2: ``P_G = 1 - exp(-gamma / 2)``.

    Parameters
    ----------
    gamma : float
        Threshold on the squared Mahalanobis distance.
    dim : int, default 2
        Measurement dimension.

    Returns
    -------
    float
        P_G in [0, 1].
    """
    if dim == 2:
        return -math.expm1(-gamma / 2.0)
    from scipy.special import gammainc  # chi2.cdf's own formula, without scipy.stats' import

    return float(gammainc(dim / 2.0, gamma / 2.0))

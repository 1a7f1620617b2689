"""Chi-square (ellipsoidal) validation gates.

A measurement z is in the gate of a prediction with innovation covariance S when
``(z - z_hat)^T S^-1 (z - z_hat) < gamma``; for an m-dimensional Gaussian innovation the gate
probability is ``P_G = F_chi2(gamma; m)`` (Bar-Shalom, Li, Kirubarajan 2001, sec. 2.6).
For m = 2 both directions are closed form: ``P_G = 1 - exp(-gamma / 2)``.
"""

from __future__ import annotations

import math


def gate_threshold(gate_probability: float, dim: int = 2) -> float:
    """gamma such that a chi-square(dim) variable is below it with ``gate_probability``."""
    if not 0.0 < gate_probability < 1.0:
        raise ValueError("gate probability must be in (0, 1)")
    if dim == 2:
        return -2.0 * math.log1p(-gate_probability)
    from scipy.stats import chi2

    return float(chi2.ppf(gate_probability, dim))


def gate_probability(gamma: float, dim: int = 2) -> float:
    """P_G of a chi-square(dim) gate of size gamma."""
    if dim == 2:
        return -math.expm1(-gamma / 2.0)
    from scipy.stats import chi2

    return float(chi2.cdf(gamma, dim))

"""The law of a CW cell's noise estimate in homogeneous exponential noise, its threshold, and the map between laws.

The normaliser of detection/cw_cells.py divides a cell's power y by M = max(mu_f, G), mu_f the OS estimate across
Doppler and G = sqrt(mu_e mu_l) of the OS estimates before and after the cell along delay (the early delays:
G = mu_1^(1 + r) / mu_2^r of the two later windows, r >= 0).

Threshold. In homogeneous exponential noise the three estimates use disjoint cells, so they are independent,
and for s = y / M with y exponential (mean 1):

    P(s > alpha) = E[exp(-alpha M)] = alpha int_0^inf exp(-alpha m) F_M(m) dm,   M = max(mu_f, G), G = sqrt(mu_e mu_l)

(integration by parts), F_M = F_f F_G, F_f the CDF of an OS estimate x_(k) / c_k of N unit exponentials,
P(x_(k) <= x) = sum_{j=k}^{N} C(N, j) (1 - e^-x)^j e^(-x (N - j)), and F_G(m) = P(log mu_e + log mu_l <= 2 log m)
by the convolution of the two log estimates' laws on a fine grid; alpha is the root of P(alpha) = pfa
(:meth:`CwEstimate.threshold`, checked against Monte Carlo in tests/detection/test_cw_cells.py).

With r set, F_G is the law of (1 + r) X_1 - r X_2 (X = log mu) by the same grid, and two laws' statistics are
mapped to each other by equal tails, s -> Q_2^-1(Q_1(s)), Q(a) = P(s > a) (:func:`equal_tail_map`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require
from sonartrack.detection.cfar import os_mean_factor


def os_cdf(m, n: int, k: int) -> np.ndarray:
    """CDF of the OS estimate x_(k) / c_k of n unit exponentials at m (module doc).

    Parameters
    ----------
    m : array
        Values (>= 0).
    n, k : int
        Reference cells and rank.

    Returns
    -------
    numpy.ndarray
        P(x_(k) / c_k <= m).
    """
    from scipy.stats import binom

    p = -np.expm1(-os_mean_factor(n, k) * np.asarray(m, float))
    return binom.sf(k - 1, n, p)


def os_draws(rng: np.random.Generator, n: int, k: int, shape) -> np.ndarray:
    """Draws of x_(k) / c_k, x_(k) the k-th smallest of n unit exponentials, by x_(k) = -log(1 - U_(k)),
    U_(k) ~ Beta(k, n - k + 1), float32 of ``shape``."""
    return (-np.log1p(-rng.beta(k, n - k + 1, shape)) / os_mean_factor(n, k)).astype(np.float32)


@functools.lru_cache(maxsize=16)
def _geometric_cdf_table(n: int, k: int) -> tuple[np.ndarray, np.ndarray]:
    """(log m grid, P(sqrt(mu_e mu_l) <= m)) for two independent OS estimates (n, k): the law of log mu on a
    uniform grid of cell masses, convolved with itself (module doc)."""
    from scipy.signal import fftconvolve

    u = np.linspace(np.log(1e-7), np.log(1e3), 16_001)
    mass = np.diff(os_cdf(np.exp(u), n, k))
    total = np.clip(np.cumsum(fftconvolve(mass, mass)), 0.0, 1.0)  # P(i + j <= s), cell centres u_0 + (i + 1/2) h
    h = u[1] - u[0]
    log_m = (2.0 * u[0] + (np.arange(total.size) + 1.0) * h) / 2.0
    return log_m, total


@functools.lru_cache(maxsize=16)
def _trend_cdf_table(n: int, k: int, trend: float) -> tuple[np.ndarray, np.ndarray]:
    """(log m grid, P(mu_1^(1 + r) / mu_2^r <= m)) for two independent OS estimates (n, k), r = ``trend``:
    P((1 + r) X_1 - r X_2 <= z) = sum_j P(X_2 in cell j) F_X1((z + r x_j) / (1 + r)), X = log mu (module doc)."""
    u = np.linspace(np.log(1e-7), np.log(1e3), 4_001)
    cdf = os_cdf(np.exp(u), n, k)
    mass, centre = np.diff(cdf), 0.5 * (u[1:] + u[:-1])
    z = np.linspace((1.0 + trend) * u[0] - trend * u[-1], (1.0 + trend) * u[-1] - trend * u[0], 4_001)
    f1 = np.interp((z[:, None] + trend * centre[None, :]) / (1.0 + trend), u, cdf, left=0.0, right=1.0)
    return z, np.clip(f1 @ mass, 0.0, 1.0)


@dataclass(frozen=True, slots=True)
class CwEstimate:
    """The law of a CW cell's noise estimate M = max(mu_f, sqrt(mu_e mu_l)) in homogeneous exponential noise
    (module doc): ``doppler`` the (N, k) of mu_f, ``delay`` the (N, k) of each of mu_e, mu_l (None: M = mu_f);
    ``trend`` r set: the early delays' M = max(mu_f, mu_1^(1 + r) / mu_2^r), mu_1 and mu_2 the next two later
    windows (r = 0: mu_1 alone)."""

    doppler: tuple[int, int]
    delay: tuple[int, int] | None
    trend: float | None = None

    def cdf(self, m) -> np.ndarray:
        """F_M(m) = F_f(m) F_G(m) (with ``trend`` r: F_G the law of mu_1^(1 + r) / mu_2^r instead).

        Parameters
        ----------
        m : array
            Values (>= 0).

        Returns
        -------
        numpy.ndarray
            P(M <= m).
        """
        m = np.asarray(m, float)
        f = os_cdf(m, *self.doppler)
        if self.delay is None:
            return f
        if self.trend is not None:
            log_m, table = _trend_cdf_table(*self.delay, self.trend)
            return f * np.interp(np.log(np.maximum(m, 1e-300)), log_m, table, left=0.0, right=1.0)
        log_m, table = _geometric_cdf_table(*self.delay)
        return f * np.interp(np.log(np.maximum(m, 1e-300)), log_m, table, left=0.0, right=1.0)

    def pfa(self, alpha: float) -> float:
        """P(y / M > alpha) = alpha int exp(-alpha m) F_M(m) dm (trapezoid on a grid fine against 1 / alpha).

        Parameters
        ----------
        alpha : float
            Threshold on s.

        Returns
        -------
        float
            False-alarm probability per cell.
        """
        m = np.linspace(0.0, 40.0 / max(alpha, 1e-3) + 8.0, 20_001)
        return float(alpha * np.trapezoid(np.exp(-alpha * m) * self.cdf(m), m))

    @functools.cache  # noqa: B019 -- a frozen, hashable value: the cache holds a few thresholds
    def threshold(self, pfa: float) -> float:
        """alpha with :meth:`pfa` (alpha) = pfa (bisection on log alpha).

        Parameters
        ----------
        pfa : float
            False-alarm probability per cell, in (0, 1).

        Returns
        -------
        float
            The threshold on s.
        """
        require(0.0 < pfa < 1.0, f"the false-alarm rate must be in (0, 1), got {pfa}")
        lo, hi = np.log(1e-3), np.log(1e6)
        for _ in range(48):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if self.pfa(float(np.exp(mid))) > pfa else (lo, mid)
        return float(np.exp(0.5 * (lo + hi)))

    @functools.cache  # noqa: B019 -- a frozen, hashable value: one table per law
    def survival_table(self) -> tuple[np.ndarray, np.ndarray]:
        """(-log P(s > a), a) of the normalised noise cell s = y / M on a grid of a from 0 to where P < 1e-16:
        P(s > a) = E[exp(-a M)] = sum_i exp(-a m_i) (F_M(m_i+1) - F_M(m_i)) on a log grid of m fine against the
        scale 1 / a (cell ratio 1 + 3e-3), all a at once (the integral of :meth:`pfa`, by Stieltjes sums).

        Returns
        -------
        tuple of numpy.ndarray
            (-log P(s > a) increasing from 0, a (>= 0)), up to 601 points.
        """
        edges = np.geomspace(1e-8, 1e3, 8_001)
        mass = np.diff(self.cdf(edges))
        m = np.sqrt(edges[1:] * edges[:-1])
        a = np.concatenate([[0.0], np.geomspace(1e-3, 1e3, 600)])
        q = np.exp(-np.outer(a, m)) @ mass
        keep = q > 1e-16
        return -np.log(q[keep] / q[0]), a[keep]

    def draw_statistic(self, rng: np.random.Generator, shape, pool: int = 1) -> np.ndarray:
        """Draws of the max of ``pool`` independent normalised noise cells s = y / M (y a unit exponential, M this
        law), by inverting P(max <= a) = (1 - P(s > a))^pool on :meth:`survival_table`: one uniform per draw, the
        law of ``max(y / draw(...))`` exactly (up to the table's interpolation).

        Parameters
        ----------
        rng : numpy.random.Generator
            Source of the draws.
        shape : tuple of int
            Shape of the draws.
        pool : int
            Independent cells whose max is one draw (>= 1).

        Returns
        -------
        numpy.ndarray
            float64 draws of ``shape``.
        """
        x, a = self.survival_table()
        v = rng.random(shape)
        with np.errstate(divide="ignore"):
            tail = -np.log(-np.expm1(np.log(v) / pool))  # -log P(s > a) of the draw: P(max <= a) = v
        return np.interp(tail, x, a)

    def draw(self, rng: np.random.Generator, shape) -> np.ndarray:
        """Independent draws of M (:func:`os_draws`), float32 of ``shape``.

        Parameters
        ----------
        rng : numpy.random.Generator
            Source of the draws.
        shape : tuple of int
            Shape of the draws.

        Returns
        -------
        numpy.ndarray
            M.
        """
        m = os_draws(rng, *self.doppler, shape)
        if self.delay is not None and self.trend is not None:
            near, far = os_draws(rng, *self.delay, shape), os_draws(rng, *self.delay, shape)
            return np.maximum(m, near ** (1.0 + self.trend) / far**self.trend)
        if self.delay is not None:
            m = np.maximum(m, np.sqrt(os_draws(rng, *self.delay, shape) * os_draws(rng, *self.delay, shape)))
        return m


def equal_tail_map(stat: np.ndarray, source: CwEstimate, target: CwEstimate) -> np.ndarray:
    """The statistic of ``source``'s law mapped to ``target``'s at the same tail probability,
    a -> Q_target^-1(Q_source(a)), Q(a) = P(s > a) (:meth:`CwEstimate.survival_table`): in homogeneous noise the
    mapped cells have ``target``'s law, so its thresholds and the MFTD's calibration hold for them (module doc).
    Beyond the tables' ends (P < 1e-16) the map goes on in proportion.

    Parameters
    ----------
    stat : ndarray
        Normalised cells s = y / M, M of ``source``'s law.
    source, target : CwEstimate
        The laws.

    Returns
    -------
    ndarray
        float32, the shape of ``stat``.
    """
    x_s, a_s = source.survival_table()
    x_t, a_t = target.survival_table()
    v = np.asarray(stat, np.float64)
    out = np.interp(np.interp(v, a_s, x_s), x_t, a_t)
    far = v > a_s[-1]
    out[far] = a_t[-1] * v[far] / a_s[-1]
    return out.astype(np.float32)

"""Constant false-alarm rate normalisers along range: cell averaging (CA) and order statistic (OS).

For each cell under test y (a square-law cell, exponential under noise), the reference window holds
``reference_cells`` cells on each side of it, beyond ``guard_cells`` on each side (which keep the target's
own spread out of the estimate): N = 2 reference_cells values x_1..x_N. The noise mean is estimated by

    CA:  mu = (1/N) sum_i x_i
    OS:  mu = x_(k) / c_k,   x_(k) the k-th smallest,  c_k = E[x_(k)] for unit-mean exponentials
         = sum_{i=N-k+1}^{N} 1/i       (so both estimates are unbiased in homogeneous noise)

and the normalised statistic is s = y / mu (in homogeneous exponential noise exponential with mean 1 given
mu; its mean over mu is E[1 / mu] > 1 by Jensen: N / (N - 1) for CA, 1.05 for OS with N = 32, k = 24). A detection is
s >= alpha, with alpha set in closed form for a false-alarm probability Pfa in homogeneous exponential
noise (Gandhi and Kassam, IEEE Trans. AES 24(4), 1988; Rohling, IEEE Trans. AES 19(4), 1983):

    CA:  Pfa = (1 + alpha / N)^(-N)               ->  alpha = N (Pfa^(-1/N) - 1)
    OS:  Pfa = prod_{i=0}^{k-1} (N - i) / (N - i + T),   T = alpha / c_k   (the multiplier of x_(k); Rohling)

The OS estimate ignores up to N - k strong cells in the window (other targets, reverberation spikes), where
CA's mean rises and masks the target (tests/detection/test_cfar.py: a 20 dB target with three as strong
interferers keeps Pd 0.88 with OS, drops to 0.38 with CA). At a step in the background (a clutter edge) both
over-alarm on the loud side for a window's length (measured, 10 dB step, Pfa 1e-3: ~20x for CA, ~35x for
OS in the first cells: the k-th value of a half-quiet window is the loud half's median) and mask on the quiet
side. At the ends of the range axis the window is reflected into the axis (so every cell has N references).
"""

from __future__ import annotations

from functools import cache
from typing import Literal

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting


class CfarSettings(Settings):
    """The CFAR normaliser along range (module doc)."""

    method: Literal["os", "ca"] = setting("os", "normaliser: os = order statistic (holds at reverberation "
                                                "edges), ca = cell averaging", unit="")
    guard_cells: int = setting(4, "guard cells on each side of the cell under test (the target's own spread)",
                               unit="1", ge=0)
    reference_cells: int = setting(16, "reference cells on each side (N = twice this)", unit="1", ge=1)
    os_rank: float = setting(0.75, "order statistic: rank k as a fraction of N (k = round(os_rank N), Rohling's "
                                   "3/4)", unit="1", gt=0, le=1)

    @property
    def n_reference(self) -> int:
        """N = 2 reference_cells."""
        return 2 * self.reference_cells

    @property
    def rank(self) -> int:
        """k of the order statistic (1 .. N)."""
        return int(min(max(round(self.os_rank * self.n_reference), 1), self.n_reference))


def os_mean_factor(n: int, k: int) -> float:
    """c_k = E[x_(k)] of ``n`` = N unit-mean exponentials, ``k`` the rank (1 = smallest): sum_{i=N-k+1}^{N} 1/i."""
    return float(np.sum(1.0 / np.arange(n - k + 1, n + 1)))


def ca_pfa(alpha, n: int):
    """Pfa of CA-CFAR with threshold ``alpha`` on s = y / mean: (1 + alpha / N)^(-N) (module doc).

    Parameters
    ----------
    alpha, n
        Threshold on the normalised statistic s (dimensionless, float or array_like) and the number N of reference
        cells.

    Returns
    -------
    float or ndarray
        False-alarm probability per cell in homogeneous exponential noise.
    """
    return (1.0 + np.asarray(alpha, dtype=float) / n) ** (-n)


def ca_threshold(pfa: float, n: int) -> float:
    """alpha = N (Pfa^(-1/N) - 1) on s = y / mean (module doc).

    Parameters
    ----------
    pfa, n
        The false-alarm probability per cell, in (0, 1), and the number N of reference cells.

    Returns
    -------
    float
        Threshold on the normalised statistic s.
    """
    require(0 < pfa < 1, f"the false-alarm probability must be in (0, 1), got {pfa:g}")
    return float(n * (pfa ** (-1.0 / n) - 1.0))


def os_pfa(alpha, n: int, k: int):
    """Pfa of OS-CFAR with threshold ``alpha`` on s = y / (x_(k) / c_k) (Rohling 1983; module doc).

    Parameters
    ----------
    alpha : float or array_like
        Threshold on the normalised statistic s.
    n, k : int
        Number N of reference cells and the rank k of the order statistic (1 = smallest).

    Returns
    -------
    float or ndarray
        prod_{i=0}^{k-1} (N - i) / (N - i + alpha / c_k).
    """
    t = np.asarray(alpha, dtype=float)[..., None] / os_mean_factor(n, k)
    i = np.arange(k)
    return np.prod((n - i) / (n - i + t), axis=-1)


def os_threshold(pfa: float, n: int, k: int) -> float:
    """alpha with :func:`os_pfa` = ``pfa`` (bisection: Pfa falls monotonically in alpha).

    Parameters
    ----------
    pfa, n, k
        As :func:`ca_threshold`, and the rank k of the order statistic.

    Returns
    -------
    float
        Threshold on the normalised statistic s.
    """
    require(0 < pfa < 1, f"the false-alarm probability must be in (0, 1), got {pfa:g}")
    require(1 <= k <= n, f"the OS rank must be in 1..{n}, got {k}")
    lo, hi = 0.0, 1.0
    while os_pfa(hi, n, k) > pfa:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if os_pfa(mid, n, k) > pfa else (lo, mid)
    return float(0.5 * (lo + hi))


def cfar_threshold(pfa: float, settings: CfarSettings) -> float:
    """The threshold on the normalised statistic s for false-alarm probability ``pfa`` (module doc).

    Parameters
    ----------
    pfa : float
        False-alarm probability per cell, in (0, 1).
    settings : CfarSettings
        The normaliser (method, N, rank).

    Returns
    -------
    float
        :func:`ca_threshold` or :func:`os_threshold`.
    """
    n = settings.n_reference
    return ca_threshold(pfa, n) if settings.method == "ca" else os_threshold(pfa, n, settings.rank)


def _reference_windows(y: np.ndarray, settings: CfarSettings) -> np.ndarray:
    """The N reference cells of every cell along the last axis: (..., M, N) (reflected at the ends)."""
    g, r = settings.guard_cells, settings.reference_cells
    half = g + r
    require(y.shape[-1] > half, f"the range axis ({y.shape[-1]} cells) is shorter than the CFAR's half window "
                                f"({half} cells): lower guard_cells or reference_cells")
    pad = [(0, 0)] * (y.ndim - 1) + [(half, half)]
    w = np.lib.stride_tricks.sliding_window_view(np.pad(y, pad, mode="reflect"), 2 * half + 1, axis=-1)
    return np.concatenate([w[..., :r], w[..., r + 2 * g + 1:]], axis=-1)


def noise_estimate(power: np.ndarray, settings: CfarSettings, stride: int = 1) -> np.ndarray:
    """The noise mean mu of every cell along the last axis (range), CA or OS (module doc).

    ``stride`` > 1 takes the reference cells ``stride`` apart (cells of the same residue modulo ``stride``, the
    guard rounded up to whole strides): for oversampled cells (an LFM's output sampled at 2 B, a CW's delays a
    quarter pulse apart) the references are then about independent, as the closed-form thresholds assume.

    Parameters
    ----------
    power : ndarray (..., M)
        Square-law cell values, range along the last axis.
    settings : CfarSettings
        Method, guard and reference cells, OS rank.
    stride : int
        Cells between reference cells.

    Returns
    -------
    ndarray (..., M), float32
        The estimated noise mean mu of each cell (same units as ``power``).
    """
    y = np.asarray(power, dtype=np.float32)
    if stride > 1:
        sub = settings.model_copy(update={"guard_cells": -(-settings.guard_cells // stride)})
        mu = np.empty_like(y)
        for c in range(stride):
            mu[..., c::stride] = noise_estimate(y[..., c::stride], sub)
        return mu
    n, g, r = settings.n_reference, settings.guard_cells, settings.reference_cells
    if settings.method == "ca":
        half = g + r
        pad = [(0, 0)] * (y.ndim - 1) + [(half, half)]
        c = np.cumsum(np.pad(y, pad, mode="reflect"), axis=-1, dtype=np.float64)
        c = np.concatenate([np.zeros(c.shape[:-1] + (1,)), c], axis=-1)
        j = np.arange(y.shape[-1])
        total = (c[..., j + 2 * half + 1] - c[..., j]) - (c[..., j + r + 2 * g + 1] - c[..., j + r])
        return (total / n).astype(np.float32)
    require(y.shape[-1] > g + r, f"the range axis ({y.shape[-1]} cells) is shorter than the CFAR's half window "
                                 f"({g + r} cells): lower guard_cells or reference_cells")
    k = settings.rank
    pad = [(0, 0)] * (y.ndim - 1) + [(g + r, g + r)]
    rows = np.ascontiguousarray(np.pad(y, pad, mode="reflect").reshape(-1, y.shape[-1] + 2 * (g + r)))
    out = _os_kernel()(rows, g, r, k).reshape(y.shape)
    return (out / os_mean_factor(n, k)).astype(np.float32)


def os_statistic_reference(power: np.ndarray, settings: CfarSettings) -> np.ndarray:
    """x_(k) of every cell's reference window by NumPy (np.partition): the compiled kernel's reference.

    Parameters
    ----------
    power : ndarray
        Cell powers (float32 here), range along the last axis.
    settings : CfarSettings
        Guard and reference cells (N = 2 reference_cells, reflected at the ends) and the rank k.

    Returns
    -------
    ndarray
        The k-th smallest power of each cell's reference window, shape of ``power``.
    """
    y = np.asarray(power, dtype=np.float32)
    k = settings.rank
    return np.partition(_reference_windows(y, settings), k - 1, axis=-1)[..., k - 1]


@cache
def _os_kernel():
    """x_(k) of each cell's reference window along rows of a reflected-padded array (numba; built on first use).

    The N reference values are kept sorted while the window slides one cell: the left part loses one value and
    gains one, the right part likewise; each change replaces the old value by the new one and moves it to its
    place (at most N steps)."""
    import numba as nb

    @nb.njit(cache=True, nogil=True)
    def kernel(rows, g, r, k):
        n_rows, width = rows.shape
        m = width - 2 * (g + r)
        out = np.empty((n_rows, m), dtype=np.float32)
        buf = np.empty(2 * r, dtype=rows.dtype)
        for row in range(n_rows):
            x = rows[row]
            buf[:r] = x[:r]
            buf[r:] = x[r + 2 * g + 1: 2 * (g + r) + 1]
            buf.sort()
            out[row, 0] = buf[k - 1]
            for j in range(1, m):
                for side in range(2):  # the left window, then the right one: replace `old` by `new`, re-sort
                    old = x[j - 1] if side == 0 else x[j + r + 2 * g]
                    new = x[j + r - 1] if side == 0 else x[j + 2 * (g + r)]
                    i = 0
                    while i < 2 * r - 1 and buf[i] != old:  # bounded: a NaN never compares equal
                        i += 1
                    while i > 0 and buf[i - 1] > new:
                        buf[i] = buf[i - 1]
                        i -= 1
                    while i < 2 * r - 1 and buf[i + 1] < new:
                        buf[i] = buf[i + 1]
                        i += 1
                    buf[i] = new
                out[row, j] = buf[k - 1]
        return out

    return kernel


def cfar_normalise(power: np.ndarray, settings: CfarSettings, stride: int = 1) -> np.ndarray:
    """s = y / mu along the last axis (range), float32 (module doc).

    Parameters
    ----------
    power : ndarray (..., M)
        Square-law cell values y >= 0, range along the last axis.
    settings : CfarSettings
        Method, guard and reference cells, OS rank.
    stride : int
        Reference cells this far apart (:func:`noise_estimate`).

    Returns
    -------
    ndarray (..., M), float32
        The normalised statistic (mean ~1 in homogeneous exponential noise; module doc); 0 where mu is 0.
    """
    y = np.asarray(power, dtype=np.float32)
    mu = noise_estimate(y, settings, stride)
    return np.divide(y, mu, out=np.zeros_like(y), where=mu > 0)


#: ln x grid of the K laws' tabulation and the Gauss-Laguerre order of their texture integral
_LOG_X = np.linspace(np.log(1e-9), np.log(1e7), 3000)
_TEXTURE_NODES = 160


@cache
def _k_law(nu: float) -> tuple[np.ndarray, np.ndarray]:
    """(pdf, survival) of a unit-mean K intensity of shape nu on the grid exp(_LOG_X), as the texture integral

        S(x) = E_g[exp(-x / g)],   f(x) = E_g[exp(-x / g) / g],   g ~ Gamma(nu, 1 / nu)

    by generalised Gauss-Laguerre quadrature (exact for the gamma weight u^(nu-1) e^(-u), u = nu g): stable for every
    nu, where the Bessel form overflows for large nu."""
    g, wq = _texture_nodes(nu)
    x = np.exp(_LOG_X)[:, None]
    e = np.exp(-x / g[None, :]) * wq[None, :]
    return (e / g[None, :]).sum(axis=1), np.clip(e.sum(axis=1), 0.0, 1.0)


@cache
def _texture_nodes(nu: float) -> tuple[np.ndarray, np.ndarray]:
    """(g, weights): generalised Gauss-Laguerre nodes of E_g[h(g)], g ~ Gamma(nu, 1 / nu) (:func:`_k_law`)."""
    from scipy.special import gammaln, roots_genlaguerre

    u, wq = roots_genlaguerre(_TEXTURE_NODES, nu - 1.0)
    return u / nu, wq / np.exp(gammaln(nu))  # the gamma density's normalisation


def _kth_reference_law(nu: float, n: int, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, w, sf): the grid exp(_LOG_X), the density of the k-th of N K references in ln x (order statistics:
    N! / ((k-1)! (N-k)!) F^(k-1) (1-F)^(N-k) f, times x) and the K survival function on the grid."""
    from scipy.special import gammaln

    pdf, sf = _k_law(nu)
    x = np.exp(_LOG_X)
    with np.errstate(divide="ignore"):
        log_fk = (gammaln(n + 1) - gammaln(k) - gammaln(n - k + 1) + (k - 1) * np.log1p(-sf) + (n - k) * np.log(sf)
                  + np.log(pdf))
    return x, np.exp(log_fk) * x, sf


def k_os_pfa(alpha, nu: float, n: int, k: int):
    """Pfa of OS-CFAR (s = y / (x_(k) / c_k) >= alpha) when the cell y and its N references are independent
    K-distributed intensities of shape nu (a gamma(nu) texture times an exponential speckle, independent cell to cell).

    The K intensity of unit mean has (Jakeman & Pusey 1976; Ward, Tough & Watts, Sea Clutter, eq. 4.11; Watts 1987)

        f(x) = 2 nu^((nu+1)/2) x^((nu-1)/2) K_(nu-1)(2 sqrt(nu x)) / Gamma(nu),
        S(x) = P(y > x) = 2 (nu x)^(nu/2) K_nu(2 sqrt(nu x)) / Gamma(nu)

    (computed as their texture integrals, :func:`_k_law`), and the k-th of N ordered references has the density
    N! / ((k-1)! (N-k)!) F^(k-1) S^(N-k) f (David, Order Statistics, eq. 2.1.6), so

        Pfa(alpha) = integral_0^inf S(alpha x / c_k) f_(k)(x) dx

    (Gandhi & Kassam 1988 give the same integral for OS-CFAR in non-Gaussian clutter), by the trapezoid rule in ln x.
    nu -> infinity gives Rohling's closed form :func:`os_pfa`; the scale of the clutter cancels.

    Parameters
    ----------
    alpha : float or array_like
        Threshold(s) on the normalised statistic s.
    nu : float
        K shape (> 0; small: spiky).
    n, k : int
        Reference cells N and the OS rank k.

    Returns
    -------
    float or numpy.ndarray
        Pfa per cell at each alpha.
    """
    x, w, sf = _kth_reference_law(float(nu), n, k)
    a = np.atleast_1d(np.asarray(alpha, float))
    log_t = np.log(np.maximum(a[:, None] * x[None, :] / os_mean_factor(n, k), 1e-300))
    s = np.exp(np.interp(log_t, _LOG_X, np.log(np.maximum(sf, 1e-300))))
    out = np.trapezoid(s * w[None, :], _LOG_X, axis=1) / np.trapezoid(w, _LOG_X)
    return out if np.ndim(alpha) else float(out[0])


def k_os_pd(alpha, ebr: float, nu: float, n: int, k: int):
    """Pd of OS-CFAR (s = y / (x_(k) / c_k) >= alpha) for a Swerling-1 echo of mean ``ebr`` times the clutter's mean
    in K clutter of shape nu (references as :func:`k_os_pfa`): the test cell is the echo's exponential intensity added
    to a K cell, given its texture g exponential of mean g + ebr, so its survival is E_g[exp(-x / (g + ebr))] and

        Pd(alpha) = integral_0^inf E_g[exp(-alpha x / (c_k (g + ebr)))] f_(k)(x) dx

    (the integral of :func:`k_os_pfa` with the target-plus-clutter law of the test cell: Ward, Tough & Watts, Sea
    Clutter, sec. 10.3, a Swerling-1 target in K clutter; Gandhi & Kassam 1988 for the OS reference). ebr = 0 gives
    :func:`k_os_pfa`; nu -> infinity Rohling's Swerling-1 closed form os_pfa(alpha / (1 + ebr)). The yardstick of a
    detector in K clutter: at the same Pfa it needs more EBR than in exponential noise.

    Parameters
    ----------
    alpha : float or array_like
        Threshold(s) on s (the K clutter's own: :func:`k_os_log_pfa` inverted at the wanted Pfa).
    ebr : float
        Mean echo intensity over the clutter's mean (linear, >= 0).
    nu : float
        K shape (> 0; above the tabulation's 100, and inf, the exponential closed form).
    n, k : int
        Reference cells N and the OS rank k.

    Returns
    -------
    float or numpy.ndarray
        Pd per cell at each alpha.
    """
    a = np.atleast_1d(np.asarray(alpha, float))
    if not float(nu) <= K_SHAPES[-1]:  # the texture integral's quadrature overflows: the exponential closed form
        out = os_pfa(a / (1.0 + float(ebr)), n, k)
        return out if np.ndim(alpha) else float(out[0])
    x, w, _ = _kth_reference_law(float(nu), n, k)
    g, wq = _texture_nodes(float(nu))
    t = a[:, None] * x[None, :] / os_mean_factor(n, k)  # the test cell's threshold given x_(k), (A, X)
    s = np.stack([np.exp(-tt[:, None] / (g[None, :] + float(ebr))) @ wq for tt in t])
    out = np.trapezoid(s * w[None, :], _LOG_X, axis=1) / np.trapezoid(w, _LOG_X)
    return out if np.ndim(alpha) else float(out[0])


#: K shapes of the tabulated thresholds; above the last the exponential closed form
K_SHAPES = tuple(float(v) for v in np.exp(np.linspace(np.log(0.1), np.log(100.0), 31)))


@cache
def _k_table(n: int, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """log Pfa of OS-CFAR in K clutter on a grid: (shapes nu (S,), thresholds alpha (A,), log Pfa (S, A))."""
    nus = np.asarray(K_SHAPES)
    alphas = np.exp(np.linspace(np.log(0.5), np.log(1e5), 300))
    return nus, alphas, np.log(np.maximum(np.stack([k_os_pfa(alphas, v, n, k) for v in nus]), 1e-300))


def k_os_log_pfa(alpha, nu: float, n: int, k: int) -> np.ndarray:
    """ln Pfa of OS-CFAR in K clutter of shape nu at thresholds alpha, interpolated on the tabulation of
    :func:`k_os_pfa` (linear in ln nu and ln alpha; above nu = 100 the exponential closed form).

    Parameters
    ----------
    alpha : array_like
        Thresholds on s (> 0).
    nu : float
        K shape.
    n, k : int
        Reference cells N and the OS rank k.

    Returns
    -------
    numpy.ndarray
        ln Pfa at each alpha.
    """
    a = np.asarray(alpha, float)
    if nu >= K_SHAPES[-1]:
        return np.log(np.maximum(os_pfa(a, n, k), 1e-300))
    nus, alphas, log_p = _k_table(n, k)
    j = np.interp(np.log(max(nu, nus[0])), np.log(nus), np.arange(len(nus)))
    lo = int(min(np.floor(j), len(nus) - 2))
    row = (1 - (j - lo)) * log_p[lo] + (j - lo) * log_p[lo + 1]
    return np.interp(np.log(np.maximum(a, 1e-300)), np.log(alphas), row)


def k_os_threshold(pfa: float, nu: float, n: int, k: int) -> float:
    """alpha with :func:`k_os_pfa` = ``pfa`` (on the tabulation, :func:`k_os_log_pfa`).

    Parameters
    ----------
    pfa, nu, n, k
        The false-alarm probability per cell, in (0, 1), and the clutter and normaliser as :func:`k_os_log_pfa`.

    Returns
    -------
    float
        Threshold on the normalised statistic s.
    """
    require(0 < pfa < 1, f"the false-alarm probability must be in (0, 1), got {pfa:g}")
    if nu >= K_SHAPES[-1]:
        return os_threshold(pfa, n, k)
    _, alphas, _ = _k_table(n, k)
    row = k_os_log_pfa(alphas, nu, n, k)
    return float(np.exp(np.interp(-np.log(pfa), -row, np.log(alphas))))

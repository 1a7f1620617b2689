"""A CW ping's cells: the Doppler bank normalised across Doppler and delay, the reverberation ridge notched.

Why not the delay CFAR of detection/cells.py. A CW of length tau resolves 1 / tau in Doppler and tau in delay:
a 30 s window of a 1 s pulse holds ~28 independent delays, against ~3000 for a 100 Hz LFM. The delay CFAR (16
reference cells a side, one pulse apart) then spans +-20 s, more than half the window, over reverberation
that falls ~30 dB from 1.5 s to 30 s (two-way spreading over a growing scattering area): measured on the
default scene with a CW (seed 9101, ping 6) the normalised statistic had mean 5.7 (1 in noise) and 263 in the
first searched delay, so 217 of 335 single-ping detections and every MFTD detection sat there.

Background of a CW cell (beam b, delay d, Doppler f): ambient noise, flat in Doppler; reverberation, falling
with delay and concentrated on the ridge, the Doppler of the stationary sea seen in the beam (below); the
ridge's leakage through the beam's and the filter's sidelobes, spread over the platform's Doppler band. The
noise mean mu is estimated twice, by order statistics (detection/cfar.py's OS, rank 3/4):

    mu_f   across Doppler at the cell's beam and delay: ``doppler_reference`` resolution cells each side beyond
           ``doppler_guard`` (the filters one resolution 1 / tau apart, so the references are ~independent);
    mu_e, mu_l along delay at the cell's beam and Doppler: the ``delay_reference`` pulse lengths before the cell
           (beyond ``delay_guard``), and those after it, each its own OS estimate;

and mu = max(mu_f, mu_e, mu_l) (greatest-of, Hansen 1973, here over two axes and both sides of the delay): off
the ridge all see the noise; on the ridge mu_f sees the quieter Doppler cells beside it and would let the ridge
through, but mu_e and mu_l see the ridge's own level at the neighbouring delays; where the reverberation falls
steeply with delay (the first seconds after the blanking: 10 dB from 1.5 to 2.5 s on the default scene) the
later cells alone under-estimate the cell's level (two-sided, measured: median s 23 at the first searched
delay), the earlier ones do not. s = y / mu.

Threshold. In homogeneous exponential noise the three estimates use disjoint cells, so they are independent,
and for s = y / M with y exponential (mean 1):

    P(s > alpha) = E[exp(-alpha M)] = alpha int_0^inf exp(-alpha m) prod_i F_i(m) dm,   M = max(mu_f, mu_e, mu_l)

(integration by parts), F the CDF of an OS estimate x_(k) / c_k of N unit exponentials,
P(x_(k) <= x) = sum_{j=k}^{N} C(N, j) (1 - e^-x)^j e^(-x (N - j)); alpha is the root of P(alpha) = pfa
(:func:`go_threshold`, checked against Monte Carlo in tests/detection/test_cw_cells.py).

Ridge. A stationary scatterer in the direction u (unit vector) from the far field has bistatic range rate
rdot = -(u . v_T + u . v_R) (v_T, v_R the source's and receiver's velocities; far field: u_T = u_R = u).
A beam at cone theta from the array axis (heading phi) looks along both mirror directions phi +- theta, so
each beam has two ridge rates, equal when the platforms move along the axis. Cells whose range rate is within
``ridge_notch_mps`` of either are set to s = 0: a CW cannot tell an echo there from the sea's (targets that
hold the sea's Doppler are an LFM's), and persistent clutter points, which sit on the ridge, go with it.
"""

from __future__ import annotations

import functools

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting
from sonartrack.detection.cfar import CfarSettings, noise_estimate, os_mean_factor


class CwNormaliserSettings(Settings):
    """The CW front end's normaliser and ridge notch (module doc)."""

    doppler_guard: int = setting(1, "guard cells each side across Doppler, in Doppler resolution cells (1 / tau)",
                                 unit="1", ge=0, le=16)
    doppler_reference: int = setting(6, "reference cells each side across Doppler, in resolution cells", unit="1",
                                     ge=1, le=64)
    delay_guard: int = setting(1, "guard cells each side along delay, in pulse lengths", unit="1", ge=0, le=16)
    delay_reference: int | None = setting(4, "reference cells each side along delay, in pulse lengths (short: the "
                                             "reverberation falls with delay); not set: the Doppler estimate alone",
                                          unit="1", ge=1, le=64)
    os_rank: float = setting(0.75, "order statistic of both estimates: rank k as a fraction of N", unit="1", gt=0,
                             le=1)
    ridge_notch_mps: float | None = setting(
        1.0, "cells within this bistatic range rate of a beam's reverberation ridge (the stationary sea's Doppler "
             "in that beam, from the navigation) are not searched (not set: no notch)", unit="m/s", gt=0, le=50)

    def axis_cfar(self, guard: int, reference: int) -> CfarSettings:
        """One axis's OS-CFAR settings (detection/cfar.py) with this rank.

        Parameters
        ----------
        guard, reference : int
            Guard and reference cells each side (in independent cells).

        Returns
        -------
        CfarSettings
            Order statistic, these cells, ``os_rank``.
        """
        return CfarSettings(method="os", guard_cells=guard, reference_cells=reference, os_rank=self.os_rank)


def doppler_stride(duration_s: float, doppler_hz) -> int:
    """Doppler filters per resolution cell 1 / tau (>= 1).

    Parameters
    ----------
    duration_s : float
        Pulse length tau (s).
    doppler_hz : array (J,)
        The bank's filter frequencies (Hz), evenly spaced.

    Returns
    -------
    int
        round((1 / tau) / filter spacing).
    """
    f = np.asarray(doppler_hz, float)
    step = float(abs(f[1] - f[0])) if f.size > 1 else 1.0 / duration_s
    return max(int(round(1.0 / (duration_s * step))), 1)


def one_sided_os(y: np.ndarray, guard: int, reference: int, rank: int, stride: int) -> np.ndarray:
    """(2, ...) the OS estimates x_(k) / c_k of the ``reference`` cells before and of those after each cell along
    the last axis, beyond ``guard`` cells, the cells ``stride`` apart (the same residue modulo ``stride``); past the
    ends of the axis the end cell is repeated (the start of a ping's delays is the direct blast: the early
    estimate of the first cells then errs high, masking rather than alarming).

    Parameters
    ----------
    y : ndarray (..., M)
        Square-law cells.
    guard, reference, rank : int
        Guard and reference cells on each side (in strides) and the rank k (1..reference).
    stride : int
        Cells between references.

    Returns
    -------
    ndarray (2, ..., M), float32
        [early, late] estimates.
    """
    out = np.empty((2,) + y.shape, np.float32)
    half, c_k = guard + reference, os_mean_factor(reference, rank)
    for c in range(stride):
        z = np.pad(y[..., c::stride], [(0, 0)] * (y.ndim - 1) + [(half, half)], mode="edge")
        w = np.lib.stride_tricks.sliding_window_view(z, 2 * half + 1, axis=-1)
        for side, cells in enumerate((w[..., :reference], w[..., reference + 2 * guard + 1:])):
            out[side, ..., c::stride] = np.partition(cells, rank - 1, axis=-1)[..., rank - 1] / c_k
    return out


def cw_noise_estimate(power: np.ndarray, settings: CwNormaliserSettings, delay_stride: int,
                      doppler_step: int) -> np.ndarray:
    """mu = max(mu_f, mu_early, mu_late) of every cell of (beams, delays, Dopplers) power (module doc), float32.

    Parameters
    ----------
    power : ndarray (B, D, J)
        Square-law matched-filter output.
    settings : CwNormaliserSettings
        Guards, references, rank.
    delay_stride : int
        Delay cells per pulse length (the delay references are this far apart).
    doppler_step : int
        Doppler filters per resolution cell (:func:`doppler_stride`).

    Returns
    -------
    ndarray (B, D, J), float32
        The noise mean estimate (units of ``power``).
    """
    y = np.asarray(power, dtype=np.float32)
    s = settings
    n_dop = -(-y.shape[2] // doppler_step)
    require(n_dop > s.doppler_guard + s.doppler_reference,
            f"the CW Doppler bank holds {n_dop} resolution cells, fewer than the normaliser's half window "
            f"({s.doppler_guard + s.doppler_reference}): raise max_range_rate_mps or lower doppler_reference")
    mu_f = noise_estimate(y, s.axis_cfar(s.doppler_guard * doppler_step, s.doppler_reference), doppler_step)
    if s.delay_reference is None:
        return mu_f
    k_t = cw_ranks(s)[1][1]
    mu_t = one_sided_os(np.moveaxis(y, 1, -1), s.delay_guard, s.delay_reference, k_t, delay_stride).max(axis=0)
    return np.maximum(mu_f, np.moveaxis(mu_t, -1, 1))


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


def go_pfa(alpha: float, ranks: tuple[tuple[int, int], ...]) -> float:
    """P(y / max_i m_i > alpha) for y unit exponential and independent OS estimates m_i of (n_i, k_i) (module doc).

    Parameters
    ----------
    alpha : float
        Threshold on s.
    ranks : tuple of (n, k)
        Each estimate's reference cells and rank.

    Returns
    -------
    float
        alpha int exp(-alpha m) prod_i F_i(m) dm (trapezoid on a grid fine against 1 / alpha and the CDFs).
    """
    m = np.linspace(0.0, 40.0 / max(alpha, 1e-3) + 8.0, 20_001)
    f = np.exp(-alpha * m)
    for n, k in ranks:
        f = f * os_cdf(m, n, k)
    return float(alpha * np.trapezoid(f, m))


@functools.lru_cache(maxsize=32)
def go_threshold(pfa: float, ranks: tuple[tuple[int, int], ...]) -> float:
    """alpha with :func:`go_pfa` (alpha) = pfa (bisection on log alpha).

    Parameters
    ----------
    pfa : float
        False-alarm probability per cell, in (0, 1).
    ranks : tuple of (n, k)
        The estimates' reference cells and ranks.

    Returns
    -------
    float
        The threshold on s.
    """
    require(0.0 < pfa < 1.0, f"the false-alarm rate must be in (0, 1), got {pfa}")
    lo, hi = np.log(1e-3), np.log(1e6)
    for _ in range(48):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if go_pfa(float(np.exp(mid)), ranks) > pfa else (lo, mid)
    return float(np.exp(0.5 * (lo + hi)))


def cw_ranks(settings: CwNormaliserSettings) -> tuple[tuple[int, int], ...]:
    """(N, k) of the three estimates: across Doppler (both sides), along delay before and after the cell.

    Parameters
    ----------
    settings : CwNormaliserSettings
        References and rank.

    Returns
    -------
    tuple of (int, int)
        ((N_f, k_f), (N_t, k_t), (N_t, k_t)).
    """
    s = settings
    f = s.axis_cfar(s.doppler_guard, s.doppler_reference)
    if s.delay_reference is None:
        return ((f.n_reference, f.rank),)
    n_t = s.delay_reference
    k_t = int(min(max(round(s.os_rank * n_t), 1), n_t))
    return (f.n_reference, f.rank), (n_t, k_t), (n_t, k_t)


def cw_threshold(pfa: float, settings: CwNormaliserSettings) -> float:
    """Threshold on s for ``pfa`` per cell (module doc: the greatest-of three OS estimates).

    Parameters
    ----------
    pfa : float
        False-alarm probability per cell.
    settings : CwNormaliserSettings
        The normaliser.

    Returns
    -------
    float
        alpha.
    """
    return go_threshold(float(pfa), cw_ranks(settings))


def go_scales(rng: np.random.Generator, ranks: tuple[tuple[int, int], ...], shape) -> np.ndarray:
    """Independent draws of M = max_i x_(k_i) / c_(k_i), each x_(k) the k-th smallest of n unit exponentials:
    the greatest-of OS noise estimate of a CW cell (module doc), by x_(k) = -log(1 - U_(k)),
    U_(k) ~ Beta(k, n - k + 1).

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of the draws.
    ranks : tuple of (n, k)
        Each estimate's reference cells and rank.
    shape : tuple of int
        Shape of the draws.

    Returns
    -------
    numpy.ndarray
        M, float32, of ``shape``.
    """
    m = np.zeros(shape, np.float32)
    for n, k in ranks:
        m = np.maximum(m, -np.log1p(-rng.beta(k, n - k + 1, shape)) / os_mean_factor(n, k))
    return m


def ridge_range_rates(cone_deg, heading_rad: float, tx_velocity, rx_velocity) -> np.ndarray:
    """(B, 2) bistatic range rate (m/s) of the stationary sea in each beam's two mirror directions (module doc).

    Parameters
    ----------
    cone_deg : array (B,)
        Beam cone angles (deg from the array's forward axis).
    heading_rad : float
        Array axis heading (rad, clockwise from north).
    tx_velocity, rx_velocity : array (2,)
        Source and receiver velocities [east, north] (m/s).

    Returns
    -------
    numpy.ndarray
        rdot = -u . (v_T + v_R) for u along heading +- cone (starboard, port).
    """
    theta = np.deg2rad(np.asarray(cone_deg, float))
    v = np.asarray(tx_velocity, float) + np.asarray(rx_velocity, float)
    bearing = heading_rad + np.stack([theta, -theta], axis=-1)
    return -(np.sin(bearing) * v[0] + np.cos(bearing) * v[1])


def ridge_notch(range_rate_mps, ridge_mps: np.ndarray, half_width_mps: float) -> np.ndarray:
    """(B, J) True where a Doppler cell's range rate is within ``half_width_mps`` of either of its beam's ridges.

    Parameters
    ----------
    range_rate_mps : array (J,)
        The Doppler cells' bistatic range rates (m/s).
    ridge_mps : array (B, 2)
        Each beam's ridge range rates (:func:`ridge_range_rates`).
    half_width_mps : float
        Half-width of the notch (m/s).

    Returns
    -------
    numpy.ndarray
        (B, J) bool.
    """
    v = np.asarray(range_rate_mps, float)
    return (np.abs(v[None, :, None] - np.asarray(ridge_mps, float)[:, None, :]) <= half_width_mps).any(axis=-1)


def cw_ping_cells(samples: np.ndarray, fs_hz: float, waveform, array, front_end, settings: CwNormaliserSettings, *,
                  time_s: float = 0.0, ping: int = 0, ridge_mps: np.ndarray | None = None):
    """One CW ping's normalised cells (module doc): detection/cells.py's beams and Doppler bank, then this
    normaliser, the blanking, and the ridge notch when ``ridge_mps`` is given.

    Parameters
    ----------
    samples : ndarray (N, M)
        Complex baseband samples, sample 0 at the transmit time.
    fs_hz : float
        Sample rate (Hz).
    waveform : Waveform
        A CW pulse.
    array : LineArray
        Elements and spacing.
    front_end : FrontEndSettings
        Beams, sound speed, Doppler span, hop, blanking.
    settings : CwNormaliserSettings
        The normaliser and the notch width.
    time_s : float
        Transmit time (s).
    ping : int
        The ping's number.
    ridge_mps : array (B, 2), optional
        Each beam's ridge range rates (m/s; :func:`ridge_range_rates`); None: no notch.

    Returns
    -------
    PingCells
        As detection/cells.py's, the statistic s = y / max(mu_f, mu_e, mu_l), 0 in the notch.
    """
    from sonartrack.acoustics.active_beams import cone_grid_deg
    from sonartrack.acoustics.matched_filter import doppler_to_range_rate
    from sonartrack.detection.cells import PingCells, matched_cells

    require(waveform.kind == "cw", "the CW front end takes a CW pulse")
    power, delay, doppler = matched_cells(samples, fs_hz, waveform, array, front_end)
    step = float(delay[1] - delay[0]) if delay.size > 1 else waveform.duration_s
    mu = cw_noise_estimate(power, settings, max(int(round(waveform.duration_s / step)), 1),
                           doppler_stride(waveform.duration_s, doppler))
    stat = np.divide(power, mu, out=np.zeros_like(power), where=mu > 0)
    keep = delay >= front_end.blank_s
    require(bool(keep.any()), f"blank_s {front_end.blank_s:g} s leaves no delay of the {delay[-1]:.3g} s window: "
                              "lower it")
    rate = doppler_to_range_rate(doppler, waveform.carrier_hz, front_end.sound_speed_mps)
    stat = np.ascontiguousarray(stat[:, keep])
    if ridge_mps is not None and settings.ridge_notch_mps is not None:
        stat[np.broadcast_to(ridge_notch(rate, ridge_mps, settings.ridge_notch_mps)[:, None, :], stat.shape)] = 0.0
    return PingCells(int(ping), float(time_s), cone_grid_deg(front_end.beams), delay[keep], doppler, rate, stat, True,
                     np.ascontiguousarray(mu[:, keep]))

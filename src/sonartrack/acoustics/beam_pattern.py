"""Peak positions refined with the array's own broadband beam pattern, the other peaks' lobes taken out (RELAX).

Peak positions (CBF over one band, ``peak_interpolation = pattern``): the peaks of each window are refined jointly
with the array's own broadband beam pattern (:func:`pattern_sum`, :func:`resolve_peaks`), so that a louder ship's
lobes do not pull a weaker ship's peak: measured on the passive-chain study's 32 scenes, that pull was a slowly
varying bias of 0.13 deg rms (median target; up to 0.37 deg), correlated over tens of scans, which the TMA took for
information; and a ship hidden on a louder one's lobe gets its own peak (:func:`add_hidden_peaks`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from sonartrack.acoustics.beam_peaks import pick_beam_peaks
from sonartrack.acoustics.beam_powers import _band_bins
from sonartrack.acoustics.beamformer_settings import BeamformerSettings
from sonartrack.acoustics.line_array import Band, LineArray

#: sampling of the tabulated beam pattern in u = cos(theta): linear interpolation between samples errs by about
#: (step^2 / 8) |g''| < 1e-4 of the peak for main lobes down to 0.01 in u (64 elements x 2.5 m at 1 kHz: 0.009)
PATTERN_STEP_U = 1e-4
#: fractional-beam offsets of a source from a peak's beam at which the three-beam ratio is tabulated
PATTERN_DELTAS = np.linspace(-0.75, 0.75, 151)
#: passes of the joint refinement (each: amplitudes of all peaks, then each peak's vertex with the others' lobes
#: taken out); the positions move by < 1e-3 deg after the third on two ships 5 deg apart
PATTERN_ITERATIONS = 3


@dataclass(frozen=True, slots=True)
class BeamPattern:
    """The whitened CBF's response to one broadband plane wave, as a function of u - u_s (u = cos theta), and the
    three-beam ratio of a source near each beam (:func:`beam_pattern`).

    ``g`` the response at ``u_grid`` = 0, PATTERN_STEP_U, ... 2 (even in u - u_s; g(0) = 1); ``cone_deg`` the beams;
    ``ratio`` (B, D) the ratio q = (y_+ - y_-) / (2 y_0 - y_- - y_+) of the beams k - 1, k, k + 1 for a source at
    cone_deg[k] + delta step, delta = PATTERN_DELTAS; ``monotone`` (B,) whether q rises with delta at beam k (false
    at the grid's ends, whose mirrored neighbours are equal)."""

    u_grid: np.ndarray
    g: np.ndarray
    cone_deg: np.ndarray
    ratio: np.ndarray
    monotone: np.ndarray
    #: the main lobe's half-power half-width in u (g = 1/2 there)
    half_width_u: float

    def response(self, du: np.ndarray) -> np.ndarray:
        """g(u - u_s) at the offsets ``du`` in u (any shape; |du| <= 2), linear between the table's samples (the
        grid is uniform: the sample index by division, no search)."""
        x = np.minimum(np.abs(du) / PATTERN_STEP_U, self.g.size - 1.000001)
        i = x.astype(np.intp)
        w = x - i
        return self.g[i] * (1.0 - w) + self.g[i + 1] * w


def pattern_sum(du: np.ndarray, f0_hz: float, df_hz: float, n_bins: int, array: LineArray) -> np.ndarray:
    """The whitened CBF's broadband beam pattern g(du) of one plane wave, du = cos(theta) - cos(theta_s).

    Every bin of a whitened band weighs the same, so the power of the beam steered at theta is the sum over the
    bins f_k = f0 + k df (k < K) of the uniform line's array factor (Van Trees, Optimum Array Processing, sec. 2.4,
    eq. 2.97), written with the lags l of the module doc:

        g(du) = [N K + 2 sum_{l=1}^{N-1} (N - l) sum_k cos(2 pi f_k l d du / c)] / (N^2 K),

    and the sum over the bins in closed form, sum_k cos(a + k b) = sin(K b / 2) / sin(b / 2) cos(a + (K - 1) b / 2).
    Sources that are independent add their patterns in the expected power (their cross terms average out).

    Parameters
    ----------
    du : numpy.ndarray
        Offsets in u = cos(cone angle) (dimensionless), any shape.
    f0_hz, df_hz : float
        First bin and bin spacing of the band (Hz).
    n_bins : int
        Number of bins K (>= 1).
    array : LineArray
        Element count N, spacing d (m) and sound speed c (m/s).

    Returns
    -------
    numpy.ndarray
        g(du), same shape as ``du``; 1 at du = 0.
    """
    x = np.asarray(du, dtype=float)
    n, k = array.elements, int(n_bins)
    total = np.full(x.shape, float(n * k))
    scale = 2.0 * np.pi * array.spacing_m / array.sound_speed_mps * x
    for lag in range(1, n):
        a, half = scale * lag * f0_hz, 0.5 * scale * lag * df_hz
        sh = np.sin(half)
        flat = np.abs(sh) < 1e-9  # b/2 a multiple of pi: every bin in phase, the limit K cos(K b/2) / cos(b/2)
        kernel = np.where(flat, k * np.cos(k * half) / np.where(flat, np.cos(half), 1.0),
                          np.sin(k * half) / np.where(flat, 1.0, sh))
        total += 2.0 * (n - lag) * kernel * np.cos(a + (k - 1) * half)
    return total / (n * n * k)


def beam_pattern(array: LineArray, settings: BeamformerSettings, fs_hz: float, band: Band) -> BeamPattern | None:
    """The front end's beam pattern on ``array`` over ``band`` (:class:`BeamPattern`), cached per recording; None
    when the band holds no bin.

    Parameters
    ----------
    array : LineArray
        The line array.
    settings : BeamformerSettings
        Its ``window_s`` (the bins) and ``beams``.
    fs_hz : float
        Sample rate (Hz).
    band : Band
        The processing band (:func:`front_end_band`).

    Returns
    -------
    BeamPattern or None
        The tabulated pattern and three-beam ratios.
    """
    return _beam_pattern(array, int(round(settings.window_s * fs_hz)), float(fs_hz), band.as_tuple(),
                         int(settings.beams))


@lru_cache(maxsize=4)
def _beam_pattern(array: LineArray, n_samples: int, fs_hz: float, band: tuple[float, float],
                  beams: int) -> BeamPattern | None:
    _, f = _band_bins(n_samples, fs_hz, band)
    if f.size == 0:
        return None
    grid = np.arange(0.0, 2.0 + PATTERN_STEP_U, PATTERN_STEP_U)
    g = pattern_sum(grid, float(f[0]), fs_hz / n_samples, f.size, array)
    cone = np.linspace(0.0, 180.0, beams)
    step = cone[1] - cone[0]
    nb = np.clip(np.arange(beams)[:, None] + np.array([-1, 0, 1])[None], -1, beams)
    nb = np.where(nb < 0, 1, np.where(nb >= beams, beams - 2, nb))  # mirrored at 0 and 180 deg, as the peak search
    u_src = np.cos(np.deg2rad(cone[:, None] + PATTERN_DELTAS[None] * step))  # (B, D)
    y = np.interp(np.abs(np.cos(np.deg2rad(cone[nb]))[:, None, :] - u_src[..., None]), grid, g)  # (B, D, 3)
    den = 2.0 * y[..., 1] - y[..., 0] - y[..., 2]
    ratio = np.divide(y[..., 2] - y[..., 0], den, out=np.zeros_like(den), where=den > 0)
    monotone = np.all(np.diff(ratio, axis=1) > 0, axis=1) & np.all(den > 0, axis=1)
    half = float(grid[np.argmax(g < 0.5)])
    return BeamPattern(grid, g, cone, ratio, monotone, half)


def _vertices(residual: np.ndarray, angle_deg: np.ndarray, pattern: BeamPattern) -> np.ndarray:
    """Each peak's cone angle (deg) from its own slice of ``residual`` (K, B, J): the largest of the three beams
    around its current angle ``angle_deg`` (K, J), and the offset delta whose tabulated three-beam ratio equals the
    measured one (the parabola's q / 2 where the ratio is not monotone), within half a beam."""
    cone = pattern.cone_deg
    n_w, b, n_p = residual.shape
    step = cone[1] - cone[0]
    kk, jj = np.arange(n_w)[:, None], np.arange(n_p)[None, :]
    k0 = np.rint((angle_deg - cone[0]) / step).astype(np.intp)
    cand = np.minimum(np.maximum(k0[None] + np.array([-1, 0, 1])[:, None, None], 0), b - 1)  # (3, K, J)
    k = np.take_along_axis(cand, np.argmax(residual[kk[None], cand, jj[None]], axis=0)[None], axis=0)[0]
    padded = np.concatenate([residual[:, 1:2], residual, residual[:, -2:-1]], axis=1)  # mirrored at 0 and 180 deg
    y0, y1, y2 = padded[kk, k, jj], padded[kk, k + 1, jj], padded[kk, k + 2, jj]
    den = 2.0 * y1 - y0 - y2
    q = np.divide(y2 - y0, den, out=np.zeros_like(den), where=den > 0)
    # the tabulated ratio rises with delta: linear interpolation between the two entries around q
    table = pattern.ratio[k]  # (K, J, D)
    hi = np.minimum(np.maximum(np.sum(table < q[..., None], axis=-1), 1), table.shape[-1] - 1)
    r0 = np.take_along_axis(table, (hi - 1)[..., None], axis=-1)[..., 0]
    r1 = np.take_along_axis(table, hi[..., None], axis=-1)[..., 0]
    w = np.minimum(np.maximum((q - r0) / np.where(r1 > r0, r1 - r0, 1.0), 0.0), 1.0)
    exact = PATTERN_DELTAS[hi - 1] + w * (PATTERN_DELTAS[hi] - PATTERN_DELTAS[hi - 1])
    delta = np.minimum(np.maximum(np.where(pattern.monotone[k], exact, 0.5 * q), -0.5), 0.5)
    return np.minimum(np.maximum(cone[k] + delta * step, 0.0), 180.0)


def _amplitudes(z: np.ndarray, resp: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Least-squares amplitudes a_j >= 0 (clipped; 0 for padding) of the peaks' patterns ``resp`` (K, B, J) in z
    (K, B) with a constant per window: the normal equations of [1, resp] (a small ridge keeps two peaks on one lobe
    solvable; a padded peak's empty column gets a unit diagonal)."""
    n_w, b, n_p = resp.shape
    design = np.empty((n_w, b, n_p + 1))
    design[..., 0] = 1.0
    design[..., 1:] = resp
    design_t = design.transpose(0, 2, 1)
    gram = design_t @ design
    diag = np.arange(n_p + 1)
    gram[:, diag, diag] = gram[:, diag, diag] * (1.0 + 1e-9) + np.concatenate(
        [np.zeros((n_w, 1)), ~valid], axis=1)
    rhs = (design_t @ z[..., None])[..., 0]
    try:
        coef = np.linalg.solve(gram, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:  # two peaks with one pattern: the pseudo-inverse shares their amplitude
        coef = (np.linalg.pinv(gram) @ rhs[..., None])[..., 0]
    return np.where(valid, np.maximum(coef[:, 1:], 0.0), 0.0)


def _padded_angles(angles_deg: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """(angles (K, J) zero-padded, valid (K, J), counts) of one array of peak angles per window."""
    counts = [len(a) for a in angles_deg]
    n_p = max(counts, default=0)
    valid = np.arange(n_p)[None, :] < np.array(counts, dtype=int)[:, None]
    ang = np.zeros((len(counts), n_p))
    for i, a in enumerate(angles_deg):
        ang[i, :len(a)] = a
    return ang, valid, counts


def _fit(z: np.ndarray, ang: np.ndarray, valid: np.ndarray, pattern: BeamPattern) -> tuple[np.ndarray, np.ndarray]:
    """(patterns (K, B, J), amplitudes (K, J)) of the peaks at ``ang`` fitted to z (K, B) (:func:`_amplitudes`)."""
    u = np.cos(np.deg2rad(pattern.cone_deg))
    resp = pattern.response(u[None, :, None] - np.cos(np.deg2rad(ang))[:, None, :]) * valid[:, None, :]
    return resp, _amplitudes(z, resp, valid)


def resolve_peaks_batch(z: np.ndarray, angles_deg: list[np.ndarray], pattern: BeamPattern,
                        iterations: int = PATTERN_ITERATIONS) -> list[np.ndarray]:
    """:func:`resolve_peaks` on K windows at once: z (K, B), one array of peak angles (deg) per window (padded to the
    most peaks inside; a window's result depends on its own row only). Returns one array per window."""
    z = np.atleast_2d(np.asarray(z, dtype=float))
    ang, valid, counts = _padded_angles(angles_deg)
    if ang.shape[1] == 0:
        return [np.asarray(a, dtype=float).copy() for a in angles_deg]
    # a window with one peak has nothing to take out: one pass, whatever its batch holds, so that a window's angles
    # are the same batched or alone (the live chain's windows come one at a time: systems/live/)
    again = valid & (np.array(counts, dtype=int) > 1)[:, None]
    for it in range(iterations if ang.shape[1] > 1 else 1):
        resp, amp = _fit(z, ang, valid, pattern)
        residual = (z - (resp @ amp[..., None])[..., 0])[:, :, None] + resp * amp[:, None, :]
        ang = np.where(valid if it == 0 else again, _vertices(residual, ang, pattern), ang)
    return [ang[i, :c] for i, c in enumerate(counts)]


def add_hidden_peaks(z: np.ndarray, peaks: list[tuple[np.ndarray, np.ndarray]], pattern: BeamPattern,
                     settings: BeamformerSettings) -> list[tuple[np.ndarray, np.ndarray]]:
    """The windows' peaks with the ships hidden on louder ones' lobes added (one CLEAN step: Hogbom, Astron.
    Astrophys. Suppl. 15, 1974; the sources' fitted patterns taken out of the map, the residual searched again).

    A weak ship less than a beamwidth or so from a loud one makes a shoulder on the loud one's lobe, not a maximum
    of z, and has no peak. With the peaks' patterns fitted to z (:func:`resolve_peaks`), the residual
    z - sum_j a_j g(cos theta - u_j) is at most z everywhere (a_j >= 0, g >= 0); its maxima at or above the
    threshold more than the main lobe's half-power half-width (in u) from every peak are new peaks, with the
    residual's height as their amplitude, and each window with new peaks is refined again. At most ``max_peaks``
    per window (the highest), in increasing cone angle.

    Parameters
    ----------
    z : numpy.ndarray
        (K, B) the windows' normalised levels.
    peaks : list of (numpy.ndarray, numpy.ndarray)
        Per window, the refined peak angles (deg) and heights.
    pattern : BeamPattern
        The front end's pattern (:func:`beam_pattern`).
    settings : BeamformerSettings
        Its ``threshold`` and ``max_peaks``.

    Returns
    -------
    list of (numpy.ndarray, numpy.ndarray)
        Per window, the angles (deg) and heights with the hidden peaks.
    """
    z = np.atleast_2d(np.asarray(z, dtype=float))
    ang, valid, _ = _padded_angles([a for a, _ in peaks])
    resp, amp = _fit(z, ang, valid, pattern)
    residual = z - (resp @ amp[..., None])[..., 0]
    out, grown = list(peaks), []
    for i, (a, h) in enumerate(peaks):
        if not len(a):
            continue
        a2, h2 = pick_beam_peaks(residual[i], pattern.cone_deg, settings)
        du = np.abs(np.cos(np.deg2rad(a2))[:, None] - np.cos(np.deg2rad(a))[None, :])
        new = np.all(du > pattern.half_width_u, axis=1)
        if new.any():
            out[i] = (np.concatenate([a, a2[new]]), np.concatenate([h, h2[new]]))
            grown.append(i)
    if grown:
        refined = resolve_peaks_batch(z[grown], [out[i][0] for i in grown], pattern)
        for i, a in zip(grown, refined, strict=True):
            h = out[i][1]
            keep = np.sort(np.argsort(-h, kind="stable")[: settings.max_peaks])
            order = keep[np.argsort(a[keep], kind="stable")]
            out[i] = (a[order], h[order])
    return out


def resolve_peaks(z: np.ndarray, angle_deg: np.ndarray, pattern: BeamPattern,
                  iterations: int = PATTERN_ITERATIONS) -> np.ndarray:
    """The peaks' cone angles refined jointly with the array's own beam pattern (the RELAX iteration: Li & Stoica,
    IEEE Trans. Signal Process. 44(2), 1996, sec. III).

    The expected beam power of independent sources is a constant plus the sum of their patterns,
    z(theta) = c + sum_j a_j g(cos theta - u_j) (:func:`pattern_sum`; the normaliser is affine in each window). A
    parabola through three beams finds the vertex of the sum, which the slope of the other sources' lobes pulls
    off each source's own: 0.1-0.3 deg on 16-element arrays with a ship 17 deg away, towards endfire where the
    beam is wide, slowly varying and so not averaged out by the TMA. Each pass fits c and the amplitudes a_j >= 0
    by least squares over all beams, then moves each peak to the vertex of z minus the other peaks' patterns,
    found exactly for the pattern: the offset from the largest beam whose three-beam ratio equals the tabulated
    one (:class:`BeamPattern`; a single plane wave's peak then lies on its cone angle to < 0.01 beamwidth). Two
    ships within one beam give one peak and stay one source (their strength-weighted centre).

    Parameters
    ----------
    z : numpy.ndarray
        (B,) the window's normalised level on the pattern's beams.
    angle_deg : numpy.ndarray
        (J,) the peaks' cone angles (deg) as picked (:func:`pick_beam_peaks`).
    pattern : BeamPattern
        The front end's pattern (:func:`beam_pattern`).
    iterations : int
        Passes over all peaks (one when there is a single peak: nothing to take out).

    Returns
    -------
    numpy.ndarray
        (J,) refined cone angles (deg, within 0..180), same order.
    """
    return resolve_peaks_batch(np.asarray(z, dtype=float)[None], [np.asarray(angle_deg, dtype=float)], pattern,
                               iterations)[0]

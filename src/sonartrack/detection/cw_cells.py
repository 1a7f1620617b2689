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

and mu = max(mu_f, sqrt(mu_e mu_l)): off the ridge all see the noise; on the ridge's skirts mu_f sees the quieter
Doppler cells beside it and would let the ridge through, but the delay estimate sees the ridge's own level at the
neighbouring delays. The reverberation falls with delay (two-way spreading over a growing area, ~t^-3: 9 dB from
7 to 14 s); where its log level is linear in delay over the window the geometric mean of the estimates before and
after the cell is its level at the cell (where it is convex, as t^-3 is, above it: conservative). The greatest-of
of the two (the first version) took the earlier, louder side: measured on the default scene with a CW (seed 9101,
every 3rd ping of 3600 s) the strongest target's median statistic rose from 10.6 to 22.3 and the echoes found
from 54 to 71 of 200 with the geometric mean. Where no earlier reference lies after the blanking (the first
``delay_guard + 1`` pulse lengths after ``blank_s``) the trend is not known: with the geometric mean there those
delays were not searched (measured: the detections off the targets fell from 209 to 81 in 40 pings, the echoes
found 71 -> 68), which lost the echoes that come early (a quarter of crossing-b's pings on the default scene). With
``early_search`` they are searched with mu = max(mu_f, mu_l), the later delay estimate alone against the Doppler
estimate of the same delay (the reverberation's leakage off the ridge is in mu_f), at their own exact law
(detection/cw_law.py, F_G replaced by F_l, the OS law of mu_l) mapped to the two-sided law by equal tails,
s -> Q_2^-1(Q_1(s)), Q(a) = P(s > a) (:func:`equal_tail_map`): in homogeneous noise the early cells then have the
same law as the others, so one threshold and the MFTD's calibration (detection/mftd_tiles.py) hold for all.
``trend`` extrapolates instead the log level of the two later windows, mu_1^(1 + r) / mu_2^r (r the cell's distance
to the first window's centre over the windows' spacing; law by the convolution of the two log estimates' laws).
Measured (default scene as CW, seed 1, 1 h, benchmarks/bench_cw_held.py; held % of detectable pings approacher /
crossing-a / crossing-b / maneuvering, false targets): off 86/72/72/71, 1; late 67/58/90/80, 100; trend 77/65/100/81,
70: the echoes there are found, but the reverberation right after the blanking is heavier-tailed than the
exponential law (K-distributed, the sea's discrete scatterers) and ~11 cells a ping alarm: off by default.
The delay estimates run over every delay, the blanked start too, whose direct blast then lifts the earlier estimate
of the delays up to (delay_guard + delay_reference + 1) pulse lengths after ``blank_s`` (most of the default scene's
echoes lie 3.5 to 10 s out): with ``references_after_blank`` they take only the cells from ``blank_s`` on, the
window's part before it filled with the largest of the first ``delay_reference`` cells (conservative: one cell
repeated is an estimate of one cell, not of the OS law, and alarmed: off-target single-ping detections 282 -> 446 in
120 pings, 7 false targets, nearly all 3.5-4.5 s). Measured (default scene as CW, 1 h, benchmarks/bench_cw_held.py,
held % of detectable pings approacher / crossing-a / crossing-b / maneuvering, false targets; MFTD detections of the
approacher and crossing-b): seed 1 86/72/72/71, 1 -> 90/72/76/70, 1 (18 -> 24 %, 27 -> 28 %); seed 2 74/82/71/79, 1
-> 75/82/76/79, 1 (24 -> 28 %, 18 -> 22 %); the second CW scene (32 x 0.3 m, 2.4 kHz) seed 1 100/82/93/82, 1 ->
100/82/87/83, 0. On by default. s = y / mu.

Delay guard. A CW's matched filter answers its echo with a triangle 2 tau wide at its base: the delay references
one pulse length from the cell (``delay_guard`` 0) hold none of the echo (at most -18 dB of it with the echo's peak
an eighth of a pulse off the cell grid), so no guard pulse is needed, and without one the first delay searched is
blank_s + tau (2.5 s, not 3.5 s) and the references lie nearer the cell, where the reverberation's level is.
Measured (benchmarks/bench_cw_held.py, 1 h, held % of detectable pings approacher / crossing-a / crossing-b /
maneuvering, false targets; guard 1 -> 0): default scene as CW seed 1 90/73/76/84, 1 -> 90/75/94/84, 1; seed 2
86/80/76/79, 1 -> 86/80/93/77, 2; the second CW scene (32 x 0.3 m, 2.4 kHz) seed 1 100/76/85/92, 1 -> 80/80/99/88,
1. Its cost (benchmarks/bench_cw_contacts.py, seed 2): false detections given to the tracker 0.32 -> 0.48 a ping,
single-ping ones 1.48 -> 2.29 (the nearer references follow the reverberation more closely, and it is
heavier-tailed than the exponential law the threshold assumes); the detectable pings' Pd of crossing-b 54 -> 67 %.

Threshold: the law of M and the threshold on s are detection/cw_law.py's.

Ridge. A stationary scatterer in the direction u (unit vector) from the far field has bistatic range rate
rdot = -(u . v_T + u . v_R) (v_T, v_R the source's and receiver's velocities; far field: u_T = u_R = u).
A beam at cone theta from the array axis (heading phi) looks along both mirror directions phi +- theta, and it
hears the sea over its whole main lobe, and over its grating lobe near endfire (elements half a wavelength apart
steered to endfire have one at the opposite endfire): the ridge of a beam is the set of rdot of the directions
where its pattern |sin(N x) / (N sin x)|^2 (acoustics/active_beams.py) is above ``ridge_beam_level_db``
(-10 dB: the main and grating lobes, not the -13 dB sidelobes, whose leakage the normaliser follows) in both
mirror directions; at broadside of the default array (6 deg beam, platforms at 2.5 m/s) it is ~1 m/s wide,
near endfire it holds both ends of the band. Cells within ``ridge_margin_cells`` Doppler resolution cells
(c / (f_c tau) m/s each) of it are set to s = 0: a CW cannot tell an echo there from the sea's (targets that
hold the sea's Doppler are an LFM's), and persistent clutter points, which sit on the ridge, go with it.
Measured (as above): the detections off the targets fell from 164 to 90 (40 pings), the echoes found 56 -> 54.
A notched point's echo still spreads past the notch through the pulse's ambiguity function (at half a pulse off in
delay its Doppler main lobe is twice as wide): those skirt cells are not searched either (``skirt_margin_db``,
:func:`notch_skirts`; study active-chain trial 1's reverberation-only hour: 6 -> 0 false confirmed tracks). Off
by default: a target on or near the ridge (crossing, zero world Doppler) is notched too, and its skirt had kept its
track alive; measured on the default scene as CW (benchmarks/bench_active_rows.py, 1 h; rows, false, extra; held %
approacher/crossing-a/crossing-b/maneuvering), off -> 3 dB: seed 1 7, 1, 2; 95/75/100/91 -> 8, 1, 3; 95/79/100/65;
seed 2 5, 0, 1; 90/76/100/85 -> 7, 1, 2; 92/74/100/82. Sources of 15 dB (s >= 30) instead of 10 dB: trial 1 6 -> 4.
What the chain does instead: the echoes under the notch (:func:`ridge_echoes`) feed a clutter map of their own, not the
tracker; where it shows one still at one world place over pings, its skirt and images are withheld (detection/
clutter_map.py module doc), and a target crossing the ridge, not still in the world, keeps its skirt.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting
from sonartrack.detection.cfar import CfarSettings, noise_estimate, os_mean_factor
from sonartrack.detection.cw_law import CwEstimate, equal_tail_map, os_cdf, os_draws

__all__ = ["CwEstimate", "CwNormaliserSettings", "cw_noise_estimate", "cw_ping_cells", "cw_statistic", "cw_threshold",
           "doppler_stride", "equal_tail_map", "first_searched_delay_s", "notch_skirts", "one_sided_os", "os_cdf",
           "os_draws", "ridge_echoes", "skirt_gain"]


class CwNormaliserSettings(Settings):
    """The CW front end's replica taper, normaliser and ridge notch (module doc)."""

    taper: str = setting("rect", "the replica's amplitude taper: rect (the pulse itself) or hann (Doppler sidelobes "
                                 "-31 dB, not -13, at 1.8 dB less gain in noise; acoustics/matched_filter.py)", unit="")
    doppler_guard: int = setting(1, "guard cells each side across Doppler, in Doppler resolution cells (1 / tau)",
                                 unit="1", ge=0, le=16)
    doppler_reference: int = setting(6, "reference cells each side across Doppler, in resolution cells", unit="1",
                                     ge=1, le=64)
    delay_guard: int = setting(0, "guard cells each side along delay, in pulse lengths beyond the first (0: the "
                                  "references start one pulse length from the cell, where the echo's triangle ends; "
                                  "module doc)", unit="1", ge=0, le=16)
    delay_reference: int | None = setting(4, "reference cells each side along delay, in pulse lengths (short: the "
                                             "reverberation falls with delay); 'off': the Doppler estimate alone",
                                          unit="1", ge=1, le=64)
    os_rank: float = setting(0.75, "order statistic of both estimates: rank k as a fraction of N", unit="1", gt=0,
                             le=1)
    ridge_beam_level_db: float = setting(-10.0, "a beam's reverberation ridge: the stationary sea's range rate in the "
                                                "directions where its pattern is above this", unit="dB", le=0)
    ridge_margin_cells: float | None = setting(
        1.0, "cells within this many Doppler resolution cells (c / (f_c tau) m/s each) of a beam's reverberation ridge "
             "are not searched ('off': no notch)", unit="1", ge=0, le=20)

    skirt_margin_db: float | None = setting(
        None, "a cell off the notch is the delay-Doppler skirt of a notched echo (its own beam; the echo's statistic "
             "before the notch >= SKIRT_SOURCE_STAT) when its power is at most the CW ambiguity's prediction from that "
             "echo plus this margin, and is not searched (:func:`notch_skirts`; not set: no skirt test, the "
             "default: at 3 dB it costs targets near the ridge, module doc)", unit="dB",
        ge=0, le=20)

    early_search: Literal["off", "late", "trend"] = setting(
        "off", "the delays from blank_s to the first two-sided delay: off (not searched), late (searched with the "
                 "Doppler estimate and the next later delay estimate) or trend (the later two delay estimates' log "
                 "level extrapolated to the cell); their statistic mapped to the two-sided law's (module doc)",
        unit="")

    references_after_blank: bool = setting(
        True, "the delay estimates take only the cells after blank_s (the blanked start holds the direct blast; "
               "the earlier references of the first delays then repeat the first cell after it)", unit="")

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

    def early_estimate(self) -> CwEstimate | None:
        """The law of the early delays' estimate (module doc), or None when they are not searched.

        Returns
        -------
        CwEstimate or None
            :meth:`estimate` with ``trend`` :meth:`early_trend`.
        """
        e = self.estimate()
        return None if e.delay is None or self.early_search == "off" else CwEstimate(e.doppler, e.delay,
                                                                                     self.early_trend())

    def early_trend(self) -> float:
        """r of the early estimate mu_1^(1 + r) / mu_2^r: the cell's distance to the centre of the next later
        window over the two windows' distance, (delay_guard + (delay_reference + 1) / 2) / delay_reference
        (log level linear in delay); 0 for ``late``."""
        if self.early_search != "trend" or self.delay_reference is None:
            return 0.0
        return (self.delay_guard + (self.delay_reference + 1) / 2.0) / self.delay_reference

    def estimate(self) -> CwEstimate:
        """The law of the noise estimate (module doc): the Doppler estimate's and the delay estimates' (N, k).

        Returns
        -------
        CwEstimate
            (N_f, k_f) both sides across Doppler; (N_t, k_t) each side along delay, or None.
        """
        f = self.axis_cfar(self.doppler_guard, self.doppler_reference)
        if self.delay_reference is None:
            return CwEstimate((f.n_reference, f.rank), None)
        n_t = self.delay_reference
        return CwEstimate((f.n_reference, f.rank), (n_t, int(min(max(round(self.os_rank * n_t), 1), n_t))))


def cw_threshold(pfa: float, settings: CwNormaliserSettings) -> float:
    """Threshold on s for ``pfa`` per cell (module doc).

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
    return settings.estimate().threshold(float(pfa))


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


def one_sided_os(y: np.ndarray, guard: int, reference: int, rank: int, stride: int,
                 pad_with_max: bool = False) -> np.ndarray:
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
    pad_with_max : bool
        Past the ends repeat the largest of the ``reference`` end cells instead (the axis starts after the
        blanking: one repeated cell would be an estimate of one cell, not of the OS law, and alarm; the largest
        errs high, masking).

    Returns
    -------
    ndarray (2, ..., M), float32
        [early, late] estimates.
    """
    out = np.empty((2,) + y.shape, np.float32)
    half, c_k = guard + reference, os_mean_factor(reference, rank)
    for c in range(stride):
        z = np.pad(y[..., c::stride], [(0, 0)] * (y.ndim - 1) + [(half, half)],
                   **({"mode": "maximum", "stat_length": reference} if pad_with_max else {"mode": "edge"}))
        w = np.lib.stride_tricks.sliding_window_view(z, 2 * half + 1, axis=-1)
        for side, cells in enumerate((w[..., :reference], w[..., reference + 2 * guard + 1:])):
            out[side, ..., c::stride] = np.partition(cells, rank - 1, axis=-1)[..., rank - 1] / c_k
    return out


def cw_noise_estimate(power: np.ndarray, settings: CwNormaliserSettings, delay_stride: int,
                      doppler_step: int, early_rows: int = 0) -> np.ndarray:
    """mu = max(mu_f, sqrt(mu_early mu_late)) of every cell of (beams, delays, Dopplers) power (module doc), float32;
    max(mu_f, mu_1^(1 + r) / mu_2^r) in the first ``early_rows`` delays (``early_trend`` r; mu_1 the later
    estimate, mu_2 the later estimate ``delay_reference`` pulse lengths on).

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
    early_rows : int
        Delays (from the first) whose earlier reference is not known (module doc): the later estimate alone.

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
    k_t = s.estimate().delay[1]
    early, late = one_sided_os(np.moveaxis(y, 1, -1), s.delay_guard, s.delay_reference, k_t, delay_stride,
                               s.references_after_blank)
    mu_t = np.sqrt(early * late)
    near = late[..., :early_rows]
    far = late[..., np.minimum(np.arange(early_rows) + s.delay_reference * delay_stride, late.shape[-1] - 1)]
    r = s.early_trend()
    mu_t[..., :early_rows] = near if r == 0 else near ** (1.0 + r) / np.maximum(far, 1e-30) ** r
    return np.maximum(mu_f, np.moveaxis(mu_t, -1, 1))


def cw_matched_cells(samples: np.ndarray, fs_hz: float, waveform, array, front_end, taper: str):
    """Beams, then the CW Doppler bank with the replica's ``taper`` (detection/cells.py's ``matched_cells`` for a
    CW; acoustics/matched_filter.py): (power (B, D, J) float32, delay_s (D,), doppler_hz (J,))."""
    from sonartrack.acoustics.active_beams import beamform_spectra, cone_grid_deg
    from sonartrack.acoustics.matched_filter import cw_doppler_bank, fft_length
    from sonartrack.detection.cells import matched_cells

    if taper == "rect":
        return matched_cells(samples, fs_hz, waveform, array, front_end)
    x = np.asarray(samples)
    require(x.ndim == 2, f"a ping must be channels x samples, got shape {x.shape}")
    n_pulse, m = waveform.n_samples(fs_hz), x.shape[1]
    require(m > n_pulse, f"the ping ({m} samples) is not longer than the pulse ({n_pulse} samples at {fs_hz:g} Hz)")
    spectra = np.fft.fft(x.astype(np.complex64, copy=False), fft_length(m + n_pulse), axis=1)
    beams = beamform_spectra(spectra, fs_hz, waveform.carrier_hz, array, cone_grid_deg(front_end.beams),
                             front_end.sound_speed_mps)
    f_max = front_end.max_range_rate_mps * waveform.carrier_hz / front_end.sound_speed_mps
    hop = max(int(round(front_end.cw_hop * n_pulse)), 1)
    z, delay, doppler = cw_doppler_bank(np.fft.ifft(beams, axis=1)[:, :m], fs_hz, waveform, f_max, hop,
                                        front_end.doppler_pad, taper)
    return (z.real**2 + z.imag**2).astype(np.float32), delay, doppler


def first_searched_delay_s(front_end, settings: CwNormaliserSettings, duration_s: float) -> float:
    """The first delay searched (module doc): ``blank_s``, and with the delay estimate (delay_guard + 1) pulse
    lengths later, so that the earlier estimate holds a reference after the blanking."""
    if settings.delay_reference is None:
        return float(front_end.blank_s)
    return float(front_end.blank_s + (settings.delay_guard + 1) * duration_s)


def cw_statistic(power: np.ndarray, delay: np.ndarray, doppler: np.ndarray, waveform, front_end,
                 settings: CwNormaliserSettings) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The normalised cells s = y / mu of (B, D, J) power (module doc), the early delays' mapped to the two-sided
    law (``early_search``), the delay estimates over every delay or after ``blank_s`` (``references_after_blank``).

    Returns
    -------
    tuple of ndarray
        (s (B, D, J), mu (B, D, J), the delays searched (D,) bool).
    """
    step = float(delay[1] - delay[0]) if delay.size > 1 else waveform.duration_s
    first = first_searched_delay_s(front_end, settings, waveform.duration_s)
    early_law = settings.early_estimate()
    start_s = float(front_end.blank_s) if early_law is not None else first
    keep = delay >= start_s - 1e-9
    require(bool(keep.any()), f"the CW search starts at {start_s:g} s (blank_s and the delay estimate's cells), past "
                              f"the {delay[-1]:.3g} s window: lower blank_s or delay_guard")
    early = np.nonzero(keep & (delay < first - 1e-9))[0]
    n_early = int(early[-1]) + 1 if early.size else 0
    start = int(np.argmax(delay >= front_end.blank_s - 1e-9)) if settings.references_after_blank else 0
    mu = np.full_like(power, np.inf)
    mu[:, start:] = cw_noise_estimate(power[:, start:], settings, max(int(round(waveform.duration_s / step)), 1),
                                      doppler_stride(waveform.duration_s, doppler), max(n_early - start, 0))
    stat = np.divide(power, mu, out=np.zeros_like(power), where=mu > 0)
    if early.size:
        stat[:, early] = equal_tail_map(stat[:, early], early_law, settings.estimate())
    return stat, mu, keep


def cw_ping_cells(samples: np.ndarray, fs_hz: float, waveform, array, front_end, settings: CwNormaliserSettings, *,
                  time_s: float = 0.0, ping: int = 0, motion: tuple | None = None):
    """One CW ping's normalised cells (module doc): the beams and the Doppler bank (:func:`cw_matched_cells`),
    this normaliser, the blanking, and the ridge notch when ``motion`` is given.

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
        The taper, the normaliser and the notch.
    time_s : float
        Transmit time (s).
    ping : int
        The ping's number.
    motion : tuple, optional
        (array heading rad, source velocity (2,), receiver velocity (2,) [east, north] m/s) at the ping:
        the reverberation ridge (detection/cw_ridge.py); None: no notch.

    Returns
    -------
    PingCells
        As detection/cells.py's, the statistic s = y / max(mu_f, sqrt(mu_e mu_l)), 0 in the notch; with the array's
        lobe band and the power before the notch when ``front_end.lobe_margin_db`` is set (detection/lobes.py).
    """
    from sonartrack.acoustics.active_beams import cone_grid_deg
    from sonartrack.acoustics.matched_filter import doppler_to_range_rate
    from sonartrack.detection.cells import PingCells, lobe_band
    from sonartrack.detection.cw_ridge import beam_ridge_notch

    require(waveform.kind == "cw", "the CW front end takes a CW pulse")
    power, delay, doppler = cw_matched_cells(samples, fs_hz, waveform, array, front_end, settings.taper)
    stat, mu, keep = cw_statistic(power, delay, doppler, waveform, front_end, settings)
    rate = doppler_to_range_rate(doppler, waveform.carrier_hz, front_end.sound_speed_mps)
    stat = np.ascontiguousarray(stat[:, keep])
    cone = cone_grid_deg(front_end.beams)
    if motion is not None and settings.ridge_margin_cells is not None:
        margin = settings.ridge_margin_cells * front_end.sound_speed_mps / (waveform.carrier_hz * waveform.duration_s)
        notch = beam_ridge_notch(rate, cone, *motion, array, waveform.carrier_hz, front_end.sound_speed_mps,
                                 settings.ridge_beam_level_db, margin)
        if settings.skirt_margin_db is not None:  # a notched echo's delay-Doppler skirt goes with it
            skirt = notch_skirts(power[:, keep], stat, notch, delay[keep], doppler, waveform.duration_s,
                                 settings.skirt_margin_db)
            stat[skirt] = 0.0
        stat[np.broadcast_to(notch[:, None, :], stat.shape)] = 0.0
    lobes = lobe_band(waveform, array, front_end)  # the power before the notch: a notched clutter point's sidelobes
    raw = np.ascontiguousarray(power[:, keep]) if lobes is not None else None
    return PingCells(int(ping), float(time_s), cone, delay[keep], doppler, rate, stat, True,
                     np.ascontiguousarray(mu[:, keep]), lobes, raw)



#: a notched cell is an echo whose skirt is sought when its statistic before the notch is at least this (10 dB over
#: its own background: a point on the ridge, not the ridge's reverberation, whose skirt the normaliser already sees)
SKIRT_SOURCE_STAT = 10.0


def skirt_gain(dt_s, df_hz, tau_s: float) -> np.ndarray:
    """Power of a rectangular CW's ambiguity function at delay offset dt and Doppler offset df, bounded by its
    sidelobe envelope: |chi(dt, df)|^2 = (1 - |dt| / tau)^2 sinc^2(df (tau - |dt|)) (the ambiguity function of a
    constant-frequency rectangular pulse: Levanon & Mozeson, Radar Signals, 2004, ch. 2), sinc^2(x) =
    (sin pi x / pi x)^2 replaced by its envelope min(1, 1 / (pi x)^2) so that the nulls (which a cell grid does not
    sample exactly) hold no gap; 0 for |dt| >= tau.

    Parameters
    ----------
    dt_s, df_hz : array
        Delay (s) and Doppler (Hz) offsets from the echo's peak (broadcast).
    tau_s : float
        Pulse length (s).

    Returns
    -------
    numpy.ndarray
        Power gain (1 at the peak).
    """
    rest = np.clip(1.0 - np.abs(np.asarray(dt_s, float)) / tau_s, 0.0, 1.0)
    x = np.pi * np.abs(np.asarray(df_hz, float)) * tau_s * rest
    return rest**2 * np.minimum(1.0, 1.0 / np.maximum(x, 1e-12) ** 2)


def notch_skirts(power: np.ndarray, stat: np.ndarray, notch: np.ndarray, delay_s: np.ndarray, doppler_hz: np.ndarray,
                 tau_s: float, margin_db: float) -> np.ndarray:
    """(B, D, J) bool: the cells off the ridge notch that a notched echo of their own beam explains.

    A still clutter point sits at zero world Doppler, on its own beam's reverberation ridge, which the front end
    notches; its echo's peak is then not searched, but the CW's matched filter spreads it over delay and Doppler by
    the ambiguity function (:func:`skirt_gain`: at half a pulse off in delay the Doppler main lobe is twice as wide),
    and the skirt's cells beyond the notch were detected (measured on study active-chain trial 1, CW 8 x 0.5 m,
    1 kHz, a TS 30 dB point: contacts 600-1000 m off in bistatic range and 1.5-2.4 m/s off the point's range rate,
    on ~10 of 120 pings, enough for 6 false confirmed tracks an hour; benchmarks/bench_active_family.py). A cell is a
    skirt when some notched cell of its beam with statistic before the notch >= :data:`SKIRT_SOURCE_STAT` (an echo
    above the ridge) within a pulse length has power P' with P <= P' |chi(dt, df)|^2 10^(margin_db / 10), any
    notched cell above the source level, not only the echo's peak: its skirt's own notched cells then reach up to
    two pulse lengths from the peak (measured: with the peak alone as source, the largest notched power within one
    or half a pulse length, trial 1 kept 2 of the 6 false tracks, a mirror pair on the TS 30 dB point at ping 76;
    with every notched cell above the level, none). The price: an echo near the ridge within two pulse lengths of a
    stronger notched echo, no stronger than that echo's skirt, is lost on that ping.

    Parameters
    ----------
    power : ndarray (B, D, J)
        Matched-filter power.
    stat : ndarray (B, D, J)
        The normalised statistic before the notch.
    notch : ndarray (B, J) bool
        The notched Doppler cells of each beam.
    delay_s, doppler_hz : ndarray (D,), (J,)
        The cells' delays (s) and Doppler shifts (Hz).
    tau_s : float
        Pulse length (s).
    margin_db : float
        Allowed above the ambiguity's prediction (dB).

    Returns
    -------
    numpy.ndarray
        (B, D, J) bool, False in the notch.
    """
    B, D, J = stat.shape
    out, step = np.zeros((B, D, J), bool), (float(np.median(np.diff(delay_s))) if D > 1 else tau_s)
    w = int(np.ceil(tau_s / step))
    lag = np.arange(-w, w + 1)
    scale = 10.0 ** (margin_db / 10.0)
    for b in range(B):
        js = np.nonzero(notch[b])[0]
        if not len(js):
            continue
        src = np.where(stat[b][:, js] >= SKIRT_SOURCE_STAT, power[b][:, js], 0.0)  # (D, n)
        if not src.any():
            continue
        gain = skirt_gain(lag[:, None, None] * step, doppler_hz[None, None, :] - doppler_hz[js][None, :, None],
                          tau_s)  # (L, n, J)
        explained = np.zeros((D, J))
        for k, s in enumerate(lag):  # explained[d] = max over lag, notched j' of P'(d - s, j') gain(s, j', j)
            shifted = np.zeros_like(src)
            lo, hi = max(s, 0), D + min(s, 0)
            shifted[lo:hi] = src[lo - s:hi - s]
            explained = np.maximum(explained, (shifted[:, :, None] * gain[k][None]).max(axis=1))
        out[b] = (power[b] <= explained * scale) & (explained > 0) & ~notch[b][None, :]
    return out



def ridge_echoes(cells, threshold: float):
    """The echoes the ridge notch hides: local maxima of the statistic BEFORE the notch, s' = P / mu (``cells.power``
    over ``cells.level``), at or above ``threshold``, whose cell lies in its beam's notched Doppler cells (those set
    to s = 0 at every delay).

    Why. A still clutter point echoes at the stationary sea's Doppler in its own direction, on its own beam's ridge,
    which the front end notches (module doc): the chain's detections never hold the point itself, only its skirt
    past the notch and its sidelobe images in other beams, 400-2000 m off it and at varying places, which no clutter
    map shows still (study active-chain trial 15, CW 16 x 0.5 m, 2.4 kHz: 8 of 9 false confirmed tracks an hour on
    two points of TS 25-30 dB; benchmarks/bench_active_family.py). These echoes are the point itself, at its own
    delay and cone, on every ping it is above the ridge's reverberation: the clutter map (detection/clutter_map.py)
    is fed them, not the tracker (a CW cannot tell a still point from a target holding the sea's Doppler on one
    ping; the map's recurrence at one world place and its stillness fit over pings can; systems/active/
    contact_tracker.py ``ridge_map_of``).

    Parameters
    ----------
    cells : PingCells
        A CW ping's cells from :func:`cw_ping_cells` with ``power`` and ``level`` kept (``lobe_margin_db`` set).
    threshold : float
        Threshold on s' (the single-ping detector's).

    Returns
    -------
    Detections or None
        The hidden echoes (``statistic`` s'); None when the cells keep no power before the notch.
    """
    from dataclasses import replace

    from sonartrack.detection.cells import detect_ping

    if cells.power is None or cells.level is None:
        return None
    notch = (np.asarray(cells.statistic) <= 0.0).all(axis=1)  # (B, J): the notched Doppler cells of each beam
    level = np.asarray(cells.level, np.float32)
    before = np.divide(np.asarray(cells.power, np.float32), level, out=np.zeros_like(level), where=level > 0)
    det = detect_ping(replace(cells, statistic=before, lobes=None, power=None), threshold)
    keep = notch[det.beam, det.doppler_cell]
    return type(det)(**{f: np.asarray(getattr(det, f))[keep] for f in type(det).__slots__})

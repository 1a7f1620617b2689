"""An active ping's cells and single-ping detections: beams -> matched filter -> CFAR -> threshold.

One ping on a towed line array (complex baseband, channels x samples) becomes a cube of cells
(beams x delays x Dopplers) holding the CFAR-normalised square-law statistic s = |z|^2 / mu
(acoustics/active_beams.py, acoustics/matched_filter.py, detection/cfar.py):

* beams: true-time-delay CBF on a cone grid (0 = ahead along the array axis);
* delays: the travel time of the echo's leading edge from transmission to the array centre; an LFM's
  cells are the samples (1 / f_s apart), a CW's are every ``cw_hop`` pulse lengths;
* Dopplers: one cell (0 Hz) for an LFM (Doppler tolerant: an echo at Doppler f_d compresses at the delay
  travel time - f_d tau / B, acoustics/matched_filter.py), the Doppler filter bank for a CW, spanning
  |bistatic range rate| <= ``max_range_rate_mps`` (f_d = -f_c rdot_B / c);
* delays below ``blank_s`` are dropped (the direct blast of the source and the pulse's own length), and so are
  those before the end of the direct blast where the navigation gives its arrival (|Tx - Rx| / c, one pulse long,
  plus ``blast_guard_s``): the samples before that gate are zeroed before the beams (:func:`gated_samples` says
  why) and the CFAR runs on the cells after it only (a reference in the blanked start would be no reference);
* the CFAR runs along delay with its reference cells one resolution cell apart (:func:`cfar_stride`: 2 cells
  for the default LFM sampled at 2 B, 4 for a CW's quarter-pulse delays), so that they are about independent,
  as the closed-form thresholds assume (with every cell as a reference the noise-only false-alarm rate was
  measured 2-6 times the stated Pfa); the window then spans stride x (guard + reference) cells a side.

In homogeneous noise s is exponential with mean 1 (paper P1's square-law cell statistic, eq. 8, has mean 2:
multiply by 2 before P1's detector). A single-ping detection is a cell with s >= threshold that is the
largest in its neighbourhood (+-1 beam, +-guard_cells delays, +-1 Doppler: one detection per echo, not one
per cell of its main lobe); its delay and Doppler are refined by a parabola through the log statistic of the
neighbours on each axis (offset within +-half a cell). Its cone angle is taken from the beams' power
|z|^2 = s mu, not from s (:func:`power_cone_deg`): the CFAR's mu differs from beam to beam (a strong echo's own
range sidelobes raise it in the beams that hold the echo, and the wide beams near endfire gather more
reverberation), so the peak of s across beams is pulled towards the beams of lower mu. Measured on the default
scene (seed 9002, not a study seed) for an echo 44 dB above the noise at cone 170.5 deg: the power peaks at 171
deg, s at 162. The threshold for a stated Pfa per cell is the CFAR's closed form (:func:`detection_threshold`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.acoustics.active_beams import LineArray, beamform_spectra, cone_grid_deg
from sonartrack.acoustics.matched_filter import (
    Waveform,
    cw_doppler_bank,
    doppler_to_range_rate,
    fft_length,
    pulse_compress,
)
from sonartrack.core.errors import require
from sonartrack.core.rows import Rows
from sonartrack.core.settings import Settings, setting
from sonartrack.detection.cfar import CfarSettings, cfar_threshold, noise_estimate
from sonartrack.detection.lobes import LobeBand, cell_images
from sonartrack.detection.normalise import DelayShapes, DelayShapeSettings


class FrontEndSettings(Settings):
    """The active front end of one ping (module doc)."""

    beams: int = setting(61, "cone-angle grid: this many beams uniform in 0..180 deg (61 = 3 deg steps; the "
                             "default 16-element array's beams are ~6 deg wide at broadside)", unit="1", ge=2)
    sound_speed_mps: float = setting(1500.0, "sound speed c at the array (steering, Doppler to range rate)",
                                     unit="m/s", gt=1300, lt=1700)
    max_range_rate_mps: float = setting(15.0, "CW Doppler bank: |bistatic range rate| spanned (rate of the total "
                                              "path Tx -> target -> Rx)", unit="m/s", gt=0)
    cw_hop: float = setting(0.25, "CW delay cells: step in pulse lengths (0.25: an echo is within 1.2 dB of a "
                                  "cell's peak)", unit="1", gt=0, le=1)
    doppler_pad: int = setting(2, "CW Doppler filters 1 / (doppler_pad tau) apart (the resolution is ~0.88 / tau)",
                               unit="1", ge=1, le=8)
    blank_s: float = setting(1.5, "delays below this are not searched: the direct blast (baseline / c) and the "
                                  "pulse length", unit="s", ge=0)
    blast_guard_s: float | None = setting(
        0.2, "the samples before the end of the direct blast plus this guard are zeroed before the beams, and no delay "
             "before it is searched or used as a CFAR reference: the blast's arrival is the source-array distance / c "
             "from the navigation, its end one pulse later (module doc; 'off': only blank_s)", unit="s", ge=0, le=10)
    pfa: float = setting(1e-5, "false-alarm probability per cell of the single-ping threshold", unit="1",
                         gt=0, lt=1)
    heavy_tail: bool = setting(True, "each ping's OS-normalised statistic is mapped onto its law in exponential noise "
                                     "through the K distribution whose shape fits its tail, per Doppler cell "
                                     "(detection/normalise.py): thresholds set for exponential noise then keep their "
                                     "false-alarm rate in spiky reverberation (OS CFAR only)", unit="")
    cfar: CfarSettings = setting(default_factory=CfarSettings, doc="the CFAR normaliser along range")
    heavy_tail_by_delay: bool = setting(
        True, "in a run of pings (the chain), heavy_tail's K shape is fitted per tile (a delay band x adjacent beams) "
              "on its exceedance counts pooled over pings (detection/normalise.py DelayShapes): the near, "
              "reverberation-limited delays are spikier than the far, noise-limited ones; the first ~3 pings, and a "
              "ping on its own, are fitted by beam group over all delays (heavy_tail_cells)", unit="")
    heavy_tail_tiles: DelayShapeSettings = setting(default_factory=DelayShapeSettings,
                                                   doc="the tiles and pings of heavy_tail_by_delay")
    heavy_tail_cells: int | None = setting(
        20000, "heavy_tail's K shape is fitted per group of adjacent beams holding at least this many cells (a narrow "
               "beam's reverberation is spikier than a wide one's: cells.py heavy_tail_statistic); 'off': one fit "
               "over all beams", unit="1", ge=10000)
    lobe_margin_db: float | None = setting(
        3.0, "drop a single-ping detection that is a sidelobe or grating-lobe image of a stronger echo of the same "
              "ping (detection/lobes.py cell_images: a beam outside its main lobe holds, at its travel time and "
              "Doppler, a stronger echo whose power times the array's beam pattern there, plus this margin, explains "
              "its own); 'off': every detection kept. Measured (study active-chain trial 1, CW 8 x 0.5 m at 1 kHz, "
              "14 clutter points, 1 h reverberation-only, benchmarks/bench_active_family.py): false confirmed tracks "
              "37 -> 6 at 3 dB (at a point's range elsewhere in cone 21 -> 0); the price: a second echo within "
              "the pattern's sidelobe level + margin of a stronger one at the same travel time is lost",
        unit="dB", ge=0, le=20)


#: half-width in u = cos(cone) of the search for the beam of largest power around a detection: half the main lobe's
#: half-width (first null) lambda / (N d) of the default array (16 elements half a wavelength apart: 0.125). Wide
#: enough for the shift of the peak of s near endfire (seed 9002: 0.032-0.037 in u), narrow enough that a weak
#: echo's cone is not moved onto a noise peak a beam or more away (at 0.125 the single-ping cone error at broadside
#: grew from 0.7 to 1.6 deg)
CONE_SEARCH_U = 0.0625


@dataclass(frozen=True, slots=True)
class PingCells:
    """The normalised cells of one ping.

    ``statistic`` (B, D, J) float32: s = |z|^2 / mu (mean 1 in noise) per beam, delay and Doppler cell;
    ``cone_deg`` (B,) beam cone angles (deg, 0 = ahead along the array axis); ``delay_s`` (D,) travel times
    from transmission to the array centre (s); ``doppler_hz`` (J,) Doppler cells (Hz; [0.] for an LFM) and
    ``range_rate_mps`` (J,) the bistatic range rates they stand for (m/s; NaN for an LFM, which measures none);
    ``time_s`` the transmit time (s); ``ping`` the ping's number; ``level`` (B, D, J) float32 the CFAR's noise
    estimate mu of each cell (so the power is s mu; None: not kept, cone angles then come from s); ``lobes`` the array
    and band whose sidelobe and grating-lobe images :func:`detect_ping` drops (None: none dropped); ``power``
    (B, D, J) float32 the matched-filter power before any notch (a CW's, kept for the lobe test only; None: s mu)."""

    ping: int
    time_s: float
    cone_deg: np.ndarray
    delay_s: np.ndarray
    doppler_hz: np.ndarray
    range_rate_mps: np.ndarray
    statistic: np.ndarray
    doppler_measured: bool
    level: np.ndarray | None = None
    lobes: LobeBand | None = None
    power: np.ndarray | None = None


@dataclass(frozen=True, slots=True)
class Detections(Rows):
    """Single-ping detections, arrays (n,): ``ping`` number, transmit ``time_s`` (s), ``cone_deg`` (deg),
    ``travel_time_s`` (s, to the array centre; an LFM's is biased by -f_d tau / B), ``doppler_hz`` (Hz) and
    ``range_rate_mps`` (bistatic, m/s; both NaN for an LFM), ``statistic`` (normalised s at the peak cell),
    ``beam``, ``delay_cell``, ``doppler_cell`` (indices into the ping's cells)."""

    ping: np.ndarray
    time_s: np.ndarray
    cone_deg: np.ndarray
    travel_time_s: np.ndarray
    doppler_hz: np.ndarray
    range_rate_mps: np.ndarray
    statistic: np.ndarray
    beam: np.ndarray
    delay_cell: np.ndarray
    doppler_cell: np.ndarray


def detection_threshold(settings: FrontEndSettings) -> float:
    """Threshold on s for the stated per-cell Pfa (the CFAR's closed form, detection/cfar.py).

    Parameters
    ----------
    settings : FrontEndSettings
        Its ``pfa`` and ``cfar``.

    Returns
    -------
    float
        Threshold on the normalised statistic s.
    """
    return cfar_threshold(settings.pfa, settings.cfar)


def matched_cells(samples: np.ndarray, fs_hz: float, waveform: Waveform, array: LineArray,
                  settings: FrontEndSettings) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Beams, then the matched filter (module doc): the raw square-law cells before the CFAR.

    Parameters
    ----------
    samples, fs_hz
        Complex baseband samples, ndarray (N, M), sample 0 at the transmit time, and their rate (Hz).
    waveform, array
        The transmitted pulse and the array (element count and spacing).
    settings : FrontEndSettings
        Beams, sound speed, CW bank.

    Returns
    -------
    power : ndarray (B, D, J), float32
        |z|^2 per beam, delay and Doppler cell (Pa^2 s^2 scale: unnormalised).
    delay_s : ndarray (D,)
        Delays (s).
    doppler_hz : ndarray (J,)
        Doppler cells (Hz; [0.] for an LFM).
    """
    x = np.asarray(samples)
    require(x.ndim == 2, f"a ping must be channels x samples, got shape {x.shape}")
    n, m = x.shape
    n_pulse = waveform.n_samples(fs_hz)
    require(m > n_pulse, f"the ping ({m} samples) is not longer than the pulse ({n_pulse} samples at {fs_hz:g} Hz)")
    n_fft = fft_length(m + n_pulse)
    spectra = np.fft.fft(x.astype(np.complex64, copy=False), n_fft, axis=1)
    beams = beamform_spectra(spectra, fs_hz, waveform.carrier_hz, array, cone_grid_deg(settings.beams),
                             settings.sound_speed_mps)
    if waveform.kind == "lfm":
        z = pulse_compress(beams, waveform.replica(fs_hz), m - n_pulse + 1)[..., None]
        delay, doppler = np.arange(m - n_pulse + 1) / fs_hz, np.zeros(1)
    else:
        series = np.fft.ifft(beams, axis=1)[:, :m]
        f_max = settings.max_range_rate_mps * waveform.carrier_hz / settings.sound_speed_mps
        hop = max(int(round(settings.cw_hop * n_pulse)), 1)
        z, delay, doppler = cw_doppler_bank(series, fs_hz, waveform, f_max, hop, settings.doppler_pad)
    return (z.real**2 + z.imag**2).astype(np.float32), delay, doppler


def cfar_stride(waveform: Waveform, fs_hz: float, delay_s: np.ndarray) -> int:
    """Delay cells per resolution cell (1 / B for an LFM, tau for a CW): the CFAR's reference stride, so that
    its references are about independent (detection/cfar.py).

    Parameters
    ----------
    waveform : Waveform
        The pulse.
    fs_hz : float
        Sample rate (Hz).
    delay_s : ndarray (D,)
        The delay cells (s).

    Returns
    -------
    int
        Stride >= 1 (cells).
    """
    step = float(delay_s[1] - delay_s[0]) if delay_s.size > 1 else 1.0 / fs_hz
    resolution = 1.0 / waveform.bandwidth_hz if waveform.kind == "lfm" else waveform.duration_s
    return max(int(round(resolution / step)), 1)


def ping_front_end(samples: np.ndarray, fs_hz: float, waveform: Waveform, array: LineArray,
                   settings: FrontEndSettings, *, time_s: float = 0.0, ping: int = 0,
                   direct_arrival_s: float | None = None, shapes: DelayShapes | None = None) -> PingCells:
    """One ping's normalised cells (module doc).

    Parameters
    ----------
    samples : ndarray (N, M)
        Complex baseband samples of the N elements (element 0 = the front) over the listening window, sample 0
        at the transmit time.
    fs_hz : float
        Sample rate (Hz).
    waveform : Waveform
        The transmitted pulse (its carrier is the baseband's).
    array : LineArray
        Element count (= N) and spacing (m).
    settings : FrontEndSettings
        Beams, CW bank, blanking, CFAR.
    time_s : float
        Transmit time (s), copied to the cells.
    ping : int
        The ping's number, copied to the cells.
    direct_arrival_s : float, optional
        Arrival of the direct blast at the array (s after transmit, |Tx - Rx| / c from the navigation): the samples
        before its end plus ``blast_guard_s`` are zeroed and no delay before it is searched (:func:`blast_gate_s`).
    shapes : DelayShapes, optional
        The run's K shapes by delay band and beam group (``heavy_tail_by_delay``): this ping's counts join them and
        its statistic is mapped by them; None: by this ping's own fit by beam group (:func:`heavy_tail_statistic`).

    Returns
    -------
    PingCells
        Normalised statistic (B, D, J) with its axes (cells before the blast's gate hold 0).
    """
    gate = blast_gate_s(settings, waveform, direct_arrival_s)
    power, delay, doppler = matched_cells(gated_samples(samples, fs_hz, gate), fs_hz, waveform, array, settings)
    keep = delay >= settings.blank_s
    require(bool(keep.any()), f"blank_s {settings.blank_s:g} s leaves no delay of the {delay[-1]:.3g} s window: "
                              "lower it")
    live = delay[keep] >= gate
    require(bool(live.any()), f"the direct blast (arrival {direct_arrival_s or 0.0:.3g} s from the navigation, plus "
                              f"the pulse and blast_guard_s) ends at {gate:.3g} s, after the {delay[-1]:.3g} s window: "
                              "check the navigation's source and array positions")
    y = np.asarray(np.moveaxis(power[:, keep][:, live], 1, -1), dtype=np.float32)
    mu = noise_estimate(y, settings.cfar, cfar_stride(waveform, fs_hz, delay))
    stat = np.zeros((power.shape[0], int(keep.sum()), power.shape[2]), np.float32)
    level = np.zeros_like(stat)
    s_live = np.divide(y, mu, out=np.zeros_like(y), where=mu > 0)
    if shapes is None or not settings.heavy_tail or settings.cfar.method != "os":
        s_live, _ = heavy_tail_statistic(s_live, settings)
    else:  # on the whole delay axis (the gated cells 0): the tiles stay put when the blast's gate moves
        whole = np.zeros(y.shape[:2] + (int(keep.sum()),), np.float32)
        whole[..., live] = s_live
        s_live = shapes.push(whole, delay[keep], settings.heavy_tail_cells)[0][..., live]
    stat[:, live] = np.moveaxis(s_live, -1, 1)
    level[:, live] = np.moveaxis(np.divide(y, s_live, out=mu.copy(), where=s_live > 0), -1, 1)  # s level = power
    rate = (doppler_to_range_rate(doppler, waveform.carrier_hz, settings.sound_speed_mps)
            if waveform.measures_doppler else np.full(doppler.shape, np.nan))
    return PingCells(int(ping), float(time_s), cone_grid_deg(settings.beams), delay[keep], doppler, rate, stat,
                     waveform.measures_doppler, level, lobe_band(waveform, array, settings))


def lobe_band(waveform: Waveform, array: LineArray, settings: FrontEndSettings) -> LobeBand | None:
    """The array and band whose lobes :func:`detect_ping` drops (detection/lobes.py), None when
    ``lobe_margin_db`` is not set; an image's travel time within the delay resolution (1 / B, a CW's pulse)."""
    if settings.lobe_margin_db is None:
        return None
    half = 0.5 * waveform.bandwidth_hz if waveform.kind == "lfm" else 0.0
    tol = 1.0 / waveform.bandwidth_hz if waveform.kind == "lfm" and waveform.bandwidth_hz > 0 else waveform.duration_s
    return LobeBand(array.elements, array.spacing_m, waveform.carrier_hz - half, waveform.carrier_hz + half,
                    settings.sound_speed_mps, tol, float(settings.lobe_margin_db))


def heavy_tail_statistic(stat: np.ndarray, settings: FrontEndSettings) -> tuple[np.ndarray, np.ndarray]:
    """The OS-normalised statistic (B, J, D) mapped per Doppler cell and group of adjacent beams through the K law
    of its fitted shape (detection/normalise.py :func:`k_shape_from_exceedance`, :func:`k_to_exponential`), and the
    shapes (B, J) (inf: exponential, left as it is; all inf when ``heavy_tail`` is off or the CFAR is CA).

    The beams are fitted in groups of at least ``heavy_tail_cells`` cells (:func:`shape_groups`), not all together:
    a narrow beam (broadside of a long array) holds fewer scatterers per cell than a wide one (near endfire), so its
    reverberation is spikier, and one shape for all beams let it through. Measured on study active-chain's trial 2
    (seed 2017; 32 elements x 0.5 m at 2.4 kHz, K reverberation +10 dB, 20 min reverberation-only,
    benchmarks/bench_active_family.py): 115 single-ping detections a ping, 60 % of them at cone 80-100 deg, with one
    shape for all beams.

    Parameters
    ----------
    stat : ndarray (B, J, D)
        s = y / mu of the searched cells.
    settings : FrontEndSettings
        ``heavy_tail``, ``heavy_tail_cells`` and the CFAR (N, k).

    Returns
    -------
    tuple
        (mapped statistic (B, J, D) float32, K shape per beam and Doppler cell (B, J)).
    """
    from sonartrack.detection.normalise import k_shape_from_exceedance, k_to_exponential

    shapes = np.full(stat.shape[:2], np.inf)
    if not settings.heavy_tail or settings.cfar.method != "os":
        return stat, shapes
    n, k = settings.cfar.n_reference, settings.cfar.rank
    out = np.array(stat, dtype=np.float32, copy=True)
    for group in shape_groups(stat.shape[0], stat.shape[2], settings.heavy_tail_cells):
        for j in range(stat.shape[1]):
            shapes[group, j] = k_shape_from_exceedance(stat[group, j], n, k)
            out[group, j] = k_to_exponential(stat[group, j], shapes[group.start, j], n, k)
    return out, shapes


def shape_groups(n_beams: int, n_delays: int, min_cells: int | None) -> list[slice]:
    """Adjacent beams in groups of at least ``min_cells`` cells of ``n_delays`` delays each (the last group takes
    the remainder; None or too few cells in all: one group)."""
    if min_cells is None or n_beams * n_delays < 2 * min_cells:
        return [slice(0, n_beams)]
    size = max(1, int(np.ceil(min_cells / max(n_delays, 1))))
    starts = list(range(0, n_beams, size))
    if n_beams - starts[-1] < size and len(starts) > 1:
        starts.pop()
    return [slice(a, b) for a, b in zip(starts, starts[1:] + [n_beams], strict=True)]


def blast_gate_s(settings: FrontEndSettings, waveform: Waveform, direct_arrival_s: float | None) -> float:
    """End of the blanked start of a ping (s): ``blank_s``, or the direct blast's end plus ``blast_guard_s`` where
    that is later (the blast arrives at ``direct_arrival_s`` = |Tx - Rx| / c and lasts one pulse).

    Parameters
    ----------
    settings : FrontEndSettings
        ``blank_s`` and ``blast_guard_s``.
    waveform : Waveform
        The pulse (its length).
    direct_arrival_s : float or None
        Arrival of the direct blast at the array (s after transmit; None: not known).

    Returns
    -------
    float
        Samples and delays before this time are not used (s).
    """
    if direct_arrival_s is None or settings.blast_guard_s is None:
        return float(settings.blank_s)
    return float(max(settings.blank_s, direct_arrival_s + waveform.duration_s + settings.blast_guard_s))


def gated_samples(samples: np.ndarray, fs_hz: float, gate_s: float) -> np.ndarray:
    """The ping with its samples before ``gate_s`` zeroed (a copy; the input is not changed).

    Why: the beamformer's block-wise steering (acoustics/active_beams.py) leaks a fraction ~1e-7 of each sample's
    power across the whole window, so a direct blast of ~170 dB re 1 uPa^2 (a towed source 150 m ahead of the array)
    leaves ~100 dB at every delay, as loud as the late reverberation: measured on the independent generator
    (tests/worlds/active_pings.py) 46 false single-ping detections a ping spread over 2-12 s, 32 false confirmed
    tracks an hour. No searched delay uses a sample before the gate (an echo at delay d fills d .. d + tau).

    Parameters
    ----------
    samples : ndarray (N, M)
        Complex baseband, sample 0 at the transmit time.
    fs_hz : float
        Sample rate (Hz).
    gate_s : float
        Samples before this time are zeroed (s).

    Returns
    -------
    numpy.ndarray
        (N, M) the gated samples.
    """
    n = min(int(np.floor(gate_s * fs_hz)), samples.shape[-1])
    if n <= 0:
        return samples
    x = np.array(samples, copy=True)
    x[..., :n] = 0
    return x


def _refine(log_s: np.ndarray, idx: tuple[np.ndarray, ...], axis: int) -> np.ndarray:
    """Offset (cells, in [-0.5, 0.5]) of a parabola's peak through the log statistic at idx -1, 0, +1 on ``axis``."""
    size = log_s.shape[axis]
    i = idx[axis]
    if size < 3:
        return np.zeros(i.shape)
    lo = list(idx)
    hi = list(idx)
    lo[axis] = np.clip(i - 1, 0, size - 1)
    hi[axis] = np.clip(i + 1, 0, size - 1)
    y0, y1, y2 = log_s[tuple(lo)], log_s[idx], log_s[tuple(hi)]
    den = y0 - 2.0 * y1 + y2
    ok = (den < 0) & (i > 0) & (i < size - 1)
    delta = np.where(ok, 0.5 * (y0 - y2) / np.where(ok, den, -1.0), 0.0)
    return np.clip(delta, -0.5, 0.5)


def _axis_value(grid: np.ndarray, position: np.ndarray) -> np.ndarray:
    """Values of an axis at fractional cell positions (linear between cells)."""
    return np.interp(position, np.arange(grid.size), grid)


def power_cone_deg(cells: PingCells, b, d, j, search_u: float = CONE_SEARCH_U) -> np.ndarray:
    """Cone angle (deg) of each peak at cells (b, d, j) from the beams' power (module doc).

    Among the beams whose direction cosine u = cos(cone) lies within ``search_u`` of the peak beam's, the beam of
    largest power |z|^2 = s mu at the peak's delay and Doppler is taken, and refined by a parabola through the log
    power of it and its two neighbours (offset within +-half a beam). Without ``cells.level`` the same is done on
    s alone within +-1 beam (the parabola of :func:`detect_ping`'s other axes).

    Parameters
    ----------
    cells : PingCells
        The ping's cells (``level`` the CFAR's mu, or None).
    b, d, j : int arrays (n,)
        Beam, delay and Doppler cell of each peak.
    search_u : float
        Half-width of the search in u (dimensionless).

    Returns
    -------
    numpy.ndarray
        (n,) cone angles (deg).
    """
    b, d, j = (np.asarray(i, np.int64) for i in (b, d, j))
    if not len(b):
        return np.zeros(0)
    s = cells.statistic
    power = s[:, d, j].astype(float) * (cells.level[:, d, j] if cells.level is not None else 1.0)  # (B, n)
    u = np.cos(np.deg2rad(np.asarray(cells.cone_deg, float)))
    width = search_u if cells.level is not None else 0.0
    near = np.abs(u[:, None] - u[b][None, :]) <= np.maximum(width, np.abs(np.diff(u)).max(initial=0.0) * 1.01)
    if cells.level is None:
        near &= np.abs(np.arange(len(u))[:, None] - b[None, :]) <= 1
    best = np.argmax(np.where(near, power, -np.inf), axis=0)
    log_p = np.log(np.maximum(power, 1e-30))[:, :, None]  # (B, n, 1): the parabola's (beam, peak, -) axes
    k = np.arange(len(b))
    offset = _refine(log_p, (best, k, np.zeros(len(b), np.int64)), 0)
    return _axis_value(np.asarray(cells.cone_deg, float), best + offset)


def detect_ping(cells: PingCells, threshold: float, guard_cells: int = 4) -> Detections:
    """:func:`detect_ping_flagged`'s detections without the lobe images (those kept when ``cells.lobes`` is None)."""
    det, image = detect_ping_flagged(cells, threshold, guard_cells)
    return Detections(**{f: np.asarray(getattr(det, f))[~image] for f in Detections.__slots__}) if image.any() else det


def detect_ping_flagged(cells: PingCells, threshold: float, guard_cells: int = 4) -> tuple[Detections, np.ndarray]:
    """The single-ping detections of ``cells``: local maxima with s >= ``threshold`` (module doc), and which of them
    are sidelobe or grating-lobe images of a stronger echo (detection/lobes.py :func:`cell_images`; none when
    ``cells.lobes`` is None): an image is for the detections table, not for tracking.

    Parameters
    ----------
    cells : PingCells
        One ping's normalised cells.
    threshold : float
        Threshold on the normalised statistic s (:func:`detection_threshold` for a stated Pfa).
    guard_cells : int
        Half-width of the neighbourhood along delay (the CFAR's guard cells).

    Returns
    -------
    tuple
        (Detections, one row per detection in beam, delay, Doppler order; (n,) bool, True for a lobe image).
    """
    from scipy.ndimage import maximum_filter

    s = cells.statistic
    peak = (s >= threshold) & (s == maximum_filter(s, size=(3, 2 * guard_cells + 1, 3), mode="nearest"))
    idx = np.nonzero(peak)
    log_s = np.log(np.maximum(s, 1e-30))
    b, d, j = (i.astype(float) + _refine(log_s, idx, ax) for ax, i in enumerate(idx))
    cone = power_cone_deg(cells, *idx)
    doppler = _axis_value(cells.doppler_hz, j) if cells.doppler_measured else np.full(b.shape, np.nan)
    rate = _axis_value(cells.range_rate_mps, j) if cells.doppler_measured else np.full(b.shape, np.nan)
    n = b.size
    det = Detections(np.full(n, cells.ping), np.full(n, cells.time_s), cone,
                     _axis_value(cells.delay_s, d), doppler, rate, s[idx].astype(float), idx[0], idx[1], idx[2])
    return det, cell_images(cells, det.beam, det.delay_cell, det.doppler_cell, det.cone_deg)

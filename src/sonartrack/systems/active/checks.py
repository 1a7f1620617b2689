"""Checks of the active chain's settings against the pings, before the first ping: the array's spacing, the memory.

Spacing (:func:`check_spacing`). A uniform line of elements d apart, steered to u_s = cos(cone), also answers
plane waves from u_s +- k lambda / d (grating lobes); one lies in the visible region |u| <= 1 for steering
directions |u_s| > lambda / d - 1, for every direction once d >= lambda. The shortest wavelength of the band,
lambda_min = c / (f_c + B / 2), sets the limit. A lobe places an echo (target or reverberation) in two beams,
each a contact at its own position, and the tracker confirms the lobes as targets. Measured on the default
scene, 30 min (seed 9101, not a study seed), simulated and processed at each spacing, confirmed tracks on a
target / false (the spacing in wavelengths at the carrier, then at the band's top): 0.5 (0.52 lambda_min) 2 / 2,
0.6 (0.62) 2 / 3, 0.75 (0.78) 2 / 5, 1 (1.03) 2 / 6, 2 (2.07) 2 / 10, 5 0 / 4, 10 0 / 0 (nothing confirmed, the
targets lost). Refused: d >= lambda_min, where every direction has a lobe and false tracks triple. Below it the
lobes reach only the directions within arccos(lambda_min / d - 1) of the axis, where the beams are widest and
the cone errors largest already (the default array, half a wavelength at the carrier, 0.52 lambda_min: 21 deg),
and the false tracks grow gradually (2, 3, 5 above): an array used above its design frequency still answers.
Refused too: an array shorter than half the longest wavelength, N d < lambda_max / 2, whose one beam covers
every direction (no bearing at all).

Memory (:func:`check_memory`). Settings asking for more than :data:`MEMORY_LIMIT_BYTES` are refused in one line
naming the largest array and the setting that shrinks it (as the passive chain's systems/passive/checks.py
``check_memory``): a beam count of 100 000 would otherwise fail half-way with numpy's MemoryError, a bug's
message.

With N elements, M samples a ping, an L-sample pulse, F = fft_length(M + L) frequency bins, B beams, D delay cells
(M - L + 1 for an LFM, (M - L) / hop + 1 for a CW) and J Doppler cells (1 for an LFM), P pings:

* beams and matched filter of one ping (detection/cells.py ``matched_cells``), the largest of its stages, which
  follow one another: the beams' spectra and their copies, 24 B F bytes (complex64); an LFM's pulse compression
  (the beams, the product and its complex128 inverse FFT, 32 B F, and the kept cells 8 B D) or a CW's bank (the
  beams and their inverse FFT 24 B F, the windows' FFTs 16 B D F_w with F_w = fft_length(2 L), the kept cells
  24 B D J); the normalisation (power, noise, statistic, level, padding) 36 B D J;
* the steering weights (acoustics/active_beams.py ``beamform_spectra``): C x B x N (C frequency chunks, more as
  the aperture (N - 1) d grows), built in complex128 and cast, 32 bytes each;
* the MFTD's threshold calibration (detection/ping_mftd.py): ``calibration_trials`` noise tiles of K frames x
  tile cells x J, float64, listed then stacked (16 bytes a cell), and its buffer of K pooled pings (8 bytes a
  cell);
* the B-scan kept for the picture: P x B x min(bscan_bins, D) float32.

Measured with tracemalloc on 16 elements, 6000 samples at 200 Hz (peak of pings 2-5, the calibration included),
against this estimate for 5 pings: LFM 61 beams 52 MB (estimate 63), 400 beams 108 MB (193), 2000 beams 539 MB
(804), 61 beams 5 m apart 69 MB (123); CW 61 beams 443 MB (527). The estimate is the larger: the needs are summed
(the B-scan and the MFTD's buffer are held while a ping is worked) and the stages' temporaries rounded up.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.errors import InputError
from sonartrack.core.memory import MEMORY_LIMIT_BYTES, refuse_over_limit  # noqa: F401  (the limit re-exported here)


def check_spacing(settings, table) -> None:
    """Refuse an element spacing whose grating lobes reach every direction, or an array too short for any bearing
    (module doc).

    Parameters
    ----------
    settings : ActiveSettings
        The checked settings (``elements``, ``spacing_m`` in m, ``sound_speed_mps`` in m/s).
    table : PingTable
        The pings (carrier and swept band, Hz).

    Raises
    ------
    InputError
        Naming the spacing, the wavelengths and the bound.
    """
    c, d, n = settings.sound_speed_mps, float(settings.spacing_m), int(settings.elements)
    half_band = 0.5 * np.where(np.asarray(table.kind) == "lfm", np.asarray(table.bandwidth_hz, float), 0.0)
    f_hi = float(np.max(np.asarray(table.fc_hz, float) + half_band))
    f_lo = float(np.min(np.maximum(np.asarray(table.fc_hz, float) - half_band, 1e-9)))
    lam_min, lam_max = c / f_hi, c / f_lo
    if d >= lam_min:
        raise InputError(f"--spacing {d:g} m is {d / lam_min:.3g} wavelengths at the band's top ({f_hi:g} Hz, "
                         f"{lam_min:.3g} m): every direction has a grating lobe, so each echo would be placed at two "
                         f"or more bearings (false tracks); give the array's element spacing in metres, below "
                         f"{lam_min:.3g} m (half a wavelength, {lam_min / 2:.3g} m, has none)")
    if n * d < 0.5 * lam_max:
        raise InputError(f"--spacing {d:g} m makes the {n}-element array {n * d:.3g} m long, less than half a "
                         f"wavelength at the band's bottom ({f_lo:g} Hz, {lam_max:.3g} m): it has no directivity, so "
                         f"no bearing; give the element spacing in metres (at least {0.5 * lam_max / n:.3g} m)")


def _steering_chunks(n_fft: int, fs_hz: float, elements: int, spacing_m: float, sound_speed_mps: float) -> int:
    """Frequency chunks C of ``beamform_spectra`` (its own rule: a chunk's phase error below STEERING_PHASE_RAD)."""
    from sonartrack.acoustics.active_beams import STEERING_PHASE_RAD

    half_aperture_s = (elements - 1) * spacing_m / (2.0 * sound_speed_mps)
    chunk = max(int(STEERING_PHASE_RAD / max(np.pi * half_aperture_s * fs_hz / n_fft, 1e-300)), 1)
    return -(-n_fft // chunk)


def _mftd_needs(settings, n_beams: int, n_delays: int, n_doppler: int, delay_step_s: float,
                period_s: float) -> list[tuple[float, str, str]]:
    """The MFTD's calibration tiles and buffer (module doc)."""
    from sonartrack.detection.ping_mftd import tile_plan

    m = settings.mftd
    pooled = max(n_delays // min(m.pool_cells, n_delays), 1)
    pooled_beams = max(n_beams // min(m.pool_beams, n_beams), 1)
    cell_m = settings.sound_speed_mps * min(m.pool_cells, n_delays) * delay_step_s
    margin = int(np.ceil(settings.max_range_rate_mps * max(m.frames - 1, 0) * period_s / cell_m)) + 1
    tile = tile_plan(pooled, m.tile_cells, margin)[0]
    cells = float(m.frames) * (tile[1] - tile[0]) * n_doppler
    return [(16.0 * m.calibration_trials * cells, f"the MFTD's threshold calibration ({m.calibration_trials} noise "
             f"tiles x {m.frames} pings x {tile[1] - tile[0]} cells x {n_doppler} Doppler cells)",
             "fewer [mftd] calibration_trials or tile_cells"),
            (8.0 * m.frames * pooled_beams * pooled * n_doppler, f"the MFTD's last {m.frames} pings ({pooled_beams} "
             f"pooled beams x {pooled} cells x {n_doppler} Doppler cells)", "fewer [front_end] beams or [mftd] frames")]


def memory_needs(settings, table, period_s: float | None) -> list[tuple[float, str, str]]:
    """The chain's largest working arrays for these pings: bytes, what sizes them, and the fix (module doc).

    Parameters
    ----------
    settings : ActiveSettings
        The checked settings (``elements`` and ``spacing_m`` set).
    table : PingTable
        The ping table (its first ping's samples, sample rate and pulse size the arrays; all pings alike).
    period_s : float or None
        The ping interval (s) of the MFTD, None when the MFTD does not run.

    Returns
    -------
    list of (float, str, str)
        Bytes (an estimate), what needs them (with the settings), how to need less.
    """
    from sonartrack.acoustics.matched_filter import fft_length

    fs, m, w = float(table.fs_hz[0]), int(table.samples[0]), table.waveform(0)
    n, b, fe = int(settings.elements), int(settings.front_end.beams), settings.front_end
    n_pulse = w.n_samples(fs)
    n_fft = fft_length(m + n_pulse)
    if w.kind == "lfm":
        d, j, step = max(m - n_pulse + 1, 1), 1, 1.0 / fs
        filt = 32.0 * b * n_fft + 8.0 * b * d
    else:
        hop = max(int(round(fe.cw_hop * n_pulse)), 1)
        d, step = max((m - n_pulse) // hop + 1, 1), hop / fs
        n_w = fft_length(fe.doppler_pad * n_pulse)
        j = max(int(2 * settings.max_range_rate_mps * w.carrier_hz / settings.sound_speed_mps * n_w / fs) + 1, 1)
        filt = 24.0 * b * n_fft + 16.0 * b * d * n_w + 24.0 * b * d * j
    c = _steering_chunks(n_fft, fs, n, float(settings.spacing_m), settings.sound_speed_mps)
    # the stages of a ping follow one another: its need is the largest stage's (beams; matched filter; normalisation)
    needs = [(max(24.0 * b * n_fft, filt, 36.0 * b * d * j), f"one ping's beams and matched filter ({b} [front_end] "
              f"beams x {n_fft} frequency bins of {m} samples, {d} delay x {j} Doppler cells)",
              "fewer [front_end] beams, or shorter pings"),
             (32.0 * c * b * n, f"the beams' steering weights ({c} frequency chunks x {b} [front_end] beams x {n} "
              f"elements; the chunks grow with the aperture, {n - 1} x {settings.spacing_m:g} m)",
              "fewer [front_end] beams, or check --spacing (metres)"),
             (4.0 * len(table) * b * min(settings.bscan_bins, d), f"the B-scan ({len(table)} pings x {b} [front_end] "
              f"beams x {min(settings.bscan_bins, d)} bins)", "fewer [front_end] beams or a lower bscan_bins, or "
                                                               "fewer pings a run")]
    if period_s is not None:
        needs += _mftd_needs(settings, b, d, j, step, period_s)
    return needs


def check_memory(settings, table, period_s: float | None) -> None:
    """Refuse settings whose working arrays (:func:`memory_needs`) together exceed :data:`MEMORY_LIMIT_BYTES`,
    naming the largest and how to shrink it.

    Parameters
    ----------
    settings : ActiveSettings
        The checked settings.
    table : PingTable
        The ping table.
    period_s : float or None
        The MFTD's ping interval (s), None without the MFTD.

    Raises
    ------
    InputError
        Naming the array, its size in GB and the settings that make it.
    """
    refuse_over_limit(memory_needs(settings, table, period_s), "the active chain's")

"""What a CW's contacts tell the tracker: their travel-time error, their range rate's error, their own clutter density.

A CW's delay is known to its cells (a quarter pulse; the MFTD's pooled pair), not to the 10 ms P4 states for its
pulse; its range rate to the Doppler bank's filter step; and it gives ~100 times fewer false contacts than the LFM
the tracker's clutter density (1e-6 per m^2) was tuned on, so the IMM-IPDA takes the density of its own contacts
(systems/active/run.py ``ContactTracker``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from sonartrack.systems.active.settings import ActiveSettings


def cw_clutter_area(cells, sound_speed_mps: float) -> float | None:
    """The area a CW's contacts can fall in, pi (c t_max / 2)^2 (the bistatic ellipse of the longest delay, the
    baseline neglected), for :class:`ContactTracker`'s clutter density; None when the detections or cells measure
    no range rate (an LFM keeps the tuned setting).

    Parameters
    ----------
    cells : PingCells or Detections
        With ``range_rate_mps`` and ``delay_s`` (cells) or ``travel_time_s`` (detections).
    sound_speed_mps : float
        Sound speed c (m/s).

    Returns
    -------
    float or None
        Area (m^2).
    """
    rate = np.asarray(cells.range_rate_mps, float)
    t = np.asarray(getattr(cells, "delay_s", getattr(cells, "travel_time_s", np.zeros(0))), float)
    if not rate.size or not np.isfinite(rate).all() or not t.size:
        return None
    return float(np.pi * (sound_speed_mps * t.max() / 2.0) ** 2)


def cw_contact_errors(settings: ActiveSettings, delay_s):
    """The contacts' input errors with the travel-time error of a CW's delay cells: the larger of the setting and
    (cells pooled per detection) x (cell step) / sqrt(12) (uniform within the cell; pooled: the MFTD's pool_cells).
    Measured on the default scene as CW (seed 9101, 900 s): median |delay offset| 0.064 s single-ping (cell step
    0.25 s: sd 0.072 s), 0.22 s MFTD (pooled pair: 0.14 s) against P4's 0.01 s, with which no CW track was formed.

    Parameters
    ----------
    settings : ActiveSettings
        The chain (its contacts' errors, detector and MFTD pooling).
    delay_s : array
        The CW cells' delays (s), evenly spaced.

    Returns
    -------
    ContactSettings
        ``settings.contacts`` with ``sigma_time_s`` raised where the cells are coarser.
    """
    d = np.asarray(delay_s, float)
    step = float(d[1] - d[0]) if d.size > 1 else 0.0
    pool = settings.mftd_settings().pool_cells if settings.detector == "mftd" else 1
    sd = max(float(settings.contacts.sigma_time_s), pool * step / np.sqrt(12.0))
    return settings.contacts.model_copy(update={"sigma_time_s": sd})


def cw_rate_sd_mps(waveform, fs_hz: float, doppler_pad: int, sound_speed_mps: float) -> float:
    """Standard deviation of a measured range rate: the larger of the CW Doppler bank's filter step and its
    resolution cell 1 / tau, in range rate, over sqrt(12) (the echo's peak falls anywhere in the main lobe of the
    filter nearest it; zero-padded filters, 1 / (pad tau) apart, share that lobe and measure it no better), 1 m/s
    (unused) for an LFM. Measured on the default scene as CW (seed 1, 1 h, MFTD detections within 0.6 s and 8 deg
    of a target): sd 0.29 m/s about the true range rate for the approacher (the resolution cell's 1 m/s / sqrt(12)
    = 0.29; the filter step's 0.14), 4-17 % of the targets' detections off by more than 1 m/s.

    Parameters
    ----------
    waveform : Waveform or WaveformSettings
        The pulse (kind, duration_s, carrier_hz).
    fs_hz : float
        Sample rate (Hz).
    doppler_pad : int
        The bank's zero-padding factor (acoustics/matched_filter.py).
    sound_speed_mps : float
        Sound speed c (m/s).

    Returns
    -------
    float
        Standard deviation (m/s).
    """
    from sonartrack.acoustics.matched_filter import doppler_to_range_rate, fft_length
    from sonartrack.systems.active.run import rate_sd_of

    if waveform.kind != "cw":
        return rate_sd_of([np.nan])
    n = max(int(round(waveform.duration_s * fs_hz)), 1)
    step_hz = max(fs_hz / fft_length(doppler_pad * n), 1.0 / waveform.duration_s)
    return rate_sd_of(doppler_to_range_rate(np.array([0.0, step_hz]), waveform.carrier_hz, sound_speed_mps))

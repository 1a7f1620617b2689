"""What a CW's contacts tell the tracker: their travel-time error, their range rate's error, their own clutter density.

A CW's delay is known to its resolution cell, the pulse length tau (the matched filter's triangle is 2 tau wide at
its base), not to the 10 ms P4 states for its pulse; its range rate to the Doppler bank's resolution cell; and it
gives ~100 times fewer false contacts than the LFM the tracker's clutter density (1e-6 per m^2) was tuned on, so the
IMM-IPDA takes the density of its own contacts (systems/active/run.py ``ContactTracker``). An MFTD detection names,
at its ping, a cell of its pooled block: where the ping's own echo peaks there (:func:`cw_peaked`) the peak measures
it, elsewhere the cell is anywhere in the echo's response and its contacts state that (:func:`cw_unpeaked_errors`,
:func:`cw_form_contacts`). Measured with benchmarks/bench_cw_contacts.py.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from sonartrack.systems.active.contacts import ContactSettings
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
    """The contacts' input errors with the travel-time error of a CW's echo: the largest of the setting, (cells
    pooled per detection) x (cell step) / sqrt(12) (uniform within the cell; pooled: the MFTD's pool_cells) and the
    pulse length tau / sqrt(12), tau = cell step / ``cw_hop``: a CW's matched filter answers an echo with a triangle
    2 tau wide at its base (its delay resolution cell is tau), and at a ping where the MFTD holds the echo on its
    earlier pings the cell it names is anywhere in that cell. Measured (benchmarks/bench_cw_contacts.py, default scene
    as CW, seed 1, 1 h, MFTD detections near the 4 strong targets, 176): travel-time error sd 0.30 s (mean +0.10 s;
    0.17 s for the 118 with a single-ping peak at that ping, 0.45 s for the 60 without), against 0.14 s stated by
    the pooled pair (error / stated sd 1.4-2.7 per target, > 3 for 6-31 % of them); tau / sqrt(12) = 0.29 s.
    Earlier (seed 9101, 900 s): median |delay offset| 0.064 s single-ping, 0.22 s MFTD, against P4's 0.01 s, with
    which no CW track was formed.

    Parameters
    ----------
    settings : ActiveSettings
        The chain (its contacts' errors, detector, MFTD pooling and the front end's ``cw_hop``).
    delay_s : array
        The CW cells' delays (s), evenly spaced.

    Returns
    -------
    ContactSettings
        ``settings.contacts`` with ``sigma_time_s`` raised where the echo's delay is known worse.
    """
    d = np.asarray(delay_s, float)
    step = float(d[1] - d[0]) if d.size > 1 else 0.0
    pool = settings.mftd_settings().pool_cells if settings.detector == "mftd" else 1
    tau = step / float(settings.front_end_settings().cw_hop)
    sd = max(float(settings.contacts.sigma_time_s), pool * step / np.sqrt(12.0), tau / np.sqrt(12.0))
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


def cw_peaked(det, single, beams: int, delay_cells: int, doppler_cells: int):
    """One ping's MFTD detections measured by that ping's own echo: each takes the cone, travel time, Doppler and
    range rate of the strongest single-ping peak (detection/cells.py ``detect_ping``) within ``beams``,
    ``delay_cells`` and ``doppler_cells`` of its cell, where there is one (its statistic, the MFTD's, kept).

    Why. The MFTD detects a target from its last K pings and names, at this ping, the cell of its pooled block
    that holds the block's maximum (detection/ping_mftd.py): where this ping's echo is weak that cell is any
    of the block's. Measured (benchmarks/bench_cw_contacts.py, default scene as CW, seed 1, 1 h, the 176 MFTD
    detections near the 4 strong targets): with a single-ping peak at their ping (118) the errors had sd 0.17 s,
    1.1 deg (cone x sin cone), 0.37 m/s; without (60) 0.45 s, 3.1 deg, 0.69 m/s; and of the 18 false MFTD
    detections 16 had no peak. Not wired into the chain (systems/active/run.py): with it, :func:`cw_form_contacts`
    and :func:`cw_merge_echoes` (benchmarks/bench_cw_held.py, default scene as CW, 1 h, delay_guard 0) the held % of
    detectable pings went 90/75/94/84 -> 77/71/93/83 (seed 1, false targets 1 -> 1) and 86/80/93/77 -> 88/75/90/77
    (seed 2, 2 -> 1): the tracker, tuned on the chain as it is, did not gain from the truer errors.

    Parameters
    ----------
    det, single : Detections
        The MFTD's and the single-ping detections of one ping (beam, delay and Doppler cells on the same axes).
    beams, delay_cells, doppler_cells : int
        Half-widths of the search about each MFTD cell (the MFTD's pooled block: pool_beams, pool_cells; one
        Doppler resolution cell).

    Returns
    -------
    tuple
        (Detections with the peaks' measurements where found, (n,) bool True there).
    """
    n = len(det)
    peaked = np.zeros(n, bool)
    if not n or not len(single):
        return det, peaked
    near = ((np.abs(np.asarray(det.beam)[:, None] - np.asarray(single.beam)[None, :]) <= beams)
            & (np.abs(np.asarray(det.delay_cell)[:, None] - np.asarray(single.delay_cell)[None, :]) <= delay_cells)
            & (np.abs(np.asarray(det.doppler_cell)[:, None] - np.asarray(single.doppler_cell)[None, :])
               <= doppler_cells))
    peaked = near.any(axis=1)
    best = np.argmax(np.where(near, np.asarray(single.statistic, float)[None, :], -np.inf), axis=1)
    fields = {}
    for name in ("cone_deg", "travel_time_s", "doppler_hz", "range_rate_mps", "beam", "delay_cell", "doppler_cell"):
        own, peak = np.asarray(getattr(det, name)), np.asarray(getattr(single, name))
        fields[name] = np.where(peaked, peak[best], own)
    return type(det)(**{f: fields.get(f, getattr(det, f)) for f in det.__dataclass_fields__}), peaked


def cw_unpeaked_errors(contacts: ContactSettings, tau_s: float, elements: int, spacing_m: float,
                       carrier_hz: float, sound_speed_mps: float) -> ContactSettings:
    """The input errors of a CW detection with no echo peak at its ping (:func:`cw_peaked`): its cell is anywhere in
    the echo's response, the travel time uniform over the matched filter's base 2 tau (sd 2 tau / sqrt(12)), the
    direction cosine over the main lobe between its nulls, 2 c / (N d f_c) (sd that / sqrt(12), the cone's
    1 / sin cone growth then ContactSettings'). Measured (as :func:`cw_peaked`): sd 0.45 s and 3.1 deg x sin cone
    against 0.58 s and 4.1 deg x sin cone here (16 elements half a wavelength apart, tau = 1 s).

    Parameters
    ----------
    contacts : ContactSettings
        The peaked detections' errors (held as a floor).
    tau_s : float
        Pulse length (s).
    elements : int
        Array elements N.
    spacing_m, carrier_hz, sound_speed_mps : float
        Element spacing d (m), carrier f_c (Hz), sound speed c (m/s).

    Returns
    -------
    ContactSettings
        ``contacts`` with ``sigma_time_s`` and ``sigma_cone_deg`` (at broadside) raised.
    """
    lobe_u = 2.0 * sound_speed_mps / (elements * spacing_m * carrier_hz)
    cone_deg = float(np.rad2deg(np.arcsin(min(lobe_u / np.sqrt(12.0), 1.0))))
    floor = float(np.rad2deg(contacts.cone_sigma_rad(None)))
    return contacts.model_copy(update={"sigma_time_s": max(contacts.sigma_time_s, 2.0 * tau_s / np.sqrt(12.0)),
                                       "sigma_cone_deg": max(cone_deg, floor)})


def cw_form_contacts(det, peaked, ping_time_s, geometry, sound_speed_mps: float, peaked_errors: ContactSettings,
                     unpeaked_errors: ContactSettings, beam_step_deg: float | None = None, ping_numbers=None):
    """contacts.py's ``form_contacts`` of one ping's CW detections, those with an echo peak at the ping with
    ``peaked_errors``, the others with ``unpeaked_errors`` (:func:`cw_unpeaked_errors`); ``detection`` the row of
    ``det`` each contact came from, rows in ``det``'s order (side +1 then -1 of each).

    Returns
    -------
    Contacts
        As ``form_contacts``.
    """
    from dataclasses import replace

    from sonartrack.systems.active.contacts import Contacts, form_contacts

    peaked = np.asarray(peaked, bool)
    parts = []
    for rows, errors in ((np.nonzero(peaked)[0], peaked_errors), (np.nonzero(~peaked)[0], unpeaked_errors)):
        if len(rows):
            sub = type(det)(**{f: np.asarray(getattr(det, f))[rows] for f in det.__dataclass_fields__})
            c = form_contacts(sub, ping_time_s, geometry, sound_speed_mps, errors, beam_step_deg, ping_numbers)
            parts.append(replace(c, detection=rows[c.detection]))
    c = Contacts.concat(parts)
    return c.rows(np.lexsort((-c.side, c.detection))) if len(c) else c


def cw_merge_echoes(det, cone_deg_of_beams, delay_cells: int, lobe_u: float, doppler_cells: int, group=None):
    """One detection per echo: of a ping's CW detections within one echo's response of each other, only the
    first in the order (``group`` ascending, then statistic descending) is kept.

    An echo's response is a triangle 2 tau wide at its base in delay (``delay_cells``: tau in cells), the main
    lobe between its nulls in direction cosine (``lobe_u`` = c / (N d f_c) each side) and the Doppler filter's
    main lobe and first sidelobes (``doppler_cells`` filters each side); the single-ping peak search
    (detection/cells.py ``detect_ping``: +-1 beam) finds a second maximum of s = y / mu in it where mu differs from
    beam to beam. Measured (benchmarks/bench_cw_contacts.py, default scene as CW, seed 1): 23 of the tracked
    detections near a target shared their ping and target with a stronger one, 2-4 beams (0-10 deg) from it, most at
    the same delay and Doppler cell and the same cone (the cone is the strongest beam's: both name it); merged
    (single-ping ones, then the tracked ones, the MFTD's preferred) 23 -> 5, Pd unchanged (57 %), false 50 -> 44 in
    120 pings. Not wired into the chain (systems/active/run.py): with it alone the held % of detectable pings
    (benchmarks/bench_cw_held.py, 1 h, delay_guard 0) went 90/75/94/84 -> 90/72/94/84 (seed 1, false targets 1 -> 1)
    and 86/80/93/77 -> 86/79/90/77 (seed 2, 2 -> 2): within a seed's scatter.

    Parameters
    ----------
    det : Detections
        One ping's detections (beam, delay and Doppler cells).
    cone_deg_of_beams : array (B,)
        The beams' cone angles (deg).
    delay_cells, doppler_cells : int
        Half-widths of an echo's response in delay and Doppler cells.
    lobe_u : float
        Half-width of the main lobe in direction cosine.
    group : array (n,), optional
        Preference before the statistic (lower first; e.g. 0 for the MFTD's, 1 for single-ping detections, whose
        statistics are on other scales).

    Returns
    -------
    numpy.ndarray
        (n,) bool, True for the detections kept.
    """
    n = len(det)
    keep = np.ones(n, bool)
    if n < 2:
        return keep
    u = np.cos(np.deg2rad(np.asarray(cone_deg_of_beams, float)))[np.asarray(det.beam, np.int64)]
    g = np.zeros(n) if group is None else np.asarray(group, float)
    d, j = np.asarray(det.delay_cell, np.int64), np.asarray(det.doppler_cell, np.int64)
    same = ((np.abs(d[:, None] - d[None, :]) <= delay_cells) & (np.abs(j[:, None] - j[None, :]) <= doppler_cells)
            & (np.abs(u[:, None] - u[None, :]) <= lobe_u))
    for i in np.lexsort((-np.asarray(det.statistic, float), g)):
        if keep[i]:
            same_i = same[i].copy()
            same_i[i] = False
            keep[same_i] = False
    return keep


def cw_echo_window(settings: ActiveSettings, waveform) -> tuple[int, float, int]:
    """(delay cells, direction-cosine half-width, Doppler filters) of one echo's response for
    :func:`cw_merge_echoes`: tau in delay cells (1 / ``cw_hop``), the main lobe to its nulls c / (N d f_c), and
    the Doppler filter's main lobe and first sidelobe (1.5 resolution cells, ``doppler_pad`` filters each)."""
    fe = settings.front_end_settings()
    lobe_u = settings.sound_speed_mps / (int(settings.elements) * float(settings.spacing_m) * waveform.carrier_hz)
    return max(int(round(1.0 / fe.cw_hop)), 1), float(lobe_u), int(np.ceil(1.5 * fe.doppler_pad))


def detection_rows(det, keep):
    """The rows ``keep`` (bool mask or indices) of a detections record."""
    return type(det)(**{f: np.asarray(getattr(det, f))[keep] for f in det.__dataclass_fields__})


#: Doppler resolution cells (c / (f_c tau) m/s each) of the range-rate window about a still point's hidden echo in
#: which its skirt and sidelobe images fall (measured, study active-chain trial 15, 2.4 kHz, tau 1 s: the contacts
#: near a TS 30 dB point 0-1.24 m/s = 0-2 cells off its range rate; trial 1, 1 kHz: 1.5-2.4 m/s = 1-1.6 cells)
RIDGE_IMAGE_CELLS = 2.5


def cw_ridge_window(waveform, sound_speed_mps: float) -> tuple[float, float] | None:
    """(bistatic range m, range rate m/s) about a still point's echo hidden by the ridge notch within which a contact
    is its skirt or a sidelobe image (detection/clutter_map.py ``echo_images``): one pulse length in travel time,
    c tau (the CW ambiguity's delay extent), and :data:`RIDGE_IMAGE_CELLS` Doppler resolution cells; None for an LFM.

    Parameters
    ----------
    waveform : Waveform or WaveformSettings
        The pulse (kind, duration_s, carrier_hz).
    sound_speed_mps : float
        Sound speed c (m/s).

    Returns
    -------
    tuple of float or None
        (r_B half-width m, range-rate half-width m/s).
    """
    if waveform.kind != "cw":
        return None
    c, tau = float(sound_speed_mps), float(waveform.duration_s)
    return c * tau, RIDGE_IMAGE_CELLS * c / (float(waveform.carrier_hz) * tau)

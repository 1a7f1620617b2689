"""The track system's files: the contacts or peaks read in, the track tables written out (atomically).

=====================  ==========================================================================================
tracks.csv             ``--contacts``: time_s, track_id, status (confirmed / tentative), existence, x_m, y_m,
                       vx_mps, vy_mps, sd_x_m, sd_y_m, mode_prob_<j> per IMM mode; a row per live track per scan
bearing_tracks.csv     ``--peaks``: time_s, track_id, bearing_deg, bearing_rate_deg_s, bearing_std_deg, strength,
                       confirmed; a row per live track per scan
=====================  ==========================================================================================

The readers are io/contacts.py and io/peaks.py (with their checks); the tables are the tracks'
``to_frame()``.
"""

from __future__ import annotations

from pathlib import Path

from sonartrack.systems.track.settings import ContactsTrackSettings

CONTACT_TRACKS_CSV = "tracks.csv"
PEAK_TRACKS_CSV = "bearing_tracks.csv"


def read_contacts_file(path, settings: ContactsTrackSettings, *, nav=None):
    """Read a contacts file, Cartesian or raw bistatic (with its navigation file), with the system's input errors.

    Parameters
    ----------
    path : path-like
        Contacts CSV/Parquet: time_s, x_m, y_m [+ var_x_m2, var_y_m2, cov_xy_m2] or raw bistatic time_s,
        travel_time_s, bearing_deg.
    settings : ContactsTrackSettings
        ``default_sigma_m`` (m) for Cartesian contacts without covariances; ``bistatic`` for raw contacts.
    nav : path-like, optional
        Navigation CSV/Parquet of raw bistatic contacts (Tx and Rx positions in m, array heading in deg).

    Returns
    -------
    Contacts
        Times (s), positions (m) and covariances (m^2), sorted by time.
    """
    from sonartrack.io.contacts import read_contacts

    b = settings.bistatic
    return read_contacts(path, nav_path=nav, default_sigma_m=settings.default_sigma_m, bistatic_errors=b.errors(),
                         sound_speed_mps=b.sound_speed_mps, max_range_m=b.max_range_m)


def read_peaks_file(path):
    """Read a bearing peaks CSV (time_s, bearing_deg, amplitude).

    Parameters
    ----------
    path : path-like
        The peaks file, as ``sonartrack bearings`` writes it.

    Returns
    -------
    PeakRecord
        Peak times (s), cone angles (deg) and amplitudes.
    """
    from sonartrack.io.peaks import read_peaks_csv

    return read_peaks_csv(path)


def write_contact_tracks(result, out) -> Path:
    """Write the tracks of ``result`` (a :class:`~sonartrack.systems.track.run.ContactTrackResult`, what
    :func:`~sonartrack.systems.track.run.run_contacts` returned) as ``tracks.csv`` in the existing output folder
    ``out``; returns the file's path."""
    from sonartrack.io.atomic import write_csv

    return write_csv(result.tracks.to_frame(), Path(out) / CONTACT_TRACKS_CSV)


def write_peak_tracks(result, out) -> Path:
    """Write the tracks of ``result`` (a :class:`~sonartrack.systems.track.run.PeakTrackResult`, what
    :func:`~sonartrack.systems.track.run.run_peaks` returned) as ``bearing_tracks.csv`` (6 significant digits) in the
    existing output folder ``out``; returns the file's path."""
    from sonartrack.io.atomic import write_csv

    return write_csv(result.tracks.to_frame(), Path(out) / PEAK_TRACKS_CSV, float_format="%.6g")

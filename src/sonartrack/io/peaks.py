"""Bearing-peak files: ``time_s, bearing_deg, amplitude``, one row per cross-correlation peak.

Written by ``sonartrack bearings`` and read by ``sonartrack track --peaks``; bearings are cone angles
(0..180 deg from the array axis), the record type is :class:`sonartrack.acoustics.xcorr_bearing.PeakRecord`.

Checks (io/tables.py, one line each): the shared file checks; times sorted (peaks of one window share a
time); no row repeated; bearings cone angles in [0, 180] deg and not radians (all within 2 pi);
amplitudes in [0, :data:`MAX_AMPLITUDE`] (the bearings command writes normalised correlation x 30000).
"""

from __future__ import annotations

from pathlib import Path

from sonartrack.acoustics.xcorr_bearing import PeakRecord
from sonartrack.io.atomic import write_csv
from sonartrack.io.tables import check_no_duplicate_rows, check_not_radians, numeric_column, read_timed_table

PEAK_COLUMNS = ["time_s", "bearing_deg", "amplitude"]
#: largest peak amplitude taken (33 x the 30000 of a perfect normalised correlation: another scale beyond it)
MAX_AMPLITUDE = 1e6


def write_peaks_csv(path, record: PeakRecord) -> Path:
    """Write a peaks file ``time_s, bearing_deg, amplitude`` (atomic write).

    Parameters
    ----------
    path : str or path-like
        Output CSV file.
    record : PeakRecord
        Peak times (s), cone angles (deg, 0..180 from the array axis) and amplitudes.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    import pandas as pd

    return write_csv(pd.DataFrame({"time_s": record.time_s, "bearing_deg": record.bearing_deg,
                                   "amplitude": record.amplitude}), path, float_format="%.6g")


def read_peaks_csv(path) -> PeakRecord:
    """Read and check a peaks file (module docstring).

    Parameters
    ----------
    path : str or path-like
        CSV or Parquet file with ``time_s, bearing_deg, amplitude``.

    Returns
    -------
    PeakRecord
        Times (s), cone angles (deg, 0..180 from the array axis), amplitudes (normalised correlation x 30000).

    Raises
    ------
    InputError
        For a missing, empty or bad file (one line naming the problem).
    """
    what = "peaks"
    df, t = read_timed_table(path, what, PEAK_COLUMNS)
    b = numeric_column(df, "bearing_deg", what, path, lo=0.0, hi=180.0,
                       fix="cone angles 0..180 deg from the array axis; compass bearings?")
    check_not_radians(b, "bearing_deg", what, path)
    a = numeric_column(df, "amplitude", what, path, lo=0.0, hi=MAX_AMPLITUDE,
                       fix="correlation peak amplitudes, normalised correlation x 30000")
    check_no_duplicate_rows({"time_s": t, "bearing_deg": b, "amplitude": a}, what, path)
    return PeakRecord(t, b, a)

"""TMA input files (bearings, ownship navigation) and the target-solution table, shared by every
``sonartrack tma`` method (sequential EKF/MGEKF/IMM and batch ML/EM-MAP).

Bearings file (CSV or Parquet; ``#`` comment lines allowed in CSV), one row per measurement:

* ``time_s`` (s, strictly increasing), ``bearing_deg`` (degrees clockwise from north, true, of the
  target from the ownship; any of -180..180 or 0..360);
* optional ``frequency_hz`` (received frequency of the tracked line, Hz, > 0; an empty cell means
  no frequency at that time);
* optional ``snr_db`` (signal-to-noise ratio, dB; used by the batch methods);
* optional ``bearing_sd_deg`` (each bearing's noise standard deviation, degrees, > 0 and at most
  :data:`MAX_BEARING_SD_DEG`; e.g. a line array's, which grows towards endfire): the ML and the record's checks
  weigh each bearing by it, the single-sd methods use the sd of the same information (tma/solve.py
  ``with_record_sd``); it replaces ``--sigma-bearing-deg`` (giving both is refused).

Ownship file (CSV or Parquet): ``time_s`` (s, strictly increasing), ``x_m``, ``y_m`` (m, x east, y
north, in the same local frame as the solution). Positions are interpolated linearly to the
measurement times, velocities from central differences of the samples; that the file covers the
measurements is checked by the solver (tma/records.py ``check_coverage``).

Checks with one-line errors: missing or non-numeric values, unsorted or repeated times, columns in
the wrong unit (``bearing_rad``, ``x_km``, ``time_ms`` ...), bearings beyond +-360 deg, bearings that
all lie within +-2 pi (radians written in a degrees column; switch off with ``check_radians=False``
for a target genuinely within 6 deg of north), frequencies outside (0, 1 MHz], SNRs beyond +-200 dB,
positions beyond +-1e7 m, an ownship moving faster than 40 m/s (about 78 kn: kilometres or minutes
written as metres or seconds).

Solution table (CSV), one row per solution time: the columns of tma/solution_table.py (``time_s, x_m,
y_m, vx_mps, vy_mps, course_deg, speed_kn, range_m, bearing_deg`` and their ``*_std`` standard
deviations), written atomically.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.errors import InputError
from sonartrack.io.atomic import write_csv
from sonartrack.io.records import BearingRecord, OwnshipTrack, TmaSolution
from sonartrack.io.tables import (
    MAX_POSITION_M,
    cell_text,
    check_not_radians,
    check_platform_speed,
    check_range,
    numeric_column,
    read_timed_table,
)
from sonartrack.tma.solution_table import solution_columns

BEARING_COLUMNS = ["time_s", "bearing_deg"]
OWNSHIP_COLUMNS = ["time_s", "x_m", "y_m"]
#: largest received frequency taken (Hz): passive sonar tonals are far below; beyond it the column is another unit
MAX_FREQUENCY_HZ = 1e6
#: largest |SNR| taken (dB)
SNR_LIMIT_DB = 200.0
#: largest per-bearing sd taken (deg): the settings' limit for one sd (tma/settings.py ``sigma_bearing_deg``) is 30;
#: a line array's sd at endfire may exceed it, so the column takes up to 90 (beyond that a bearing says nothing)
MAX_BEARING_SD_DEG = 90.0


def _optional_column(df, col: str, what: str, path) -> np.ndarray:
    """A column where empty cells are allowed (NaN) but text or infinities are not."""
    import pandas as pd

    raw = df[col]
    values = pd.to_numeric(raw, errors="coerce").to_numpy(dtype=float)
    bad = (np.isnan(values) & raw.notna().to_numpy()) | np.isinf(values)
    if bad.any():
        row = int(np.argmax(bad))
        raise InputError(f"{what} file {path}: column '{col}' has a non-numeric value at data row {row + 1} "
                         f"({cell_text(raw.iloc[row])}): fix it or leave the cell empty")
    return values


def read_bearings(path, *, check_radians: bool = True) -> BearingRecord:
    """Read and validate a bearings file (module docstring) into SI units.

    Parameters
    ----------
    path : str or path-like
        CSV or Parquet file: ``time_s, bearing_deg[, frequency_hz][, snr_db][, bearing_sd_deg]``.
    check_radians : bool, default True
        Refuse a bearing column that looks like radians (switch off for a target within 6 deg of north).

    Returns
    -------
    BearingRecord
        Times (s), bearings (rad, clockwise from north, wrapped to (-pi, pi]), frequencies (Hz, NaN where
        empty; None if no column or no value), SNRs (dB, or None) and each bearing's sd (rad, or None).

    Raises
    ------
    InputError
        On any failed check.
    """
    what = "bearings"
    df, t = read_timed_table(path, what, BEARING_COLUMNS, strict=True)
    b_deg = numeric_column(df, "bearing_deg", what, path, lo=-360.0, hi=360.0,
                           fix="beyond ±360: give bearings in degrees clockwise from north")
    if check_radians:
        check_not_radians(b_deg, "bearing_deg", what, path, switch="or set check_radians = false under [inputs] if "
                                                                   "the target really stays within 6 deg of north")
    freq = snr = sd = None
    if "frequency_hz" in df.columns:
        freq = _optional_column(df, "frequency_hz", what, path)
        given = np.isfinite(freq)
        check_range(np.where(given, freq, 1.0), "frequency_hz", what, path, lo=0.0, hi=MAX_FREQUENCY_HZ,
                    lo_open=True, fix="hertz, positive")
        if not given.any():
            freq = None
    if "snr_db" in df.columns:
        snr = numeric_column(df, "snr_db", what, path, lo=-SNR_LIMIT_DB, hi=SNR_LIMIT_DB, fix="decibels")
    if "bearing_sd_deg" in df.columns:
        sd = np.deg2rad(numeric_column(df, "bearing_sd_deg", what, path, lo=0.0, hi=MAX_BEARING_SD_DEG, lo_open=True,
                                       fix="each bearing's noise sd in degrees, positive"))
    return BearingRecord(time_s=t, bearing_rad=np.asarray(wrap_angle(np.deg2rad(b_deg))), frequency_hz=freq, snr_db=snr,
                         bearing_sd_rad=sd)


def read_ownship(path) -> OwnshipTrack:
    """Read and validate an ownship navigation file.

    Parameters
    ----------
    path : str or path-like
        CSV or Parquet file: ``time_s, x_m, y_m``.

    Returns
    -------
    OwnshipTrack
        Times (s) and positions [x east, y north] (m), at least two samples.

    Raises
    ------
    InputError
        On any failed check (columns, times, positions, a single sample, a speed no ship makes).
    """
    what = "ownship"
    df, t = read_timed_table(path, what, OWNSHIP_COLUMNS, strict=True)
    if len(t) < 2:
        raise InputError(f"{what} file {path} has one sample: give at least two (the ownship's velocity is needed)")
    x, y = (numeric_column(df, c, what, path, lo=-MAX_POSITION_M, hi=MAX_POSITION_M,
                           fix="metres in a local frame, at most 10 000 km from its origin") for c in ("x_m", "y_m"))
    check_platform_speed(t, x, y, what, path)
    return OwnshipTrack(time_s=t, x_m=x, y_m=y)


def write_solution_csv(path, solution: TmaSolution, ownship: OwnshipTrack) -> Path:
    """Write the solution table (tma/solution_table.py) atomically.

    Parameters
    ----------
    path : str or path-like
        Output CSV file (its folder is created).
    solution : TmaSolution
        The target solution.
    ownship : OwnshipTrack
        The sensor track (range and bearing columns are relative to it).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    import pandas as pd

    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    return write_csv(pd.DataFrame(solution_columns(solution, ownship)), p, float_format="%.10g")

"""Contacts for the position tracker: Cartesian points or raw bistatic measurements.

Contacts file (CSV or Parquet), one row per contact, rows with the same ``time_s`` form one scan:

* Cartesian: ``time_s, x_m, y_m`` and optionally ``var_x_m2, var_y_m2, cov_xy_m2`` (the point's
  covariance). Without covariance columns a ``default_sigma_m`` must be configured.
* raw bistatic: ``time_s, travel_time_s, bearing_deg`` (bearing relative to the receiving array's
  axis, clockwise), optionally ``sound_speed_mps``; with a navigation file giving, against
  ``time_s``, ``tx_x_m, tx_y_m, rx_x_m, rx_y_m, array_heading_deg`` (linearly interpolated to the
  contact times; times outside the navigation span are an error). Each contact becomes a point with
  covariance J Sigma J^T (models/bistatic.py) using the configured input errors.

Checks (io/tables.py, one line each, naming the file, column, first offending row and value): times sorted
(refused, not re-sorted); no row repeated (same time and values: it would become two identical tracks);
positions within +-1e7 m; variances positive; bearings in [-360, 360] deg and not radians (all within +-2 pi);
sound speeds 1300..1700 m/s; travel times positive and at most 2 * max_range / c (the bistatic range sum
c t = R_tx + R_rx of a target within ``max_range_m`` of both: longer ones are milliseconds written as seconds).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import InputError
from sonartrack.io.tables import (
    MAX_POSITION_M,
    MAX_TIME_S,
    check_columns,
    check_no_duplicate_rows,
    check_not_radians,
    check_sorted,
    numeric_column,
    read_table,
    time_column,
)

RAW_COLUMNS = ["time_s", "travel_time_s", "bearing_deg"]
NAV_COLUMNS = ["time_s", "tx_x_m", "tx_y_m", "rx_x_m", "rx_y_m", "array_heading_deg"]
#: the sound speed in sea water lies in this band (m/s); outside it the column is in another unit
SOUND_SPEED_BAND_MPS = (1300.0, 1700.0)
#: default largest range of a target from the transmitter or receiver (m), for the travel-time check
DEFAULT_MAX_RANGE_M = 100_000.0


@dataclass(frozen=True, slots=True)
class Contacts:
    """Contacts as arrays: times (k,), points (k, 2), covariances (k, 2, 2), sorted by time (rows sharing a time
    are one scan: tracking/run.py track_contacts)."""

    time_s: np.ndarray
    z: np.ndarray
    R: np.ndarray


def _position(df, col, what, path) -> np.ndarray:
    return numeric_column(df, col, what, path, lo=-MAX_POSITION_M, hi=MAX_POSITION_M,
                          fix="metres in a local frame, at most 10 000 km from its origin")


def read_contacts(path, *, nav_path=None, default_sigma_m: float | None = None, bistatic_errors=None,
                  sound_speed_mps: float = 1500.0, max_range_m: float = DEFAULT_MAX_RANGE_M) -> Contacts:
    """Read and validate a contacts file (and its navigation file for raw bistatic columns); module docstring.

    Parameters
    ----------
    path : str or path-like
        Contacts file (CSV or Parquet): Cartesian ``time_s, x_m, y_m[, var_x_m2, var_y_m2, cov_xy_m2]`` or
        raw bistatic ``time_s, travel_time_s, bearing_deg[, sound_speed_mps]``.
    nav_path : str or path-like, optional
        Tx/Rx navigation file, needed for raw bistatic contacts.
    default_sigma_m : float, optional
        Position standard deviation per axis (m) for Cartesian contacts without covariance columns.
    bistatic_errors : BistaticErrors, optional
        Input errors of raw contacts (default: ``BistaticErrors()``, paper P4's).
    sound_speed_mps : float, default 1500.0
        Assumed sound speed (m/s) where the file has no ``sound_speed_mps`` column.
    max_range_m : float, default 100000.0
        Largest target range from Tx or Rx (m), for the travel-time check.

    Returns
    -------
    Contacts
        Times (k,) in s, points (k, 2) [x east, y north] in m, covariances (k, 2, 2) in m^2, sorted by time.

    Raises
    ------
    InputError
        On any failed check (one line naming the file, column, row and value).
    """
    df = read_table(path, "contacts")
    raw = "travel_time_s" in df.columns or "bearing_deg" in df.columns or "travel_time_ms" in df.columns
    check_columns(df, RAW_COLUMNS if raw else ["time_s", "x_m", "y_m"], "contacts", path)
    t = time_column(df, "contacts", path)
    if raw:
        return _raw_bistatic(df, t, path, nav_path, bistatic_errors, sound_speed_mps, max_range_m)
    z = np.stack([_position(df, "x_m", "contacts", path), _position(df, "y_m", "contacts", path)], axis=-1)
    check_no_duplicate_rows({"time_s": t, "x_m": z[:, 0], "y_m": z[:, 1]}, "contacts", path)
    cov_cols = ["var_x_m2", "var_y_m2", "cov_xy_m2"]
    if any(c in df.columns for c in cov_cols):
        check_columns(df, cov_cols, "contacts", path)
        big = MAX_POSITION_M**2
        vx, vy = (numeric_column(df, c, "contacts", path, lo=0.0, hi=big, lo_open=True, fix="a variance, m^2")
                  for c in cov_cols[:2])
        cxy = numeric_column(df, "cov_xy_m2", "contacts", path, lo=-big, hi=big, fix="a covariance, m^2")
        R = np.stack([np.stack([vx, cxy], -1), np.stack([cxy, vy], -1)], -2)
        bad = ~(vx * vy - cxy**2 > 0)
        if bad.any():
            raise InputError(f"contacts file {path}: covariance at data row {int(np.argmax(bad)) + 1} is not positive "
                             "definite (need var_x_m2 > 0, var_y_m2 > 0, var_x_m2 * var_y_m2 > cov_xy_m2^2)")
    else:
        if default_sigma_m is None:
            raise InputError(f"contacts file {path} has no covariance columns (var_x_m2, var_y_m2, cov_xy_m2): "
                             "add them or set default_sigma_m in the config")
        R = np.broadcast_to(np.eye(2) * default_sigma_m**2, (len(t), 2, 2)).copy()
    _check_spread(z, R, path)
    return Contacts(t, z, R)


def _check_spread(z: np.ndarray, R: np.ndarray, path) -> None:
    """Many contacts spanning less than one of their own position standard deviations are not metres: a scene in
    kilometres written into the _m columns (20 or more rows: noise alone then spans several standard deviations)."""
    if len(z) < 20:
        return
    for k, col in enumerate(("x_m", "y_m")):
        extent, sd = float(np.ptp(z[:, k])), float(np.median(np.sqrt(R[:, k, k])))
        if extent < sd:
            raise InputError(f"contacts file {path}: the {len(z)} contacts span only {extent:.3g} m in {col}, less "
                             f"than their own position standard deviation ({sd:.3g} m): positions in kilometres? "
                             "give metres")


def _navigation(nav_path, t: np.ndarray) -> tuple[dict, np.ndarray]:
    """Tx/Rx positions interpolated to the contact times, and the array heading (rad) on the unit circle."""
    what = "navigation"
    nav = read_table(nav_path, what)
    check_columns(nav, NAV_COLUMNS, what, nav_path)
    nt = numeric_column(nav, "time_s", what, nav_path, lo=-MAX_TIME_S, hi=MAX_TIME_S, fix="seconds")
    check_sorted(nt, what, nav_path, strict=True)
    if t[0] < nt[0] or t[-1] > nt[-1]:
        raise InputError(f"contact times {t[0]}..{t[-1]} s are outside the navigation file's span {nt[0]}..{nt[-1]} s: "
                         "extend the navigation record")
    navv = {c: np.interp(t, nt, _position(nav, c, what, nav_path)) for c in NAV_COLUMNS[1:5]}
    heading_deg = numeric_column(nav, "array_heading_deg", what, nav_path, lo=-360.0, hi=360.0, fix="degrees")
    check_not_radians(heading_deg, "array_heading_deg", what, nav_path)
    # the array heading is interpolated on the unit circle, not as a number (359 -> 1 deg)
    h = np.deg2rad(heading_deg)
    return navv, np.arctan2(np.interp(t, nt, np.sin(h)), np.interp(t, nt, np.cos(h)))


def _raw_columns(df, path, c_default, max_range_m):
    """(travel times s, bearings deg, sound speeds m/s) of raw bistatic contacts, checked (module doc)."""
    what = "contacts"
    lo_c, hi_c = SOUND_SPEED_BAND_MPS
    c = (numeric_column(df, "sound_speed_mps", what, path, lo=lo_c, hi=hi_c, fix="metres per second")
         if "sound_speed_mps" in df.columns else np.full(len(df), float(c_default)))
    tt = numeric_column(df, "travel_time_s", what, path, lo=0.0, lo_open=True, fix="seconds, positive")
    far = c * tt > 2.0 * max_range_m
    if far.any():
        row = int(np.argmax(far))
        raise InputError(f"{what} file {path}: travel_time_s = {tt[row]:g} at data row {row + 1} gives a bistatic "
                         f"range sum c t = {c[row] * tt[row] / 1e3:.6g} km, beyond twice the maximum range "
                         f"({max_range_m / 1e3:g} km): milliseconds written as seconds? divide by 1000 (or raise "
                         "max_range_m under [bistatic])")
    bearing_deg = numeric_column(df, "bearing_deg", what, path, lo=-360.0, hi=360.0, fix="degrees")
    check_not_radians(bearing_deg, "bearing_deg", what, path)
    return tt, bearing_deg, c


def _raw_bistatic(df, t, path, nav_path, errors, c_default, max_range_m) -> Contacts:
    from sonartrack.models.bistatic import BistaticErrors, bistatic_covariance, bistatic_position

    if nav_path is None:
        raise InputError(f"contacts file {path} has raw bistatic columns: give the Tx/Rx navigation file with --nav")
    tt, bearing_deg, c = _raw_columns(df, path, c_default, max_range_m)
    check_no_duplicate_rows({"time_s": t, "travel_time_s": tt, "bearing_deg": bearing_deg}, "contacts", path)
    navv, phi = _navigation(nav_path, t)
    tx = np.stack([navv["tx_x_m"], navv["tx_y_m"]], -1)
    rx = np.stack([navv["rx_x_m"], navv["rx_y_m"]], -1)
    theta = np.deg2rad(bearing_deg)
    z, rr = bistatic_position(tt, theta, phi, c, tx, rx)
    keep = rr > 0
    if not keep.any():
        raise InputError(f"contacts file {path}: no contact gives a valid bistatic position "
                         "(c * t shorter than the baseline?)")
    errors = errors or BistaticErrors()
    R = bistatic_covariance(tt, theta, phi, c, tx, rx, errors.variances())
    return Contacts(t[keep], z[keep], R[keep])

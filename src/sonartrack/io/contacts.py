"""Contacts for the position tracker: Cartesian points or raw bistatic measurements.

Contacts file (CSV or Parquet), one row per contact, rows with the same ``time_s`` form one scan:

* Cartesian: ``time_s, x_m, y_m`` and optionally ``var_x_m2, var_y_m2, cov_xy_m2`` (the point's
  covariance). Without covariance columns a ``default_sigma_m`` must be configured.
* raw bistatic: ``time_s, travel_time_s, bearing_deg`` (bearing relative to the receiving array's
  axis, clockwise), optionally ``sound_speed_mps``; with a navigation file giving, against
  ``time_s``, ``tx_x_m, tx_y_m, rx_x_m, rx_y_m, array_heading_deg`` (linearly interpolated to the
  contact times; times outside the navigation span are an error). Each contact becomes a point with
  covariance J Sigma J^T (models/bistatic.py) using the configured input errors.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import InputError
from sonartrack.io.tables import check_columns, check_sorted, numeric_column, read_table

RAW_COLUMNS = ["time_s", "travel_time_s", "bearing_deg"]
NAV_COLUMNS = ["time_s", "tx_x_m", "tx_y_m", "rx_x_m", "rx_y_m", "array_heading_deg"]


@dataclass(frozen=True, slots=True)
class Contacts:
    """Contacts as arrays: times (k,), points (k, 2), covariances (k, 2, 2), sorted by time (rows sharing a time
    are one scan: tracking/run.py track_contacts)."""

    time_s: np.ndarray
    z: np.ndarray
    R: np.ndarray


def read_contacts(path, *, nav_path=None, default_sigma_m: float | None = None, bistatic_errors=None,
                  sound_speed_mps: float = 1500.0) -> Contacts:
    """Read and validate a contacts file (and its navigation file for raw bistatic columns)."""
    df = read_table(path, "contacts")
    raw = "travel_time_s" in df.columns or "bearing_deg" in df.columns or "travel_time_ms" in df.columns
    if raw:
        check_columns(df, RAW_COLUMNS, "contacts", path)
    else:
        check_columns(df, ["time_s", "x_m", "y_m"], "contacts", path)
    t = numeric_column(df, "time_s", "contacts", path)
    check_sorted(t, "contacts", path)
    if raw:
        return _raw_bistatic(df, t, path, nav_path, bistatic_errors, sound_speed_mps)
    z = np.stack([numeric_column(df, "x_m", "contacts", path), numeric_column(df, "y_m", "contacts", path)], axis=-1)
    cov_cols = ["var_x_m2", "var_y_m2", "cov_xy_m2"]
    if any(c in df.columns for c in cov_cols):
        check_columns(df, cov_cols, "contacts", path)
        vx, vy, cxy = (numeric_column(df, c, "contacts", path) for c in cov_cols)
        R = np.stack([np.stack([vx, cxy], -1), np.stack([cxy, vy], -1)], -2)
        bad = ~((vx > 0) & (vy > 0) & (vx * vy - cxy**2 > 0))
        if bad.any():
            raise InputError(f"contacts file {path}: covariance at data row {int(np.argmax(bad)) + 1} is not positive "
                             "definite (need var_x_m2 > 0, var_y_m2 > 0, var_x_m2 * var_y_m2 > cov_xy_m2^2)")
    else:
        if default_sigma_m is None:
            raise InputError(f"contacts file {path} has no covariance columns (var_x_m2, var_y_m2, cov_xy_m2): "
                             "add them or set default_sigma_m in the config")
        R = np.broadcast_to(np.eye(2) * default_sigma_m**2, (len(t), 2, 2)).copy()
    return Contacts(t, z, R)


def _raw_bistatic(df, t, path, nav_path, errors, c_default) -> Contacts:
    from sonartrack.models.bistatic import BistaticErrors, bistatic_covariance, bistatic_position

    if nav_path is None:
        raise InputError(f"contacts file {path} has raw bistatic columns: give the Tx/Rx navigation file with --nav")
    nav = read_table(nav_path, "navigation")
    check_columns(nav, NAV_COLUMNS, "navigation", nav_path)
    nt = numeric_column(nav, "time_s", "navigation", nav_path)
    check_sorted(nt, "navigation", nav_path, strict=True)
    if t[0] < nt[0] or t[-1] > nt[-1]:
        raise InputError(f"contact times {t[0]}..{t[-1]} s are outside the navigation file's span {nt[0]}..{nt[-1]} s: "
                         "extend the navigation record")
    navv = {c: np.interp(t, nt, numeric_column(nav, c, "navigation", nav_path)) for c in NAV_COLUMNS[1:]}
    # the array heading is interpolated on the unit circle, not as a number (359 -> 1 deg)
    h = np.deg2rad(numeric_column(nav, "array_heading_deg", "navigation", nav_path))
    phi = np.arctan2(np.interp(t, nt, np.sin(h)), np.interp(t, nt, np.cos(h)))
    tt = numeric_column(df, "travel_time_s", "contacts", path)
    bearing_deg = numeric_column(df, "bearing_deg", "contacts", path)
    if np.any(tt <= 0):
        raise InputError(f"contacts file {path}: travel_time_s must be positive (seconds)")
    if np.any(np.abs(bearing_deg) > 360):
        raise InputError(f"contacts file {path}: bearing_deg has values beyond ±360: give degrees")
    c = (numeric_column(df, "sound_speed_mps", "contacts", path) if "sound_speed_mps" in df.columns
         else np.full(len(t), c_default))
    if np.any((c < 1300) | (c > 1700)):
        raise InputError(f"contacts file {path}: sound_speed_mps outside 1300..1700 m/s: give metres per second")
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

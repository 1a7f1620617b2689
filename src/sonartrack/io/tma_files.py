"""TMA input files (bearings, ownship navigation) and the target-solution table, shared by every
``sonartrack tma`` method (sequential EKF/MGEKF/IMM and batch ML/EM-MAP).

Bearings file (CSV or Parquet; ``#`` comment lines allowed in CSV), one row per measurement:

* ``time_s`` (s, strictly increasing), ``bearing_deg`` (degrees clockwise from north, true, of the
  target from the ownship; any of -180..180 or 0..360);
* optional ``frequency_hz`` (received frequency of the tracked line, Hz, > 0; an empty cell means
  no frequency at that time);
* optional ``snr_db`` (signal-to-noise ratio, dB; used by the batch methods).

Ownship file (CSV or Parquet): ``time_s`` (s, strictly increasing), ``x_m``, ``y_m`` (m, x east, y
north, in the same local frame as the solution). Positions are interpolated linearly to the
measurement times, velocities from central differences of the samples. Measurement times outside
the ownship file's span are an error (no extrapolation), and so is a measurement inside a gap of more
than ``max_gap_s`` (default 120 s) between two ownship samples.

Checks with one-line errors: missing or non-numeric values, unsorted or repeated times, columns in
the wrong unit (``bearing_rad``, ``x_km``, ``time_ms`` ...), bearings beyond +-360 deg, bearings that
all lie within +-2 pi (radians written in a degrees column; switch off with ``check_radians=False``
for a target genuinely within 6 deg of north), non-positive frequencies, an ownship moving faster
than 40 m/s (about 78 kn: kilometres or minutes written as metres or seconds).

Solution table (CSV), one row per measurement time: ``time_s, x_m, y_m, vx_mps, vy_mps,
course_deg, speed_kn, range_m, bearing_deg`` and the standard deviation of each (``*_std``
columns, with the same unit), from the solution's covariance by first-order propagation (the course
std is capped at 180 deg, where the speed is too uncertain for a course); range and bearing are from
the ownship to the target.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.errors import InputError
from sonartrack.io.records import BearingRecord, OwnshipTrack, TmaSolution
from sonartrack.io.tables import check_columns, check_sorted, numeric_column, read_table

BEARING_COLUMNS = ["time_s", "bearing_deg"]
OWNSHIP_COLUMNS = ["time_s", "x_m", "y_m"]
MAX_NAV_GAP_S = 120.0
MAX_OWNSHIP_SPEED_MPS = 40.0
KNOT_MPS = 1852.0 / 3600.0


def _optional_column(df, col: str, what: str, path) -> np.ndarray:
    """A column where empty cells are allowed (NaN) but text or infinities are not."""
    import pandas as pd

    raw = df[col]
    values = pd.to_numeric(raw, errors="coerce").to_numpy(dtype=float)
    bad = (np.isnan(values) & raw.notna().to_numpy()) | np.isinf(values)
    if bad.any():
        row = int(np.argmax(bad))
        raise InputError(f"{what} file {path}: column '{col}' has a non-numeric value at data row {row + 1} "
                         f"({raw.iloc[row]!r}): fix it or leave the cell empty")
    return values


def read_bearings(path, *, check_radians: bool = True) -> BearingRecord:
    """Read and validate a bearings file into a :class:`BearingRecord` (SI units)."""
    what = "bearings"
    df = read_table(path, what)
    check_columns(df, BEARING_COLUMNS, what, path)
    t = numeric_column(df, "time_s", what, path)
    check_sorted(t, what, path, strict=True)
    b_deg = numeric_column(df, "bearing_deg", what, path)
    if np.any(np.abs(b_deg) > 360.0):
        row = int(np.argmax(np.abs(b_deg) > 360.0))
        raise InputError(f"{what} file {path}: bearing_deg = {b_deg[row]:g} at data row {row + 1} is beyond ±360: "
                         "give bearings in degrees clockwise from north")
    if check_radians and len(b_deg) >= 5 and np.all(np.abs(b_deg) <= 2.0 * np.pi):
        raise InputError(f"{what} file {path}: every bearing_deg lies within ±6.29, so these look like radians: "
                         "multiply by 180/pi (or set check_radians = false if the target really stays within 6 deg of north)")
    freq = snr = None
    if "frequency_hz" in df.columns:
        freq = _optional_column(df, "frequency_hz", what, path)
        if np.any(freq <= 0):
            row = int(np.argmax(freq <= 0))
            raise InputError(f"{what} file {path}: frequency_hz must be positive (data row {row + 1}: {freq[row]:g})")
        if not np.isfinite(freq).any():
            freq = None
    if "snr_db" in df.columns:
        snr = numeric_column(df, "snr_db", what, path)
    return BearingRecord(t, np.asarray(wrap_angle(np.deg2rad(b_deg))), freq, snr)


def read_ownship(path) -> OwnshipTrack:
    """Read and validate an ownship navigation file into an :class:`OwnshipTrack`."""
    what = "ownship"
    df = read_table(path, what)
    check_columns(df, OWNSHIP_COLUMNS, what, path)
    t = numeric_column(df, "time_s", what, path)
    check_sorted(t, what, path, strict=True)
    if len(t) < 2:
        raise InputError(f"{what} file {path} has one sample: give at least two (the ownship's velocity is needed)")
    x = numeric_column(df, "x_m", what, path)
    y = numeric_column(df, "y_m", what, path)
    speed = np.hypot(np.diff(x), np.diff(y)) / np.diff(t)
    if np.any(speed > MAX_OWNSHIP_SPEED_MPS):
        row = int(np.argmax(speed > MAX_OWNSHIP_SPEED_MPS)) + 1
        raise InputError(f"{what} file {path}: the ownship moves at {speed[row - 1]:.0f} m/s before data row {row + 1}: "
                         "positions must be metres and times seconds")
    return OwnshipTrack(t, x, y)


def check_coverage(record: BearingRecord, ownship: OwnshipTrack, max_gap_s: float = MAX_NAV_GAP_S) -> None:
    """Every measurement time must lie within the ownship span, in no gap longer than ``max_gap_s``."""
    t = np.asarray(record.time_s, float)
    nt = np.asarray(ownship.time_s, float)
    outside = (t < nt[0]) | (t > nt[-1])
    if outside.any():
        raise InputError(f"{int(outside.sum())} measurement time(s) (first {t[np.argmax(outside)]:g} s) lie outside the "
                         f"ownship file's span {nt[0]:g}..{nt[-1]:g} s: extend the ownship file or trim the bearings "
                         "(positions are not extrapolated)")
    k = np.clip(np.searchsorted(nt, t, side="right"), 1, len(nt) - 1)
    gap = nt[k] - nt[k - 1]
    on_sample = np.isin(t, nt)
    bad = (gap > max_gap_s) & ~on_sample
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"no ownship position near t = {t[i]:g} s: the ownship file has a {gap[i]:g} s gap "
                         f"({nt[k[i] - 1]:g}..{nt[k[i]]:g} s) and sonartrack interpolates across at most "
                         f"{max_gap_s:g} s: add ownship samples or drop those measurements")


def solution_columns(solution: TmaSolution, ownship: OwnshipTrack) -> dict[str, np.ndarray]:
    """The solution table's columns (module docstring), standard deviations by first-order propagation:

        course = atan2(vx, vy):  J = [vy, -vx] / s^2 on (vx, vy);   speed s = |v|:  J = [vx, vy] / s
        bearing = atan2(dx, dy): J = [dy, -dx] / r^2 on (x, y);     range r = |d|:  J = [dx, dy] / r
    with d = target - ownship position.
    """
    t = np.asarray(solution.time_s, float)
    X = np.asarray(solution.state, float)
    P = np.asarray(solution.covariance, float)
    own = ownship.position_at(t)
    dx, dy = X[:, 0] - own[:, 0], X[:, 1] - own[:, 1]
    vx, vy = X[:, 2], X[:, 3]
    r = np.hypot(dx, dy)
    s = np.hypot(vx, vy)

    def quad(J, block):
        return np.sqrt(np.maximum(np.einsum("ni,nij,nj->n", J, P[:, block, block], J), 0.0))

    pos, vel = slice(0, 2), slice(2, 4)
    with np.errstate(invalid="ignore", divide="ignore"):
        s_safe = np.where(s > 0, s, np.nan)
        r_safe = np.where(r > 0, r, np.nan)
        course_std = quad(np.stack([vy, -vx], -1) / s_safe[:, None] ** 2, vel)
        speed_std = quad(np.stack([vx, vy], -1) / s_safe[:, None], vel)
        brg_std = quad(np.stack([dy, -dx], -1) / r_safe[:, None] ** 2, pos)
        rng_std = quad(np.stack([dx, dy], -1) / r_safe[:, None], pos)
    course = np.rad2deg(np.arctan2(vx, vy)) % 360.0
    bearing = np.rad2deg(np.arctan2(dx, dy)) % 360.0
    sd = np.sqrt(np.maximum(np.einsum("nii->ni", P), 0.0))
    return {"time_s": t, "x_m": X[:, 0], "y_m": X[:, 1], "vx_mps": vx, "vy_mps": vy, "course_deg": course,
            "speed_kn": s / KNOT_MPS, "range_m": r, "bearing_deg": bearing,
            "x_std_m": sd[:, 0], "y_std_m": sd[:, 1], "vx_std_mps": sd[:, 2], "vy_std_mps": sd[:, 3],
            # a course is undefined at zero speed: its std saturates at 180 deg
            "course_std_deg": np.minimum(np.rad2deg(np.nan_to_num(course_std, nan=np.pi)), 180.0), "speed_std_kn": speed_std / KNOT_MPS,
            "range_std_m": rng_std, "bearing_std_deg": np.rad2deg(brg_std)}


def write_solution_csv(path, solution: TmaSolution, ownship: OwnshipTrack) -> Path:
    """Write the solution table atomically (temporary name in the same folder, then rename)."""
    import pandas as pd

    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    tmp = p.with_name(f".{p.name}.{os.getpid()}.tmp")
    try:
        pd.DataFrame(solution_columns(solution, ownship)).to_csv(tmp, index=False, float_format="%.10g")
        os.replace(tmp, p)
    finally:
        if tmp.exists():
            tmp.unlink()
    return p

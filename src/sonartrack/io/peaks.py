"""Bearing-peak files: ``time_s, bearing_deg, amplitude``, one row per cross-correlation peak.

Written by ``sonartrack bearings`` and read by ``sonartrack track --peaks``; bearings are cone angles
(0..180 deg from the array axis), the record type is :class:`sonartrack.acoustics.xcorr_bearing.PeakRecord`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.acoustics.xcorr_bearing import PeakRecord
from sonartrack.core.errors import InputError, require
from sonartrack.io.atomic import write_csv


def write_peaks_csv(path, record: PeakRecord) -> Path:
    """time_s, bearing_deg, amplitude (atomic write)."""
    import pandas as pd

    return write_csv(pd.DataFrame({"time_s": record.time_s, "bearing_deg": record.bearing_deg,
                                   "amplitude": record.amplitude}), path, float_format="%.6g")


def read_peaks_csv(path) -> PeakRecord:
    """A peaks file (time_s, bearing_deg, amplitude); one-line errors for missing, empty or bad files."""
    import pandas as pd

    p = Path(path)
    require(p.is_file(), f"peaks file not found: {p}")
    try:
        df = pd.read_csv(p)
    except pd.errors.EmptyDataError:
        raise InputError(f"peaks file {p.name} is empty: expected columns time_s, bearing_deg, amplitude") from None
    except Exception as exc:  # noqa: BLE001 - pandas raises many types for bad files
        raise InputError(f"cannot read peaks file {p.name}: {exc}") from None
    missing = [c for c in ("time_s", "bearing_deg", "amplitude") if c not in df.columns]
    require(not missing, f"peaks file {p.name} lacks column(s) {', '.join(missing)} "
                         f"(has {', '.join(map(str, df.columns))})")
    require(len(df) > 0, f"peaks file {p.name} has no rows")
    try:
        cols = {c: df[c].to_numpy(dtype=float) for c in ("time_s", "bearing_deg", "amplitude")}
    except (TypeError, ValueError):
        raise InputError(f"peaks file {p.name}: time_s, bearing_deg and amplitude must be numbers") from None
    for c, v in cols.items():
        require(bool(np.all(np.isfinite(v))), f"peaks file {p.name}: column {c} has NaN or empty cells")
    b = cols["bearing_deg"]
    require(bool(np.all((b >= 0) & (b <= 180))), f"peaks file {p.name}: bearing_deg must be cone angles in 0..180 deg "
                                                 f"(found {b.min():.3g}..{b.max():.3g}; radians or compass bearings?)")
    require(bool(np.all(np.diff(cols["time_s"]) >= 0)),
            f"peaks file {p.name}: time_s must not decrease (sort the rows)")
    return PeakRecord(cols["time_s"], b, cols["amplitude"])

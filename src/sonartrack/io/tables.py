"""Reading user tables (CSV or Parquet) with clear one-line errors.

Shared checks for every user file: the file exists and parses; required columns are present;
columns that carry a unit we do not take (``x_km``, ``time_ms``, ``bearing_rad`` where degrees are
expected...) are named with the fix; no NaN or infinite values; times sorted.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError

#: column name with a unit we do not take -> (the column we want, factor to convert, unit word)
WRONG_UNITS = {
    "x_km": ("x_m", "kilometres"), "y_km": ("y_m", "kilometres"),
    "time_ms": ("time_s", "milliseconds"), "time_min": ("time_s", "minutes"), "t_ms": ("time_s", "milliseconds"),
    "bearing_rad": ("bearing_deg", "radians"), "travel_time_ms": ("travel_time_s", "milliseconds"),
    "array_heading_rad": ("array_heading_deg", "radians"), "sound_speed_kmps": ("sound_speed_mps", "km/s"),
    "tx_x_km": ("tx_x_m", "kilometres"), "tx_y_km": ("tx_y_m", "kilometres"),
    "rx_x_km": ("rx_x_m", "kilometres"), "rx_y_km": ("rx_y_m", "kilometres"),
}


def read_table(path: str | Path, what: str):
    """Read a CSV or Parquet file into a pandas DataFrame (one-line errors)."""
    import pandas as pd

    p = Path(path)
    if not p.is_file():
        raise InputError(f"{what} file not found: {p}")
    parquet = p.suffix.lower() in (".parquet", ".pq")
    try:
        df = pd.read_parquet(p) if parquet else pd.read_csv(p, comment="#")
    except Exception as exc:  # pandas raises many types for malformed files
        raise InputError(f"{what} file {p} could not be read as {'Parquet' if parquet else 'CSV'}: "
                         f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from None
    df.columns = [str(c).strip() for c in df.columns]
    if len(df) == 0:
        raise InputError(f"{what} file {p} has no rows")
    return df


def check_columns(df, required: list[str], what: str, path) -> None:
    """Fail on wrong-unit columns (naming the fix), then on missing required columns."""
    for col in df.columns:
        if col in WRONG_UNITS and WRONG_UNITS[col][0] not in df.columns:
            want, unit = WRONG_UNITS[col]
            raise InputError(f"{what} file {path}: column '{col}' is in {unit}; sonartrack reads '{want}' "
                             f"(SI units): convert and rename the column")
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise InputError(f"{what} file {path} lacks column(s) {', '.join(missing)} "
                         f"(has: {', '.join(map(str, df.columns))})")


def numeric_column(df, col: str, what: str, path) -> np.ndarray:
    """A column as float64, refusing text, NaN and infinities with the row number."""
    import pandas as pd

    values = pd.to_numeric(df[col], errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(values)
    if bad.any():
        row = int(np.argmax(bad))
        raise InputError(f"{what} file {path}: column '{col}' has {int(bad.sum())} missing, NaN or non-numeric "
                         f"value(s), first at data row {row + 1}: fix or remove those rows")
    return values


def check_sorted(times: np.ndarray, what: str, path, strict: bool = False) -> None:
    d = np.diff(times)
    bad = (d <= 0) if strict else (d < 0)
    if bad.any():
        row = int(np.argmax(bad)) + 1
        raise InputError(f"{what} file {path}: time_s is not {'strictly increasing' if strict else 'sorted'} "
                         f"(data row {row + 1}: {times[row]} after {times[row - 1]}): sort the file by time")

"""Reading user tables (CSV or Parquet) with clear one-line errors: the one checking boundary for files.

Shared checks for every user file, each failing with one line that names the file, the column, the
first offending value and its data row, and the fix:

* the file exists, is a file (not a directory) and parses; it has rows; required columns are present;
* columns that carry a unit we do not take (``x_km``, ``time_ms``, ``bearing_rad`` ...) are named with the fix;
* numbers: no text, NaN or infinity (:func:`numeric_column`); every value within the column's physical
  range, and in any case within +-:data:`ABSURD` (a 1e300 reaches no numerics);
* unit plausibility: a ``_deg`` column whose values all lie within +-2 pi, with some spread, holds radians
  (:func:`check_not_radians`);
* times sorted (refused, never silently re-sorted: a file out of order is usually a file put together
  wrongly) and no repeated rows (:func:`check_sorted`, :func:`check_no_duplicate_rows`).

Glossary of the parameters: ``path``, the file (str or path-like); ``what``, what the file is, the subject of the
messages ("contacts", "bearings"); ``col``, a column's name.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError

#: column name with a unit we do not take -> (the column we want, unit word)
WRONG_UNITS = {
    "x_km": ("x_m", "kilometres"), "y_km": ("y_m", "kilometres"),
    "time_ms": ("time_s", "milliseconds"), "time_min": ("time_s", "minutes"), "t_ms": ("time_s", "milliseconds"),
    "bearing_rad": ("bearing_deg", "radians"), "travel_time_ms": ("travel_time_s", "milliseconds"),
    "array_heading_rad": ("array_heading_deg", "radians"), "sound_speed_kmps": ("sound_speed_mps", "km/s"),
    "tx_x_km": ("tx_x_m", "kilometres"), "tx_y_km": ("tx_y_m", "kilometres"),
    "rx_x_km": ("rx_x_m", "kilometres"), "rx_y_km": ("rx_y_m", "kilometres"),
}

#: no number in a user file is larger in magnitude than this (whatever the column: 1e300 reaches no numerics)
ABSURD = 1e15
#: positions (m) beyond this from the local origin (10 000 km) are not in one local frame
MAX_POSITION_M = 1e7
#: times (s) beyond this (about 300 years; Unix seconds pass) are nanoseconds or garbage
MAX_TIME_S = 1e10


#: leading bytes of the binary files most often given by mistake -> what they are
MAGIC = {b"\x89PNG": "a PNG image", b"\xff\xd8\xff": "a JPEG image", b"%PDF": "a PDF document",
         b"PK\x03\x04": "a ZIP archive (.npz, .xlsx ...)", b"\x93NUMPY": "a NumPy .npy array",
         b"RIFF": "a WAV (RIFF) file", b"PAR1": "a Parquet file", b"\x89HDF": "an HDF5 file",
         b"\x1f\x8b": "a gzip archive"}


def sniff_file_type(path: str | Path) -> str | None:
    """What a file is by its first bytes (:data:`MAGIC`), or None when it is none of those.

    Returns
    -------
    str or None
        E.g. "a PNG image".
    """
    with open(path, "rb") as f:
        head = f.read(8)
    return next((kind for magic, kind in MAGIC.items() if head.startswith(magic)), None)


def check_file(path: str | Path, what: str) -> Path:
    """Require the path to exist and be a regular file (a directory is named as such).

    Parameters
    ----------
    path : str or pathlib.Path
        The path.
    what : str
        What the file is, for the message ("contacts").

    Returns
    -------
    pathlib.Path
        The path.

    Raises
    ------
    InputError
        If it is a directory or does not exist.
    """
    p = Path(path)
    if p.is_dir():
        raise InputError(f"{what} file {p} is a directory: give the file inside it")
    if not p.is_file():
        raise InputError(f"{what} file not found: {p}")
    return p


def read_table(path: str | Path, what: str):
    """Read a CSV (``#`` comments allowed) or Parquet file into a pandas DataFrame, with one-line errors.

    Parameters
    ----------
    path : str or pathlib.Path
        The file; ``.parquet``/``.pq`` is read as Parquet, anything else as CSV.

    Returns
    -------
    pandas.DataFrame
        The table, column names stripped of spaces.

    Raises
    ------
    InputError
        If the file is missing, empty, a known binary type, unreadable, or has no rows.
    """
    import pandas as pd

    p = check_file(path, what)
    if p.stat().st_size == 0:
        raise InputError(f"{what} file {p} is empty (0 bytes): give a header line and data rows")
    parquet = p.suffix.lower() in (".parquet", ".pq")
    kind = sniff_file_type(p)
    if kind is not None and not (parquet and kind == "a Parquet file"):
        raise InputError(f"{what} file {p} is {kind}, not a {'Parquet' if parquet else 'CSV'} table: give the "
                         f"{'Parquet' if parquet else 'comma-separated text'} file")
    try:
        df = pd.read_parquet(p) if parquet else pd.read_csv(p, comment="#")
    except Exception as exc:  # noqa: BLE001 - pandas raises many types (and UnicodeDecodeError) for malformed files
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"{what} file {p} could not be read as {'Parquet' if parquet else 'CSV'} ({first}): "
                         f"give a {'Parquet' if parquet else 'comma-separated text'} file") from None
    df.columns = [str(c).strip() for c in df.columns]
    if len(df) == 0:
        raise InputError(f"{what} file {p} has no rows (header only?): give at least one data row")
    return df


#: the largest CSV read without pandas (bytes, about 50 000 rows of a navigation table): a plain table of numbers
#: this small parses in Python in less time than pandas takes to import; larger or other files go through pandas
PLAIN_CSV_MAX_BYTES = 4_000_000
#: a cell of a plain CSV: a decimal number (no NaN, infinity, spaces, quotes, thousands separators)
_PLAIN_CELL = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
#: an integer cell that pandas would read as an integer column's 0 where float() gives -0.0, or beyond float's
#: exact integers: left to pandas
_AWKWARD_INTEGER = re.compile(r"(?:^|,)(?:-0+|[+-]?\d{16,})(?=,|$)")


@dataclass(frozen=True, slots=True)
class NumericTable:
    """A plain CSV of numbers read without pandas (:func:`read_numeric_table`): its column names (stripped of
    spaces, in file order) and each column's float64 values; ``table[name]`` is a column, as a DataFrame's."""

    columns: list[str]
    values: dict[str, np.ndarray]

    def __getitem__(self, col: str) -> np.ndarray:
        return self.values[col]

    def __len__(self) -> int:
        return len(self.values[self.columns[0]])


def _plain_numeric_csv(p: Path) -> NumericTable | None:
    """The table when the file is a plain CSV of numbers -- ASCII, a header line of distinct names, then rows of
    decimal numbers all of the header's width, blank lines skipped, no comment, quote, NaN or infinity -- with the
    values pandas' ``read_csv`` gives it (both round the decimal text to the nearest float); None for any other
    file, which :func:`read_table` then reads (and refuses with its own messages)."""
    try:
        text = p.read_bytes().decode("ascii")
    except UnicodeDecodeError:
        return None
    text = text.replace("\r\n", "\n")
    if "\r" in text or '"' in text or "#" in text:
        return None
    head, _, body = text.partition("\n")
    names = [c.strip() for c in head.split(",")]
    rows = [line for line in body.split("\n") if line]
    if not rows or "" in names or len(set(names)) != len(names):
        return None
    row = re.compile(",".join([_PLAIN_CELL] * len(names)))
    if not all(row.fullmatch(line) for line in rows) or any(_AWKWARD_INTEGER.search(line) for line in rows):
        return None
    values = np.array([[float(c) for c in line.split(",")] for line in rows], dtype=float).reshape(len(rows), -1)
    if not np.isfinite(values).all():
        return None
    return NumericTable(names, {c: values[:, k].copy() for k, c in enumerate(names)})


def read_numeric_table(path: str | Path, what: str):
    """:func:`read_table` for a table of numbers: a small plain CSV (:data:`PLAIN_CSV_MAX_BYTES`,
    :func:`_plain_numeric_csv`) is read without importing pandas, to the same values; any other file through
    :func:`read_table`, with its checks and messages.

    Returns
    -------
    NumericTable or pandas.DataFrame
        The table (column names stripped of spaces); either gives its columns by name to :func:`check_columns`
        and :func:`numeric_column`.
    """
    p = check_file(path, what)
    if (p.suffix.lower() not in (".parquet", ".pq") and 0 < p.stat().st_size <= PLAIN_CSV_MAX_BYTES
            and sniff_file_type(p) is None):
        table = _plain_numeric_csv(p)
        if table is not None:
            return table
    return read_table(path, what)


def check_columns(df, required: list[str], what: str, path) -> None:
    """Fail on columns in a unit we do not take (naming the fix), then on missing required columns.

    Parameters
    ----------
    df : pandas.DataFrame or NumericTable
        The table.
    required : list of str
        Required column names.

    Raises
    ------
    InputError
        On the first problem.
    """
    for col in df.columns:
        if col in WRONG_UNITS and WRONG_UNITS[col][0] not in df.columns:
            want, unit = WRONG_UNITS[col]
            raise InputError(f"{what} file {path}: column '{col}' is in {unit}; sonartrack reads '{want}' "
                             f"(SI units): convert and rename the column")
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise InputError(f"{what} file {path} lacks column(s) {', '.join(missing)} "
                         f"(has: {', '.join(map(str, df.columns))})")


def cell_text(value) -> str:
    """A table cell as a message shows it: text quoted, numbers plain (nan, not np.float64(nan)).

    Parameters
    ----------
    value : object
        The cell.

    Returns
    -------
    str
        Its text.
    """
    return repr(value) if isinstance(value, str) else str(value)


def numeric_column(df, col: str, what: str, path, *, lo: float = -ABSURD, hi: float = ABSURD,
                   lo_open: bool = False, fix: str = "") -> np.ndarray:
    """A column as float64, refusing text, NaN, infinities and values outside [lo, hi].

    Parameters
    ----------
    df : pandas.DataFrame or NumericTable
        The table.
    lo, hi : float, default -1e15, 1e15
        Allowed range, in the column's unit.
    lo_open : bool, default False
        Exclude ``lo`` itself: (lo, hi].
    fix : str, default ""
        Hint added to an out-of-range message (e.g. "seconds").

    Returns
    -------
    ndarray of float64
        The values.

    Raises
    ------
    InputError
        Naming the first offending data row and value.
    """
    raw = df[col]
    if isinstance(raw, np.ndarray):  # a NumericTable's column: numbers already
        values = np.array(raw, dtype=float)
    else:
        import pandas as pd

        values = pd.to_numeric(raw, errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(values)
    if bad.any():
        row = int(np.argmax(bad))
        cell = raw[row] if isinstance(raw, np.ndarray) else raw.iloc[row]
        raise InputError(f"{what} file {path}: column '{col}' has {int(bad.sum())} missing, NaN, infinite or "
                         f"non-numeric value(s), first at data row {row + 1} ({cell_text(cell)}): fix or "
                         "remove those rows")
    check_range(values, col, what, path, lo=lo, hi=hi, lo_open=lo_open, fix=fix)
    return values


def check_range(values: np.ndarray, col: str, what: str, path, *, lo: float = -ABSURD, hi: float = ABSURD,
                lo_open: bool = False, fix: str = "") -> None:
    """Require every value within [lo, hi] (``lo_open``: lo excluded), else one line with the first offender.

    Parameters
    ----------
    values : ndarray
        The values.
    lo, hi : float, default -1e15, 1e15
        Allowed range.
    lo_open : bool, default False
        Exclude ``lo``.
    fix : str, default ""
        Hint added to the message.

    Raises
    ------
    InputError
        On the first value outside the range.
    """
    v = np.asarray(values, dtype=float)
    bad = ~((v > lo) if lo_open else (v >= lo)) | (v > hi)
    if bad.any():
        row = int(np.argmax(bad))
        span = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
        raise InputError(f"{what} file {path}: column '{col}' = {v[row]:g} at data row {row + 1} is outside "
                         f"{span}{f' ({fix})' if fix else ''}: fix that value")


def check_not_radians(values: np.ndarray, col: str, what: str, path, *, min_rows: int = 5,
                      switch: str = "") -> None:
    """Refuse a degrees column whose values all lie within +-2 pi, with some spread: it holds radians.

    Needs ``min_rows`` values (a few bearings within 6 deg are plausible).

    Parameters
    ----------
    values : ndarray
        The column (deg).
    min_rows : int, default 5
        Fewest values for the check to apply.
    switch : str, default ""
        How to turn the check off, if it can be (added to the message).

    Raises
    ------
    InputError
        If the values look like radians.
    """
    v = np.asarray(values, dtype=float)
    if len(v) >= min_rows and np.ptp(v) > 0 and np.all(np.abs(v) <= 2.0 * np.pi):
        raise InputError(f"{what} file {path}: every {col} lies within ±6.29 (from {v.min():.3g} to {v.max():.3g}), "
                         f"so these look like radians: multiply by 180/pi{f' ({switch})' if switch else ''}")


def check_sorted(times: np.ndarray, what: str, path, strict: bool = False, col: str = "time_s") -> None:
    """Require times in order (refused otherwise, never re-sorted).

    Parameters
    ----------
    times : ndarray
        Times (s).
    strict : bool, default False
        Also refuse a repeated time.
    col : str, default "time_s"
        Column name for the message.

    Raises
    ------
    InputError
        At the first time out of order.
    """
    d = np.diff(times)
    bad = (d <= 0) if strict else (d < 0)
    if bad.any():
        row = int(np.argmax(bad)) + 1
        raise InputError(f"{what} file {path}: {col} is not {'strictly increasing' if strict else 'sorted'} "
                         f"(data row {row + 1}: {times[row]:g} after {times[row - 1]:g}): sort the file by {col}"
                         f"{' and drop repeated times' if strict else ''}")


def time_column(df, what: str, path, *, strict: bool = False) -> np.ndarray:
    """The table's ``time_s`` column (s): numbers within +-:data:`MAX_TIME_S`, sorted (``strict``: increasing).

    Parameters
    ----------
    df : pandas.DataFrame or NumericTable
        The table.
    strict : bool, default False
        Refuse repeated times too (:func:`check_sorted`).

    Returns
    -------
    ndarray
        The times (s).
    """
    t = numeric_column(df, "time_s", what, path, lo=-MAX_TIME_S, hi=MAX_TIME_S, fix="seconds")
    check_sorted(t, what, path, strict=strict)
    return t


def read_timed_table(path, what: str, columns: list[str], *, strict: bool = False):
    """A table with its required ``columns`` (:func:`read_table`, :func:`check_columns`) and its times
    (:func:`time_column`).

    Returns
    -------
    df : pandas.DataFrame
        The table.
    time_s : ndarray
        Its ``time_s`` column (s), checked.
    """
    df = read_table(path, what)
    check_columns(df, columns, what, path)
    return df, time_column(df, what, path, strict=strict)


def check_no_duplicate_rows(columns: dict[str, np.ndarray], what: str, path) -> None:
    """Refuse two rows with the same values in every column given (a contact listed twice is not two contacts).

    Parameters
    ----------
    columns : dict of str to ndarray
        The columns compared.

    Raises
    ------
    InputError
        Naming the first pair of repeated rows.
    """
    import pandas as pd

    df = pd.DataFrame(columns)
    dup = df.duplicated(keep="first").to_numpy()
    if dup.any():
        row = int(np.argmax(dup))
        first = int(np.argmax((df == df.iloc[row]).all(axis=1).to_numpy()))
        raise InputError(f"{what} file {path}: data rows {first + 1} and {row + 1} repeat the same "
                         f"{', '.join(columns)} ({int(dup.sum())} repeated row(s) in all): remove the repeats")


#: a platform faster than this (m/s, about 78 kn) has kilometres or minutes written as metres or seconds
MAX_PLATFORM_SPEED_MPS = 40.0


def check_platform_speed(t, x, y, what: str, path, platform: str = "ownship") -> None:
    """Refuse positions that imply a speed above ``MAX_PLATFORM_SPEED_MPS`` (40 m/s) between two rows.

    Such a speed means kilometres or minutes written as metres or seconds.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Times (s), strictly increasing.
    x, y : ndarray, shape (n,)
        Positions east and north (m).
    platform : str, default "ownship"
        Name of the platform in the message.

    Raises
    ------
    InputError
        At the first too-fast step.
    """
    speed = np.hypot(np.diff(x), np.diff(y)) / np.diff(t)
    if np.any(speed > MAX_PLATFORM_SPEED_MPS):
        row = int(np.argmax(speed > MAX_PLATFORM_SPEED_MPS)) + 1
        raise InputError(f"{what} file {path}: the {platform} moves at {speed[row - 1]:.3g} m/s before data row "
                         f"{row + 1}: positions must be metres and times seconds")

"""An active scene's files: the layout, the writers of each file, and the checked readers.

``sonartrack simulate --kind active`` writes (``systems/simulate/active_files.py`` drives the simulator), and
``sonartrack active`` reads, one folder:

===================  ======================================================================================
pings/ping_0001.npy  one file per ping: complex64, (channels, samples), complex baseband at the carrier
                     (``|x|^2`` = mean-square pressure in Pa^2), sample 0 at the transmit time, element 0 the
                     front (nearest the ship); memory stays flat whatever the number of pings
ping_table.csv       ping, transmit_time_s, file, waveform (lfm | cw), fc_hz, bandwidth_hz, duration_s, fs_hz,
                     channels, samples
nav.csv              time_s, x_m, y_m, heading_deg (ownship), source_x_m, source_y_m, array_x_m, array_y_m,
                     array_heading_deg (array centre and axis); every second
truth.csv            per ping and target (sim/active_scene.py ``TRUTH_COLUMNS``)
scene.toml           the resolved scene settings
===================  ======================================================================================

Each file is written atomically (io/atomic.py). The readers refuse, in one line naming the fix: a ping file
whose channel count, sample count or type disagrees with the ping table, a sample count that is not the
table's listening window at its sample rate, a ping table that does not cover the navigation's pings, a
waveform the settings cannot describe (a zero-bandwidth LFM, a CW pulse as long as the ping interval).
"""

from __future__ import annotations

import io
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.atomic import write_bytes, write_csv
from sonartrack.io.tables import check_columns, check_sorted, numeric_column, read_table
from sonartrack.systems.active.records import ActiveNav, PingTable

PING_DIR = "pings"
PING_TABLE = "ping_table.csv"
NAV_FILE = "nav.csv"
TRUTH_FILE = "truth.csv"
SCENE_FILE = "scene.toml"
PING_TABLE_COLUMNS = ["ping", "transmit_time_s", "file", "waveform", "fc_hz", "bandwidth_hz", "duration_s", "fs_hz",
                      "channels", "samples"]
NAV_COLUMNS = ["time_s", "x_m", "y_m", "heading_deg", "source_x_m", "source_y_m", "array_x_m", "array_y_m",
               "array_heading_deg"]
CSV_FLOAT = "%.9g"


def ping_file(ping: int) -> str:
    """The file of ping number ``ping`` (1-based), relative to the scene folder.

    Parameters
    ----------
    ping : int
        The ping number (1-based).

    Returns
    -------
    str
        ``pings/ping_NNNN.npy`` (at least four digits).
    """
    return f"{PING_DIR}/ping_{int(ping):04d}.npy"


def write_ping(folder, ping: int, samples: np.ndarray) -> Path:
    """Write one ping's samples (channels, samples) as complex64 ``.npy``, atomically.

    Parameters
    ----------
    folder : str or path-like
        The scene folder (pings/ is created in it).
    ping : int
        The ping number (1-based).
    samples : numpy.ndarray
        (channels, samples) complex baseband (``|x|^2`` in Pa^2), element 0 the front.

    Returns
    -------
    Path
        The file written.
    """
    buf = io.BytesIO()
    np.save(buf, np.ascontiguousarray(samples, dtype=np.complex64), allow_pickle=False)
    path = Path(folder) / ping_file(ping)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_bytes(path, buf.getvalue())


def write_table(columns: dict, path) -> Path:
    """A dict of equal-length columns as CSV, atomically.

    Parameters
    ----------
    columns : dict
        Column name -> array, all of one length.
    path : str or path-like
        The CSV file to write (floats with 9 significant digits).

    Returns
    -------
    Path
        The file written.
    """
    import pandas as pd

    return write_csv(pd.DataFrame(columns), path, float_format=CSV_FLOAT)


def _checked_waveforms(df, path, interval_s: float) -> np.ndarray:
    """The waveform column, each row describable: lfm with bandwidth > 0, cw shorter than the ping interval."""
    kind = df["waveform"].astype(str).str.strip().str.lower().to_numpy()
    bad = ~np.isin(kind, ["lfm", "cw"])
    require(not bad.any(), f"ping table {path}: unknown waveform '{kind[np.argmax(bad)] if bad.any() else ''}' "
                           "(column waveform): write lfm or cw")
    bw = numeric_column(df, "bandwidth_hz", "ping table", path, lo=0.0)
    require(not np.any((kind == "lfm") & (bw <= 0)), f"ping table {path}: an LFM ping has bandwidth_hz 0 (a "
                                                    "zero-bandwidth LFM): give its swept band, or call it a cw")
    dur = numeric_column(df, "duration_s", "ping table", path, lo=0.0, lo_open=True)
    require(not np.any(dur >= interval_s), f"ping table {path}: a pulse of {dur.max():g} s is not shorter than the "
                                           f"ping interval ({interval_s:g} s): the echoes would overlap the next "
                                           "transmission; shorten duration_s")
    return kind


def read_ping_table(path) -> PingTable:
    """The ping table, checked (module doc).

    Parameters
    ----------
    path : str or path-like
        ping_table.csv.

    Returns
    -------
    PingTable
        One row per ping, in transmit order.
    """
    df = read_table(path, "ping table")
    check_columns(df, PING_TABLE_COLUMNS, "ping table", path)
    t = numeric_column(df, "transmit_time_s", "ping table", path, lo=0.0)
    check_sorted(t, "ping table", path, strict=True, col="transmit_time_s")
    interval = float(np.min(np.diff(t))) if t.size > 1 else np.inf
    kind = _checked_waveforms(df, path, interval)
    ping = numeric_column(df, "ping", "ping table", path, lo=1).astype(np.int64)
    require(np.unique(ping).size == ping.size, f"ping table {path}: repeated ping numbers: number each ping once")
    fs = numeric_column(df, "fs_hz", "ping table", path, lo=0.0, lo_open=True)
    samples = numeric_column(df, "samples", "ping table", path, lo=1).astype(np.int64)
    if np.isfinite(interval):
        require(bool(np.all(samples <= np.ceil(interval * fs) + 1)),
                f"ping table {path}: a ping holds more samples than fit in its ping interval at fs_hz ({interval:g} s "
                f"x {fs.max():g} Hz): check fs_hz (the sample rate of the ping files)")
    return PingTable(ping, t, df["file"].astype(str).to_numpy(), kind,
                     numeric_column(df, "fc_hz", "ping table", path, lo=0.0, lo_open=True),
                     numeric_column(df, "bandwidth_hz", "ping table", path, lo=0.0),
                     numeric_column(df, "duration_s", "ping table", path, lo=0.0, lo_open=True), fs,
                     numeric_column(df, "channels", "ping table", path, lo=1).astype(np.int64), samples)


def read_ping(folder, table: PingTable, i: int) -> np.ndarray:
    """Samples (channels, samples) complex64 of row ``i`` of ``table``, checked against the table.

    Parameters
    ----------
    folder : str or path-like
        The scene folder (the table's ``file`` paths are relative to it).
    table : PingTable
        The checked ping table.
    i : int
        Row of ``table`` (0-based, not the ping number).

    Returns
    -------
    numpy.ndarray
        (channels, samples) complex64 complex baseband; an InputError when the file is missing, not a complex
        .npy array, or its shape disagrees with the table.
    """
    p = Path(folder) / str(table.file[i])
    require(p.is_file(), f"ping {table.ping[i]}: file {p} is missing: the ping table and the pings folder disagree")
    try:
        x = np.load(p, mmap_mode="r", allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise InputError(f"ping {table.ping[i]}: {p} is not a NumPy .npy array ({exc}): write complex64 arrays "
                         "(channels, samples)") from None
    require(np.iscomplexobj(x), f"ping {table.ping[i]}: {p} holds {x.dtype} samples, not complex baseband: give "
                                "complex64 (channels, samples)")
    require(x.ndim == 2 and x.shape[0] == table.channels[i],
            f"ping {table.ping[i]}: {p} has shape {x.shape} but the ping table says {table.channels[i]} channels: "
            "fix the channels column or the file")
    require(x.shape[1] == table.samples[i],
            f"ping {table.ping[i]}: {p} holds {x.shape[1]} samples but the ping table says {table.samples[i]} at "
            f"{table.fs_hz[i]:g} Hz: fix the samples / fs_hz columns or the file")
    return np.asarray(x, dtype=np.complex64)


def iter_pings(folder, table: PingTable) -> Iterator[tuple[int, float, np.ndarray]]:
    """(ping number, transmit time s, samples) of each ping in turn (one ping in memory at a time).

    Parameters
    ----------
    folder : str or path-like
        The scene folder.
    table : PingTable
        The checked ping table.

    Returns
    -------
    Iterator of (int, float, numpy.ndarray)
        Ping number, transmit time (s) and the (channels, samples) complex64 samples of :func:`read_ping`, in the
        table's order.
    """
    for i in range(len(table)):
        yield int(table.ping[i]), float(table.transmit_time_s[i]), read_ping(folder, table, i)


def read_active_nav(path) -> ActiveNav:
    """The navigation of an active scene (module doc), checked; headings unwrapped, in radians.

    Parameters
    ----------
    path : str or path-like
        nav.csv (columns ``NAV_COLUMNS``; positions x east, y north in m, headings in deg clockwise from north,
        times strictly increasing).

    Returns
    -------
    ActiveNav
        Times (s), ownship / source / array-centre positions (n, 2) m, ownship and array-axis headings (n,) rad,
        unwrapped.
    """
    df = read_table(path, "navigation")
    check_columns(df, NAV_COLUMNS, "navigation", path)

    def col(name, **kw):
        return numeric_column(df, name, "navigation", path, **kw)

    t = col("time_s")
    check_sorted(t, "navigation", path, strict=True)
    heading = {h: np.unwrap(np.deg2rad(col(h, lo=-360.0, hi=720.0))) for h in ("heading_deg", "array_heading_deg")}
    xy = {p: np.stack([col(f"{p}x_m"), col(f"{p}y_m")], axis=-1) for p in ("", "source_", "array_")}
    return ActiveNav(t, xy[""], heading["heading_deg"], xy["source_"], xy["array_"], heading["array_heading_deg"])


def check_nav_covers(table: PingTable, nav: ActiveNav, slack_s: float = 1.0) -> None:
    """The navigation must span every ping's transmit time (within ``slack_s``).

    Parameters
    ----------
    table : PingTable
        The ping table (transmit times in s, increasing).
    nav : ActiveNav
        The navigation.
    slack_s : float
        How far (s) the navigation may stop short of the first and last transmit times.

    Returns
    -------
    None
        Raises InputError when the navigation does not cover the pings.
    """
    t0, t1 = float(table.transmit_time_s[0]), float(table.transmit_time_s[-1])
    require(nav.time_s[0] <= t0 + slack_s and nav.time_s[-1] >= t1 - slack_s,
            f"the navigation ({nav.time_s[0]:g}..{nav.time_s[-1]:g} s) does not cover the pings ({t0:g}..{t1:g} s): "
            "give the navigation of the whole ping sequence")


def read_truth(path):
    """truth.csv as a pandas DataFrame (scoring and studies; the chain never reads it).

    Parameters
    ----------
    path : str or path-like
        truth.csv of the scene.

    Returns
    -------
    pandas.DataFrame
        The file's columns as read (sim/active_scene.py ``TRUTH_COLUMNS``).
    """
    return read_table(path, "truth")

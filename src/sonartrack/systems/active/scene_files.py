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
table's listening window at its sample rate, a ping file that is not one .npy array (an .npz archive), a sample
that is NaN or infinite, a ping table that does not cover the navigation's pings, a waveform the settings cannot
describe (a zero-bandwidth LFM, a CW pulse as long as the ping interval, a pulse of fewer than
:data:`MIN_PULSE_SAMPLES` samples, a band wider than the sample rate).
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
#: a pulse of fewer samples than this makes no matched filter (its replica is a click, its band undefined); the
#: simulator refuses the same (sim/active_scene.py)
MIN_PULSE_SAMPLES = 4


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


def write_error(exc: OSError, path) -> Exception:
    """A failed write as one line naming the file: a full disk, a quota or a file-size limit (the user's to change)
    as an InputError with the fix, any other as the OSError with the file's name (a write error carries none).

    Parameters
    ----------
    exc : OSError
        The error of the write.
    path : str or path-like
        The file being written.

    Returns
    -------
    Exception
        The error to raise (``from None``).
    """
    import errno

    if exc.errno in (errno.EFBIG, errno.ENOSPC, errno.EDQUOT):
        return InputError(f"cannot write {path}: {exc.strerror} (a full disk, a quota or a file-size limit such as "
                          "ulimit -f): no output was changed; free space, raise the limit or give another --out")
    return OSError(exc.errno, exc.strerror, str(path))


def ping_bytes(samples: np.ndarray) -> bytes:
    """One ping's samples (channels, samples) as the bytes of a complex64 ``.npy`` file.

    Parameters
    ----------
    samples : numpy.ndarray
        (channels, samples) complex baseband (``|x|^2`` in Pa^2), element 0 the front.

    Returns
    -------
    bytes
        The file's content.
    """
    buf = io.BytesIO()
    np.save(buf, np.ascontiguousarray(samples, dtype=np.complex64), allow_pickle=False)
    return buf.getvalue()


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
    path = Path(folder) / ping_file(ping)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_bytes(path, ping_bytes(samples))


def table_text(columns: dict) -> str:
    """A dict of equal-length columns as CSV text (floats with 9 significant digits).

    Parameters
    ----------
    columns : dict
        Column name -> array, all of one length.

    Returns
    -------
    str
        The CSV, a header line then a line per row.
    """
    import pandas as pd

    return pd.DataFrame(columns).to_csv(index=False, float_format=CSV_FLOAT)


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
    fs = numeric_column(df, "fs_hz", "ping table", path, lo=0.0, lo_open=True)
    short = dur * fs < MIN_PULSE_SAMPLES
    require(not short.any(), f"ping table {path}: ping {df['ping'].iloc[int(np.argmax(short))]}'s pulse of "
                             f"{dur[np.argmax(short)]:g} s holds {dur[np.argmax(short)] * fs[np.argmax(short)]:.3g} "
                             f"samples at fs_hz {fs[np.argmax(short)]:g}, fewer than {MIN_PULSE_SAMPLES}: no matched "
                             "filter can be made of it; check duration_s (seconds) and fs_hz (Hz)")
    wide = bw >= fs
    require(not wide.any(), f"ping table {path}: ping {df['ping'].iloc[int(np.argmax(wide))]}'s band "
                            f"{bw[np.argmax(wide)]:g} Hz does not fit its complex baseband at fs_hz "
                            f"{fs[np.argmax(wide)]:g} (the sweep's edges +-bandwidth_hz / 2 must lie inside "
                            "+-fs_hz / 2, Nyquist): check bandwidth_hz and fs_hz (Hz)")
    fc = numeric_column(df, "fc_hz", "ping table", path, lo=0.0, lo_open=True)
    below = bw >= 2.0 * fc
    require(not below.any(), f"ping table {path}: ping {df['ping'].iloc[int(np.argmax(below))]}'s band "
                             f"{bw[np.argmax(below)]:g} Hz around fc_hz {fc[np.argmax(below)]:g} reaches 0 Hz or "
                             "below: the sweep fc_hz +- bandwidth_hz / 2 must lie above 0 Hz; check fc_hz and "
                             "bandwidth_hz (Hz)")
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
    except (ValueError, OSError, EOFError) as exc:
        raise InputError(f"ping {table.ping[i]}: {p} is not a NumPy .npy array ({exc}): write complex64 arrays "
                         "(channels, samples)") from None
    if not isinstance(x, np.ndarray):  # an .npz archive (np.load opens a zip whatever the file's name)
        getattr(x, "close", lambda: None)()
        raise InputError(f"ping {table.ping[i]}: {p} is a {type(x).__name__} (an .npz archive), not a NumPy .npy "
                         "array: save each ping with np.save as complex64 (channels, samples)")
    require(np.iscomplexobj(x), f"ping {table.ping[i]}: {p} holds {x.dtype} samples, not complex baseband: give "
                                "complex64 (channels, samples)")
    require(x.ndim == 2 and x.shape[0] == table.channels[i],
            f"ping {table.ping[i]}: {p} has shape {x.shape} but the ping table says {table.channels[i]} channels: "
            "fix the channels column or the file")
    require(x.shape[1] == table.samples[i],
            f"ping {table.ping[i]}: {p} holds {x.shape[1]} samples but the ping table says {table.samples[i]} at "
            f"{table.fs_hz[i]:g} Hz: fix the samples / fs_hz columns or the file")
    with np.errstate(over="ignore", invalid="ignore"):  # a value complex64 cannot hold becomes inf: refused next
        x = np.asarray(x, dtype=np.complex64)
    _check_finite(x, p, int(table.ping[i]), float(table.fs_hz[i]))
    return x


def _check_finite(x: np.ndarray, path, ping: int, fs_hz: float) -> None:
    """Refuse a ping holding a NaN or an infinity (or a value complex64 cannot hold), naming the first.

    One such sample spreads through the beams' FFTs to every cell of the ping (no detection survives it), and
    through the MFTD's stack to the next K - 1 pings': an answer that is not one."""
    bad = ~np.isfinite(x)
    if bad.any():
        ch, k = (int(v) for v in np.unravel_index(int(np.argmax(bad)), x.shape))
        raise InputError(f"ping {ping}: {path} holds {int(bad.sum())} non-finite sample(s), the first {x[ch, k]} at "
                         f"channel {ch} (from 0), sample {k} ({k / fs_hz:.6g} s): give finite samples (replace or "
                         "drop this ping and its row of the ping table)")


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

"""The chain on files: a recording and its navigation in; peaks.csv, bearing_tracks.csv, targets.csv, levels.csv and
lines.csv out (systems/passive/tables.py and :func:`lines_table`, written atomically; targets.csv with an ``origin``
column: ``broadband`` for a bearing track's target, ``narrowband`` for a target found by its tonal lines).
``sonartrack passive`` and every recording of ``sonartrack survey`` run through :func:`run_passive_recording`, so
the two read their inputs the same way.

Recording: one file or a sequence of consecutive files -- a folder, or a glob pattern -- read as one recording
on one time axis from its first sample (io/recording_sequence.py: start times from the file names or Broadcast
WAV headers; gaps and overlaps found and reported; WAV, RF64, W64 or FLAC, 16/24/32-bit PCM or float,
io/wav_blocks.py). A window that a gap touches is handed to the chain as zeros: its beam powers are zero, the
normaliser finds no peak in it, so the gap is a blank stretch of the bearing-time record and the tracker sees
empty scans (a track lives through a short gap and is dropped after a long one) -- never a silent join of the
audio on either side. Files of different channel counts or sample rates are refused.

Calibration (io/calibration.py): the samples times ``V_fs 1e-6 / 10^((S + G) / 20)`` are pascals; none: they
are pascals already. The per-window broadband level of the recording, 10 log10(mean over elements and samples
of p^2 / (1 uPa)^2) in dB re 1 uPa, is measured as the beamformer reads each window (no extra pass) and
written to levels.csv (empty where a gap is).

Navigation, told apart by the file's suffix and else by its first lines: a table in seconds from the
recording's start (.csv, .parquet; io/navigation.py), an NMEA 0183 log (.nmea, .txt, .log or ``$`` sentences;
io/nmea.py) or a GPX track (.gpx or ``<gpx``; io/gpx.py). The last two are in UTC: they are aligned with the
recording's UTC start, projected to local x/y (azimuthal equidistant about the first fix) and the array placed
``tow_length_m`` behind the ship along its track (the tow model of io/nmea.py; a tow length beyond 10 km refused).
A UTC log is checked before it is used (io/nav_checks.py): fixes that jump away and back are dropped and reported,
a track faster than 60 kn is refused, and so is a logged heading that is not the course made good (radians, a
hemisphere letter wrong on every fix).

Navigation gaps (io/nav_checks.py ``navigation_gaps``, every kind): a hole in the navigation over the recording is
reported in a warning; where the ship turned or changed speed in it, the range of every target tracked across it
(until the tow lag after it) is NOT DETERMINED, reason "navigation gap A-B s during the track, ..." in targets.csv
and the summary (systems/passive/nav_flags.py). A batch ML solution faster than ``verdict.max_speed_mps`` is not
printed as determined either (nav_flags.py ``bound_batch_speed``: reason "diverged", as the sequential filters'
verdict).

Glossary of the parameters: ``result``, the chain's result (:class:`~sonartrack.systems.passive.chain.PassiveResult`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.navigation import Navigation, check_array_fallback, check_navigation_covers, read_navigation
from sonartrack.io.recording_sequence import RecordingSequence, iter_sequence_blocks, open_sequence
from sonartrack.systems.passive.chain import PassiveResult, run_passive
from sonartrack.systems.passive.checks import (
    QUANTUM,
    check_aperture,
    check_memory,
    check_recording,
    excerpt_starts,
    first_pass,
)
from sonartrack.systems.passive.nav_flags import bound_batch_speed, flag_navigation_gaps, recording_gaps
from sonartrack.systems.passive.settings import PassiveSettings, PassiveStages
from sonartrack.systems.passive.tables import peaks_columns, targets_columns, write_columns_csv

#: navigation suffixes read as a table in seconds from the recording's start (io/navigation.py)
NAV_TABLE_SUFFIXES = (".csv", ".parquet", ".pq")
#: navigation suffixes read as NMEA 0183 (io/nmea.py)
NMEA_SUFFIXES = (".nmea", ".txt", ".log")
#: reference pressure of the levels (Pa)
P_REF_PA = 1e-6


@dataclass(frozen=True, slots=True)
class PassiveRun:
    """A run of the chain on files: its result, the recording as read (its UTC start, span, gaps and overlaps),
    and the broadband level of each window (dB re 1 uPa; NaN where a gap is)."""

    result: PassiveResult
    recording: RecordingSequence
    level_db: np.ndarray


@dataclass(frozen=True, slots=True)
class RecordingNavigation:
    """The navigation of a recording as read: the Navigation, warning lines, the times (s, on its base) of the
    log's samples whose gaps count (its fixes, and its heading sentences for a UTC log), and how long after a gap
    the array's position still rests on it (``lag_s``: tow length over speed; 0 when the array is given)."""

    nav: Navigation
    warnings: list[str] = field(default_factory=list)
    sample_times_s: tuple[np.ndarray, ...] = ()
    lag_s: float = 0.0


def navigation_kind(path) -> str:
    """``table``, ``nmea`` or ``gpx``: by the suffix, else by the file's first lines (module doc).

    Parameters
    ----------
    path : str or Path
        The navigation file.

    Returns
    -------
    str
        The kind; InputError (one line) when the file is missing or none of the three.
    """
    p = Path(path)
    require(not p.is_dir(), f"navigation {p} is a directory, not a file: give the navigation CSV, NMEA 0183 log or "
                            "GPX track inside it")
    require(p.is_file(), f"navigation file not found: {p}: give a navigation CSV, an NMEA 0183 log or a GPX track")
    suffix = p.suffix.lower()
    if suffix in NAV_TABLE_SUFFIXES:
        return "table"
    if suffix == ".gpx":
        return "gpx"
    if suffix in NMEA_SUFFIXES:
        return "nmea"
    with open(p, "rb") as fh:
        head = fh.read(4096).decode("ascii", "replace").lstrip("\ufeff \r\n\t")
    if head.startswith("<") and "<gpx" in head:
        return "gpx"
    if any(line.lstrip()[:1] == "$" or "$GP" in line or "$GN" in line for line in head.splitlines()[:20]):
        return "nmea"
    if head.split("\n", 1)[0].replace(" ", "").startswith("time_s,"):
        return "table"
    raise InputError(f"navigation {p} is neither a CSV (time_s, x_m, ...), an NMEA 0183 log ($..RMC lines) nor a "
                     "GPX track (<gpx>): give one of those (by suffix .csv, .nmea, .gpx)")


def read_recording_navigation(nav_path, seq: RecordingSequence, *, tow_length_m: float = 0.0
                              ) -> RecordingNavigation:
    """The navigation of a recording (module doc), with its warning lines.

    Parameters
    ----------
    nav_path : str or Path
        A navigation CSV/Parquet, an NMEA 0183 log or a GPX track.
    seq : RecordingSequence
        The recording (its UTC start aligns a UTC log).
    tow_length_m : float
        Array centre behind the ship along its track (m), for an NMEA/GPX log of the ship; 0: at the ship.

    Returns
    -------
    RecordingNavigation
        Times in seconds from the recording's first sample; warnings (skipped sentences, dropped fixes, the
        array-at-the-ship fallback).
    """
    from sonartrack.io.nmea import check_tow_length

    check_tow_length(tow_length_m)
    p = Path(nav_path)
    kind = navigation_kind(p)
    if kind == "table":
        nav = read_navigation(p)
        fallback = check_array_fallback(nav, p)
        return RecordingNavigation(nav, [fallback] if fallback else [], (nav.time_s,))
    return _read_utc_navigation(p, kind, seq, tow_length_m)


def _read_utc_navigation(p: Path, kind: str, seq: RecordingSequence, tow_length_m: float) -> RecordingNavigation:
    """:func:`read_recording_navigation` of an NMEA log or a GPX track (module doc)."""
    from sonartrack.io.nav_checks import check_logged_heading, drop_position_jumps
    from sonartrack.io.nmea import navigation_from_track

    require(seq.start_utc is not None, f"{p.name} is in UTC but the recording has no start time (none in its file "
                                       "names or headers): name the files by their start (rec_YYYYmmdd_HHMMSS.wav), "
                                       "or give the navigation as a CSV in seconds from the recording's start")
    warnings = []
    if kind == "gpx":
        from sonartrack.io.gpx import read_gpx

        track = read_gpx(p)
    else:
        from sonartrack.io.nmea import read_nmea

        log = read_nmea(p)
        track = log.track
        if log.counts.bad_checksum or log.counts.malformed:
            warnings.append(f"warning: NMEA log {p.name}: {log.counts.describe()}")
    track, dropped = drop_position_jumps(track, p)
    nav, _ = navigation_from_track(track, seq.start_utc, tow_length_m=tow_length_m)
    check_logged_heading(nav, track.heading_source, p)
    if tow_length_m <= 0:
        warnings.append(f"warning: the array is taken at the ship of {p.name} (tow length 0): give the tow length "
                        "for a towed array")
    t0 = seq.start_utc.timestamp()
    times = (nav.time_s,) + ((track.heading_time_unix_s - t0,) if track.heading_source != "none" else ())
    speed = np.median(np.hypot(np.diff(nav.x_m), np.diff(nav.y_m)) / np.diff(nav.time_s))
    lag_s = float(tow_length_m / speed) if speed > 0.1 else 0.0
    return RecordingNavigation(nav, warnings + dropped, times, min(lag_s, float(np.ptp(nav.time_s))))


def check_sequence(seq: RecordingSequence, stages: PassiveStages, n_windows: int, name: str) -> list[str]:
    """The checks of systems/passive/checks.py on a recording of one or more files: the array, then a first pass
    over a few excerpts (the windows a gap touches left out), on the samples as recorded.

    Parameters
    ----------
    seq : RecordingSequence
        The recording.
    stages : PassiveStages
        The chain's built settings.
    n_windows : int
        Windows the chain will read.
    name : str
        The recording's name in the messages.

    Returns
    -------
    list of str
        Warning lines; InputError for a recording that is no array recording (checks.py).
    """
    window_s = stages.settings.window_s
    window = int(round(window_s * seq.sample_rate_hz))
    check_aperture(stages.array, stages.band, window_s)
    spans = excerpt_starts(n_windows, window, seq.sample_rate_hz)
    fp = first_pass(((b for _, b in iter_sequence_blocks(seq, window, start_frame=a, stop_frame=e))
                     for a, e in spans), seq.sample_rate_hz)
    return check_recording(fp, name=name, array=stages.array, band=stages.band, window_s=window_s,
                           quantum=QUANTUM.get(seq.files[0].info.sample_format))


class SpanBlocks:
    """The chain's blocks (``blocks()`` once per pass): every window 0..n_windows - 1 of the recording's span,
    zeros where a gap touches it, scaled to pascals by ``pa_per_unit`` (channels,) unless None; the first pass
    also measures each window's broadband level (:attr:`level_db`, module doc).

    The blocks are float32 where the file's samples are exactly float32 (float32, 16- and 24-bit PCM:
    io/wav_blocks.py ``block_dtype``), the values the float64 blocks held, at half the copying; every stage casts
    them to its own precision. Scaled to pascals they are float64 (the product of the float64 calibration), and the
    level's mean square is summed in float64 (the same value to rounding)."""

    def __init__(self, seq: RecordingSequence, window: int, n_windows: int, pa_per_unit: np.ndarray | None):
        self.seq, self.window, self.n_windows, self.scale = seq, int(window), int(n_windows), pa_per_unit
        self.level_db = np.full(self.n_windows, np.nan)
        self._passes = 0

    def __call__(self):
        measure = self._passes == 0
        self._passes += 1
        zeros = np.zeros((self.seq.channels, self.window))
        present = iter_sequence_blocks(self.seq, self.window, stop_frame=self.n_windows * self.window, compact=True)
        nxt = next(present, None)
        for k in range(self.n_windows):
            if nxt is not None and int(round(nxt[0] * self.seq.sample_rate_hz)) == k * self.window:
                block, nxt = nxt[1], next(present, None)
                if self.scale is not None and block.dtype == np.float64:
                    block *= self.scale[:, None]
                elif self.scale is not None:
                    block = block * self.scale[:, None]  # float64, as the calibration: the same product
                if measure:
                    self.level_db[k] = _level_db(block)
                yield block
            else:
                yield zeros


def _level_db(block: np.ndarray) -> float:
    """10 log10(mean p^2 / p_ref^2) of a block (dB re 1 uPa; -inf for silence): the sum of squares as one BLAS dot
    in the block's own precision and memory order (no squared copy). A float32 dot's relative error, about 1e-6 for a
    window's 10^5-10^6 samples, is four orders below the 0.01 dB that levels.csv prints; a float64 einsum on float32
    blocks cost ten times as much (0.15 s of a 10-minute 32 x 8 kHz run)."""
    x = block.T if block.T.flags.c_contiguous else block
    v = np.ascontiguousarray(x).reshape(-1)
    ms = float(np.dot(v, v)) / v.size
    return 10.0 * np.log10(ms / P_REF_PA**2) if ms > 0 else -np.inf


def run_passive_recording(recording, nav_path, settings: PassiveSettings, *, calibration=None,
                          tow_length_m: float = 0.0, time_source: str = "auto", name_pattern=None,
                          progress=None) -> PassiveRun:
    """Read, check and run the chain on a recording of one or more files and its navigation (module doc).

    Parameters
    ----------
    recording : path or str
        A file, a folder of consecutive files, or a glob pattern (element 0 = front).
    nav_path : path
        Navigation CSV, NMEA 0183 log or GPX track.
    settings : PassiveSettings
        The chain's settings.
    calibration : path, optional
        Calibration TOML/CSV (io/calibration.py); None: the samples are pascals.
    tow_length_m : float
        Array behind the ship (m) for an NMEA/GPX log.
    time_source, name_pattern : str
        Where the files' start times come from (io/recording_sequence.py ``open_sequence``).
    progress : object, optional
        Progress hooks (:func:`~sonartrack.systems.passive.chain.run_passive`).

    Returns
    -------
    PassiveRun
        The result with the warning lines (gaps and overlaps among them), the recording, the window levels.
        Raises InputError on bad input (module doc, :func:`check_sequence`).
    """
    from sonartrack.io.calibration import level_warnings, read_calibration

    seq = open_sequence(recording, time_source=time_source, name_pattern=name_pattern)
    cal = read_calibration(calibration)
    scale = None if cal.is_identity else cal.pa_per_unit(seq.channels)
    stages = settings.stages(seq.sample_rate_hz, channels=seq.channels)
    window_s = stages.settings.window_s
    window = int(round(window_s * seq.sample_rate_hz))
    n_windows = seq.frames // window
    name = Path(str(recording).rstrip("/")).name
    require(n_windows >= 1, f"{name} lasts {seq.duration_s:.2f} s, less than one {window_s:g} s window")
    check_memory(stages, n_windows)
    navr = read_recording_navigation(nav_path, seq, tow_length_m=tow_length_m)
    nav, warnings = navr.nav, list(navr.warnings)
    check_navigation_covers(nav, 0.0, n_windows * window_s, path=f"navigation file {nav_path}")
    gaps = recording_gaps(navr, n_windows * window_s)
    warnings += [f"warning: {name}: {d.describe()} (left blank in the bearing-time record)" for d in seq.gaps]
    warnings += [f"warning: {name}: {d.describe()} (the later file's copy dropped)" for d in seq.overlaps]
    warnings += check_sequence(seq, stages, n_windows, name)
    blocks = SpanBlocks(seq, window, n_windows, scale)
    result = bound_batch_speed(run_passive(blocks, n_windows, nav, stages, progress=progress))
    result, gap_lines = flag_navigation_gaps(result, gaps, Path(nav_path).name)
    warnings += level_warnings(blocks.level_db, cal, name)  # levels are known only once the chain has read them
    return PassiveRun(replace(result, warnings=tuple(warnings + gap_lines) + result.warnings), seq, blocks.level_db)


def run_passive_files(wav_path, nav_path, settings: PassiveSettings, *, progress=None, **options) -> PassiveResult:
    """:func:`run_passive_recording`'s result alone (the chain on files, for callers that need no levels).

    Parameters
    ----------
    wav_path : path
        A recording file, folder or glob pattern.
    nav_path : path
        Navigation CSV, NMEA log or GPX track.
    settings : PassiveSettings
        The chain's settings.
    progress : object, optional
        Progress hooks.
    **options
        calibration, tow_length_m, time_source, name_pattern (:func:`run_passive_recording`).

    Returns
    -------
    PassiveResult
        The chain's result with the checks' warning lines.
    """
    return run_passive_recording(wav_path, nav_path, settings, progress=progress, **options).result


def levels_columns(level_db: np.ndarray, window_s: float) -> dict[str, np.ndarray]:
    """levels.csv's columns: time_s (window centre, s) and level_db_re_1upa (broadband, mean over elements; NaN,
    an empty cell, in a gap).

    Parameters
    ----------
    level_db : numpy.ndarray
        (windows,) broadband level of each window (dB re 1 uPa; NaN in a gap).
    window_s : float
        Window length (s); window k is centred at (k + 0.5) window_s.

    Returns
    -------
    dict of str to ndarray
        time_s (s) and level_db_re_1upa, one row per window.
    """
    level = np.asarray(level_db, float)
    return {"time_s": (np.arange(level.size) + 0.5) * window_s, "level_db_re_1upa": level}


def levels_table(level_db: np.ndarray, window_s: float):
    """levels.csv as a table (:func:`levels_columns`).

    Parameters
    ----------
    level_db : numpy.ndarray
        (windows,) broadband level of each window (dB re 1 uPa; NaN in a gap).
    window_s : float
        Window length (s).

    Returns
    -------
    pandas.DataFrame
        Columns time_s (s) and level_db_re_1upa, one row per window.
    """
    import pandas as pd

    return pd.DataFrame(levels_columns(level_db, window_s))


def origin_column(result: PassiveResult, target_id) -> np.ndarray:
    """``narrowband`` for the rows of targets found by their lines alone, ``broadband`` for the others.

    Parameters
    ----------
    result : PassiveResult
        The chain's result (``narrowband_target_ids``).
    target_id : array_like (n,)
        The rows' target ids.

    Returns
    -------
    ndarray of str (n,)
        The origin of each row.
    """
    nb = np.isin(np.asarray(target_id), list(result.narrowband_target_ids or ()))
    return np.where(nb, "narrowband", "broadband")


#: lines.csv's columns (:func:`lines_table`)
LINE_COLUMNS = ["line_id", "source_id", "target_id", "time_s", "frequency_hz", "cone_deg", "frequency_rate_hz_s",
                "cone_rate_deg_s", "snr_db", "measured_frequency_hz", "measured_cone_deg", "harmonic"]


def _harmonic_notes(source) -> dict[int, str]:
    """line id -> its harmonic note within its source (``n x f0`` of the family's fundamental, or the ratio)."""
    notes: dict[int, list[str]] = {}
    for lo, hi, q, p in source.harmonics:
        notes.setdefault(lo, []).append(f"{q}:{p} with line {hi}")
        notes.setdefault(hi, []).append(f"{p}:{q} with line {lo}")
    f0 = f"; family of {source.fundamental_hz:.2f} Hz" if np.isfinite(source.fundamental_hz) else ""
    return {k: ", ".join(v) + f0 for k, v in notes.items()}


def lines_columns(result: PassiveResult) -> dict[str, np.ndarray]:
    """lines.csv's columns: one row per line track per period: line and source ids, the target the source feeds
    or became (None, an empty cell: none), the period centre (s), the filtered frequency (Hz) and cone angle (deg)
    and their rates (Hz/s, deg/s), the detection's SNR (dB) and its refined frequency and cone angle (NaN where the
    period had no detection), and the line's harmonic relations within its source.

    Returns
    -------
    dict of str to ndarray
        The columns :data:`LINE_COLUMNS`; no rows when the narrowband pass did not run or found no line.
    """
    from sonartrack.systems.passive.tables import stack_column

    source_of = {i: src for src in result.line_sources for i in src.track_ids}
    feeds = result.source_targets or {}
    parts = []
    for ln in result.line_tracks:
        src = source_of.get(ln.track_id)
        n = len(ln.time_s)
        sid = src.source_id if src is not None else -1
        note = _harmonic_notes(src).get(ln.track_id, "") if src is not None else ""
        nan = np.full(n, np.nan)
        target = feeds.get(sid)
        parts.append({
            "line_id": np.full(n, ln.track_id), "source_id": np.full(n, sid),
            "target_id": np.full(n, None if target is None else int(target), dtype=object), "time_s": ln.time_s,
            "frequency_hz": ln.frequency_hz, "cone_deg": ln.cone_deg, "frequency_rate_hz_s": ln.frequency_rate_hz_s,
            "cone_rate_deg_s": ln.cone_rate_deg_s, "snr_db": ln.snr_db,
            "measured_frequency_hz": nan if ln.measured_frequency_hz is None else ln.measured_frequency_hz,
            "measured_cone_deg": nan if ln.measured_cone_deg is None else ln.measured_cone_deg,
            "harmonic": np.full(n, note)})
    if not parts:
        return {c: np.array([], dtype=object) for c in LINE_COLUMNS}
    return {c: stack_column([np.asarray(p[c]) for p in parts]) for c in LINE_COLUMNS}


def lines_table(result: PassiveResult):
    """lines.csv as a table (:func:`lines_columns`; target_id a nullable integer column).

    Returns
    -------
    pandas.DataFrame
        The rows (:data:`LINE_COLUMNS`); no rows when the narrowband pass did not run or found no line.
    """
    import pandas as pd

    cols = lines_columns(result)
    if not len(cols["line_id"]):
        return pd.DataFrame(columns=LINE_COLUMNS)
    return pd.DataFrame({**cols, "target_id": pd.array(list(cols["target_id"]), dtype="Int64")})


def passive_summary(result: PassiveResult) -> list[str]:
    """The summary lines (systems/passive/tables.py), a narrowband target's marked as such with its line.

    Returns
    -------
    list of str
        One line per target; a narrowband target's begins ``target k (narrowband, f Hz; line source s, ...``.
    """
    from sonartrack.systems.passive.tables import summary_lines

    lines = summary_lines(result)
    nb = set(result.narrowband_target_ids or ())
    if not nb or len(lines) != len(result.targets):
        return lines
    out = []
    for tg, line in zip(result.targets, lines, strict=True):
        if tg.target_id in nb:
            head = f"target {tg.target_id} (track {tg.track.track_id}, "
            mark = f"target {tg.target_id} (narrowband, {tg.tonal.line_hz:.1f} Hz; line source {tg.track.track_id}, "
            line = line.replace(head, mark, 1) if line.startswith(head) else f"{mark.rstrip(', ')}): {line}"
        out.append(line)
    return out


def write_passive_tables(result: PassiveResult, out: Path, level_db: np.ndarray | None = None) -> list[Path]:
    """Write the chain's tables.

    Parameters
    ----------
    result : PassiveResult
        The chain's result.
    out : path
        The output folder.
    level_db : ndarray, optional
        Window levels (dB re 1 uPa; :class:`PassiveRun`): levels.csv is written when given.

    Returns
    -------
    list of Path
        peaks.csv, bearing_tracks.csv (tracking/run.py PEAK_TRACK_COLUMNS), targets.csv (with ``origin``)[,
        levels.csv][, lines.csv when the narrowband pass ran] in ``out``.
    """
    from sonartrack.tracking.run import PEAK_TRACK_COLUMNS

    out = Path(out)
    targets = targets_columns(result)
    targets = {"target_id": targets.pop("target_id"), "origin": None, **targets}
    targets["origin"] = origin_column(result, targets["target_id"])
    paths = [write_columns_csv(peaks_columns(result.record), out / "peaks.csv"),
             write_columns_csv({c: getattr(result.tracks, c) for c in PEAK_TRACK_COLUMNS}, out / "bearing_tracks.csv"),
             write_columns_csv(targets, out / "targets.csv")]
    if level_db is not None:
        paths.append(write_columns_csv(levels_columns(level_db, result.settings.window_s), out / "levels.csv",
                                       float_format="%.2f"))
    if result.narrowband_target_ids is not None:
        paths.append(write_columns_csv(lines_columns(result), out / "lines.csv"))
    return paths

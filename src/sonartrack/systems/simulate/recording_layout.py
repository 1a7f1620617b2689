"""How ``sonartrack simulate`` lays out its recording: the format, one file or a folder of consecutive files with
a gap, a calibration for integer samples, and the navigation as an NMEA 0183 log -- the shapes real recorders
and navigation loggers give, so that ``passive`` and ``survey`` are tried on them.

Formats (:data:`FORMATS`): ``wav`` 32-bit float WAV of pressure in Pa (the default: ``recording.wav``, byte for
byte what simulate has always written), ``rf64`` the same samples in RF64 (EBU Tech 3306, 64-bit sizes),
``wav24`` 24-bit PCM WAV and ``flac`` 24-bit FLAC (at most 8 channels: the FLAC frame header codes 1..8). A
``.wav`` whose data passes 4 GiB is written as RF64 on its own (io/recording_writer.py). Integer samples are
p / :data:`FULL_SCALE_PA` (a pressure of 100 Pa, 160 dB re 1 uPa, is full scale; the quantisation step, 1.2e-5
Pa, lies 80 dB below the default ambient noise), and ``calibration.toml`` states the chain that turns them back
into pascals (io/calibration.py: p = x V_fs 1e-6 / 10^((S + G) / 20) Pa): a hydrophone of :data:`SENSITIVITY_DB`
dB re 1 V/uPa behind a gain of :data:`GAIN_DB` dB into a recorder whose full scale is :data:`FULL_SCALE_V` V,
so that 1 V is 100 Pa. A sample beyond full scale is refused (clipped data is never written).

Files (``split_s``): the recording as consecutive files of ``split_s`` seconds in the folder ``recording/``,
named by their UTC start as ``rec_YYYYmmdd_HHMMSS`` (the pattern io/recording_sequence.py reads by default),
the first starting at ``start_utc``; file k holds seconds k split_s .. (k + 1) split_s of the recording.
``gap_s`` leaves out the first ``gap_s`` seconds of the second file (seconds split_s .. split_s + gap_s are
never written, and that file is named by its later start): a gap between the first and second files. With
``--nmea`` and no split the recording is one such named file in ``recording/``, so that its UTC start is known.

NMEA (``nmea``): ``nav.nmea``, one RMC + HDT pair per second of the ownship (io/nmea.py ``write_nmea``):
positions from nav.csv's x_m, y_m through the azimuthal equidistant projection about :data:`ORIGIN_DEG`
(io/nmea.py ``LocalProjection``, the projection the reader inverts), times from ``start_utc``, heading from
nav.csv, speed and course over ground from the track. The log is the ship's: the reader places the array
``array.tow_length_m`` behind it (give that tow length to ``passive --tow-length`` or the manifest).

Manifest (``manifest``): ``manifest.csv``, this recording's line of a survey manifest (name = the output
folder's name, recording, navigation, spacing, calibration, tow length), so that ``sonartrack survey --manifest
A/manifest.csv --manifest B/manifest.csv`` runs several simulated recordings.
"""

from __future__ import annotations

import math
from contextlib import ExitStack
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require

#: --format -> (sample format, file suffix, what it is)
FORMATS = {"wav": ("float32", ".wav", "32-bit float WAV"), "rf64": ("float32", ".rf64", "32-bit float RF64"),
           "wav24": ("int24", ".wav", "24-bit PCM WAV"), "flac": ("int24", ".flac", "24-bit FLAC")}
#: UTC time of the recording's first sample when none is given
START_UTC = datetime(2024, 5, 17, 12, 0, 0, tzinfo=UTC)
#: (latitude, longitude) (deg, WGS84) of the scene's x = y = 0: the NMEA log's projection origin (off Plymouth)
ORIGIN_DEG = (50.0, -4.0)
#: pressure (Pa) of an integer recording's full-scale sample
FULL_SCALE_PA = 100.0
#: calibration.toml of integer recordings: sensitivity (dB re 1 V/uPa), gain (dB), full-scale voltage (V)
SENSITIVITY_DB, GAIN_DB, FULL_SCALE_V = -170.0, 10.0, 1.0
#: the folder of a split (or timed) recording, and the name of each file (strftime)
FOLDER, NAME_FORMAT = "recording", "rec_%Y%m%d_%H%M%S"
_KN = 3600.0 / 1852.0


@dataclass(frozen=True, slots=True)
class RecordingLayout:
    """The recording's format (:data:`FORMATS`), file length ``split_s`` (whole seconds; None: one file), the gap
    ``gap_s`` (whole seconds) left after the first file, whether an NMEA log is written, the UTC start, and
    whether a survey manifest line (manifest.csv) is written."""

    format: str = "wav"
    split_s: int | None = None
    gap_s: int = 0
    nmea: bool = False
    start_utc: datetime = START_UTC
    manifest: bool = False

    @property
    def sample_format(self) -> str:
        """The sample format of ``format`` in :data:`FORMATS`: "float32" or "int24"."""
        return FORMATS[self.format][0]

    @property
    def suffix(self) -> str:
        """The file name suffix of ``format`` in :data:`FORMATS` (".wav", ".rf64" or ".flac")."""
        return FORMATS[self.format][1]

    @property
    def timed(self) -> bool:
        """The recording is written as named files in ``recording/`` (split, or with an NMEA log)."""
        return self.split_s is not None or self.nmea

    @property
    def integer(self) -> bool:
        """The samples are integers (int24: scaled by :data:`FULL_SCALE_PA`, with a calibration.toml)."""
        return self.sample_format.startswith("int")


def _whole_seconds(value, what: str, low: int) -> int | None:
    if value is None:
        return None
    v = float(value)
    require(math.isfinite(v) and v == round(v) and v >= low, f"{what} must be a whole number of seconds >= {low} (the "
                                                             f"file names give the start to the second), got {value:g}")
    return int(v)


def make_layout(format: str = "wav", split_s=None, gap_s=None, nmea: bool = False,
                start_utc: str | datetime | None = None, manifest: bool = False) -> RecordingLayout:
    """The layout from the command line's options, each checked (one line naming the option and the fix).

    Parameters
    ----------
    format : str
        wav, rf64, wav24 or flac.
    split_s, gap_s : float, optional
        File length and gap (s, whole seconds).
    nmea : bool
        Write nav.nmea.
    start_utc : str or datetime, optional
        ISO 8601 UTC time of the first sample (default :data:`START_UTC`).
    manifest : bool
        Write manifest.csv.

    Returns
    -------
    RecordingLayout
        The layout (the scene's own checks: :func:`check_layout`).
    """
    require(format in FORMATS, f"unknown --format '{format}': choose {', '.join(FORMATS)}")
    split = _whole_seconds(split_s, "--split-s", 1)
    gap = _whole_seconds(gap_s, "--gap-s", 0) or 0
    require(gap == 0 or split is not None, "--gap-s needs --split-s: the gap lies between the first and second files")
    if start_utc is None:
        start = START_UTC
    elif isinstance(start_utc, datetime):
        start = start_utc
    else:
        try:
            start = datetime.fromisoformat(str(start_utc).replace("Z", "+00:00"))
        except ValueError:
            raise InputError(f"--start-utc '{start_utc}' is no ISO 8601 time: give e.g. 2024-05-17T12:00:00Z") from None
    start = start.replace(tzinfo=UTC) if start.tzinfo is None else start.astimezone(UTC)
    require(start.microsecond == 0, "--start-utc must be a whole second (the file names give the start to the second)")
    return RecordingLayout(format, split, gap, bool(nmea), start, bool(manifest))


def check_layout(layout: RecordingLayout, channels: int, duration_s: float) -> None:
    """Refuse, before anything is written, a layout the scene cannot have: FLAC of more than 8 channels, a gap
    that leaves the second file empty or that no second file follows.

    Parameters
    ----------
    layout : RecordingLayout
        The layout.
    channels : int
        The array's elements.
    duration_s : float
        The recording's length (s).
    """
    from sonartrack.io.recording_writer import FLAC_MAX_CHANNELS

    require(layout.format != "flac" or channels <= FLAC_MAX_CHANNELS,
            f"--format flac holds at most {FLAC_MAX_CHANNELS} channels but the scene's array has {channels} elements: "
            "give --format wav24 (24-bit WAV) or a scene with [array] elements = 8 or fewer")
    if layout.gap_s:
        require(layout.split_s + layout.gap_s < min(2 * layout.split_s, duration_s),
                f"--gap-s {layout.gap_s} leaves nothing of the second file (files of {layout.split_s} s, "
                f"{duration_s:g} s recorded): give a gap shorter than --split-s and a duration over split + gap")


def file_spans(layout: RecordingLayout, frames: int, sample_rate_hz: float) -> list[tuple[int, int]]:
    """Frames (start, stop) of the recording written to each file, in order (module doc).

    Parameters
    ----------
    layout : RecordingLayout
        File length ``split_s`` and gap ``gap_s`` (s).
    frames : int
        Frames of the whole recording.
    sample_rate_hz : float
        Sample rate (Hz).

    Returns
    -------
    list of (int, int)
        Half-open frame ranges; with a gap the second file starts ``gap_s`` later (those frames are not written).
    """
    if layout.split_s is None:
        return [(0, int(frames))]
    s = int(round(layout.split_s * sample_rate_hz))
    spans = [(a, min(a + s, int(frames))) for a in range(0, int(frames), s)]
    if layout.gap_s and len(spans) > 1:
        spans[1] = (spans[1][0] + int(round(layout.gap_s * sample_rate_hz)), spans[1][1])
    return spans


def recording_paths(folder: Path, layout: RecordingLayout, spans, sample_rate_hz: float) -> list[Path]:
    """The file of each span: ``recording.<suffix>``, or ``recording/rec_<UTC start>.<suffix>`` (module doc).

    Parameters
    ----------
    folder : Path
        The scene folder.
    layout : RecordingLayout
        Format, UTC start, and whether the recording is split or timed.
    spans : list of (int, int)
        :func:`file_spans`.
    sample_rate_hz : float
        Sample rate (Hz), to turn a span's first frame into its UTC start.

    Returns
    -------
    list of Path
        One path per span (one path when the layout is not timed).
    """
    if not layout.timed:
        return [Path(folder) / f"recording{layout.suffix}"]
    return [Path(folder) / FOLDER / f"{layout.start_utc + timedelta(seconds=a / sample_rate_hz):{NAME_FORMAT}}"
            f"{layout.suffix}" for a, _ in spans]


class LayoutWriter:
    """Takes the recording's (channels, m) blocks in order and writes each frame to its file (or to none, in the
    gap); each file is written atomically and closed when its last frame is in."""

    def __init__(self, folder: Path, layout: RecordingLayout, channels: int, sample_rate_hz: float, frames: int):
        self.layout, self.channels, self.fs, self.frames = layout, int(channels), float(sample_rate_hz), int(frames)
        self.spans = file_spans(layout, frames, sample_rate_hz)
        self.paths = recording_paths(folder, layout, self.spans, sample_rate_hz)
        if layout.timed:
            (Path(folder) / FOLDER).mkdir(parents=True, exist_ok=True)
        self._pos, self._k, self._open = 0, 0, None
        self._scale = 1.0 / FULL_SCALE_PA if layout.integer else 1.0

    def _writer(self, k: int):
        from sonartrack.io.recording_writer import recording_writer

        if self._open is not None and self._open[0] == k:
            return self._open[2]
        self._close_current(None)
        a, b = self.spans[k]
        stack = ExitStack()
        w = stack.enter_context(recording_writer(self.paths[k], self.channels, self.fs, self.layout.sample_format,
                                                 expected_frames=b - a))
        self._open = (k, stack, w)
        return w

    def _close_current(self, exc) -> None:
        if self._open is not None:
            _, stack, _ = self._open
            self._open = None
            if exc is None:
                stack.close()
            else:  # the atomic writer sees the exception and removes its hidden file
                stack.__exit__(type(exc), exc, exc.__traceback__)

    def _check_full_scale(self, x: np.ndarray) -> None:
        peak = float(np.max(np.abs(x))) if x.size else 0.0
        if self.layout.integer and not peak < FULL_SCALE_PA:
            raise InputError(f"the recording reaches {peak:.3g} Pa at {self._pos / self.fs:.0f} s, beyond the "
                             f"{FULL_SCALE_PA:g} Pa full scale of its 24-bit samples: write it as float (--format "
                             "wav or rf64), or make the loud ship quieter or further away")

    def write(self, block) -> None:
        """Append a (channels, m) block of pressure (Pa) at the recording's current position.

        Parameters
        ----------
        block : array_like, shape (channels, m)
            Pressure (Pa); a sample beyond full scale of an integer format is refused. Frames that fall in the gap
            are dropped.
        """
        x = np.asarray(block, dtype=np.float64)
        self._check_full_scale(x)
        lo, hi = self._pos, self._pos + x.shape[1]
        for k in range(self._k, len(self.spans)):
            a, b = self.spans[k]
            if a >= hi:
                break
            if b > lo:
                self._writer(k).write(x[:, max(a, lo) - lo: min(b, hi) - lo] * self._scale)
            if b <= hi:
                self._close_current(None)
                self._k = k + 1
        self._pos = hi

    def close(self, exc=None) -> None:
        """Finish (or, on ``exc``, discard) the file still open.

        Parameters
        ----------
        exc : BaseException, optional
            The error that stopped the writing; the open file is then discarded.
        """
        self._close_current(exc)


def layout_writer(stack: ExitStack, folder: Path, layout: RecordingLayout, channels: int, sample_rate_hz: float,
                  frames: int) -> LayoutWriter:
    """A :class:`LayoutWriter` whose open file is finished when ``stack`` closes (discarded if it closes on an
    exception).

    Parameters
    ----------
    stack : ExitStack
        The caller's stack of open writers.
    folder : Path
        The scene's output folder.
    layout : RecordingLayout
        The layout.
    channels : int
        The array's elements.
    sample_rate_hz : float
        Sample rate (Hz).
    frames : int
        Frames of the whole recording.

    Returns
    -------
    LayoutWriter
        ``write(block)``; ``paths`` the recording's files.
    """
    writer = LayoutWriter(folder, layout, channels, sample_rate_hz, frames)

    def _exit(exc_type, exc, tb):
        writer.close(exc)
        return False

    stack.push(_exit)
    return writer


def write_layout_extras(folder: Path, layout: RecordingLayout, nav: dict, scene) -> list[Path]:
    """calibration.toml (integer samples), nav.nmea (``layout.nmea``) and manifest.csv (``layout.manifest``).

    Parameters
    ----------
    folder : Path
        The scene's output folder.
    layout : RecordingLayout
        The layout.
    nav : dict of str to ndarray
        nav.csv's columns (time_s, x_m, y_m, heading_deg).
    scene : PassiveSceneSettings
        The scene.

    Returns
    -------
    list of Path
        The files written.
    """
    from sonartrack.io.atomic import write_text

    paths = []
    if layout.integer:
        paths.append(write_text(folder / "calibration.toml", (
            f"# {FORMATS[layout.format][2]}: samples x in [-1, 1); p = x {FULL_SCALE_PA:g} Pa (io/calibration.py)\n"
            f"sensitivity_db = {SENSITIVITY_DB}   # dB re 1 V/uPa\ngain_db = {GAIN_DB}   # dB\n"
            f"full_scale_v = {FULL_SCALE_V}   # V at sample value 1.0\n")))
    if layout.nmea:
        paths.append(write_ship_nmea(folder / "nav.nmea", nav, layout.start_utc))
    if layout.manifest:
        paths.append(write_manifest_line(folder, layout, scene))
    return paths


def write_manifest_line(folder: Path, layout: RecordingLayout, scene) -> Path:
    """manifest.csv: the survey manifest (systems/survey/manifest.py) of this one recording, paths relative to
    ``folder``, named by the folder; several such files make a survey (``survey --manifest A --manifest B``).

    Parameters
    ----------
    folder : Path
        The scene's output folder.
    layout : RecordingLayout
        The layout (which recording, navigation and calibration files there are).
    scene : PassiveSceneSettings
        The scene (spacing, tow length).

    Returns
    -------
    Path
        The file written.
    """
    from sonartrack.io.atomic import write_text

    recording = f"{FOLDER}/" if layout.timed else f"recording{layout.suffix}"
    nav, tow = ("nav.nmea", f"{scene.array.tow_length_m:g}") if layout.nmea else ("nav.csv", "")
    cal = "calibration.toml" if layout.integer else ""
    return write_text(folder / "manifest.csv", "name,recording,navigation,spacing_m,calibration,tow_length_m\n"
                      f"{Path(folder).absolute().name},{recording},{nav},{scene.spacing_m:g},{cal},{tow}\n")


def write_ship_nmea(path: Path, nav: dict, start_utc: datetime) -> Path:
    """The ownship of ``nav`` (time_s, x_m, y_m, heading_deg) as an NMEA log from ``start_utc`` (module doc).

    Parameters
    ----------
    path : Path
        The .nmea file.
    nav : dict of str to ndarray
        Times (s), positions (m east, north of :data:`ORIGIN_DEG`), headings (deg).
    start_utc : datetime
        UTC time of time_s = 0.

    Returns
    -------
    Path
        The file written.
    """
    from sonartrack.io.nmea import LocalProjection, write_nmea

    t, x, y = (np.asarray(nav[k], float) for k in ("time_s", "x_m", "y_m"))
    lat, lon = LocalProjection(*ORIGIN_DEG).latlon(x, y)
    vx, vy = (np.gradient(v, t) for v in (x, y))
    return write_nmea(path, start_utc.timestamp() + t, lat, lon, np.asarray(nav["heading_deg"], float),
                      np.hypot(vx, vy) * _KN, np.rad2deg(np.arctan2(vx, vy)) % 360.0)


def describe_layout(layout: RecordingLayout, duration_s: float, sample_rate_hz: float) -> str:
    """One line: the recording's format and files, the gap, the calibration and the NMEA log.

    Parameters
    ----------
    layout : RecordingLayout
        The layout.
    duration_s, sample_rate_hz : float
        The recording's length (s) and sample rate (Hz).

    Returns
    -------
    str
        The line.
    """
    spans = file_spans(layout, round(duration_s * sample_rate_hz), sample_rate_hz)
    where = f"recording{layout.suffix}" if not layout.timed else f"{FOLDER}/ ({len(spans)} file(s) {NAME_FORMAT})"
    line = f"recording: {where}, {FORMATS[layout.format][2]}"
    if layout.gap_s and len(spans) > 1:
        line += f"; a gap of {layout.gap_s} s at {spans[0][1] / sample_rate_hz:g} s (between the first two files)"
    if layout.integer:
        line += "; calibration.toml"
    if layout.nmea:
        line += (f"; nav.nmea (UTC from {layout.start_utc:%Y-%m-%dT%H:%M:%SZ}, about {ORIGIN_DEG[0]:g} N "
                 f"{-ORIGIN_DEG[1]:g} W)")
    if layout.manifest:
        line += "; manifest.csv"
    return line

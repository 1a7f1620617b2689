"""The survey manifest: one line per recording.

CSV with a header; required columns ``recording`` (a file, a folder of consecutive files or a glob pattern:
io/recording_sequence.py), ``navigation`` (a navigation CSV in seconds from the recording's start,
io/navigation.py; an NMEA 0183 log, io/nmea.py; or a GPX track, io/gpx.py: the last two in UTC, aligned with
the recording's start time from its file names or headers) and ``spacing_m`` (the array's element spacing,
m); optional ``name`` (default: the recording's file or folder name), ``calibration`` (io/calibration.py),
``settings`` (a TOML file of passive settings, ``sonartrack passive --print-config``), ``tow_length_m`` (the
array centre behind the ship along its track for an NMEA/GPX log of the ship, default 0: the array at the
ship), ``name_pattern`` (strptime pattern of the start times in the file names) and ``time_source`` (auto,
header, names, contiguous). Paths are relative to the manifest's folder; an empty cell is a value not given.

A missing file or a missing column refuses the whole manifest; a line whose own values are wrong (a spacing
that is no number, a duplicate name) is kept with its problem, so that the survey reports that recording as
failed and goes on with the others.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path

from sonartrack.core.errors import InputError, require

REQUIRED = ("recording", "navigation", "spacing_m")
OPTIONAL = ("name", "calibration", "settings", "tow_length_m", "name_pattern", "time_source")


@dataclass(frozen=True, slots=True)
class SurveyEntry:
    """One recording of the survey (module doc); ``problem`` is the one-line reason it cannot run, or None."""

    name: str
    recording: str
    navigation: Path
    spacing_m: float
    calibration: Path | None = None
    settings: Path | None = None
    tow_length_m: float = 0.0
    name_pattern: str | None = None
    time_source: str = "auto"
    problem: str | None = None


def _path(base: Path, cell: str) -> str:
    return str(Path(cell) if Path(cell).is_absolute() else base / cell)


def _number(cell: str, what: str, line: int) -> tuple[float, str | None]:
    try:
        v = float(cell)
    except ValueError:
        return math.nan, f"manifest line {line}: {what} '{cell}' is not a number: give it in metres"
    if not math.isfinite(v) or v < 0:
        return math.nan, f"manifest line {line}: {what} {cell} must be a finite number >= 0 m"
    return v, None


def _entry(row: dict, base: Path, line: int) -> SurveyEntry:
    cell = {k: (row.get(k) or "").strip() for k in REQUIRED + OPTIONAL}
    problems = [f"manifest line {line}: empty {k}: give it" for k in REQUIRED if not cell[k]]
    spacing, p1 = _number(cell["spacing_m"] or "0", "spacing_m", line)
    tow, p2 = _number(cell["tow_length_m"] or "0", "tow_length_m", line)
    problems += [p for p in (p1, p2) if p]
    recording = _path(base, cell["recording"]) if cell["recording"] else ""
    name = cell["name"] or re.sub(r"[^A-Za-z0-9_.-]+", "_", Path(cell["recording"].rstrip("/*")).stem or f"line{line}")
    return SurveyEntry(name=name, recording=recording, navigation=Path(_path(base, cell["navigation"])),
                       spacing_m=spacing, calibration=Path(_path(base, cell["calibration"])) if cell["calibration"]
                       else None, settings=Path(_path(base, cell["settings"])) if cell["settings"] else None,
                       tow_length_m=tow, name_pattern=cell["name_pattern"] or None,
                       time_source=cell["time_source"] or "auto", problem=problems[0] if problems else None)


def read_manifest(path) -> list[SurveyEntry]:
    """Read a survey manifest (module doc).

    Parameters
    ----------
    path : str or Path
        The manifest CSV.

    Returns
    -------
    list of SurveyEntry
        One per line, in file order, names unique (a repeated name is that line's problem, and the line is
        renamed NAME-lineN so that its report does not replace the first's).
    """
    p = Path(path)
    require(p.is_file(), f"survey manifest not found: {p}: give a CSV with the columns {', '.join(REQUIRED)}")
    try:
        with open(p, newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            header = [h.strip() for h in (reader.fieldnames or [])]
            reader.fieldnames = header
            rows = list(reader)
    except UnicodeDecodeError as exc:
        raise InputError(f"survey manifest {p} is not UTF-8 text (byte {exc.start}): save it as a UTF-8 CSV with "
                         f"the columns {', '.join(REQUIRED)}") from None
    missing = [c for c in REQUIRED if c not in header]
    require(not missing, f"survey manifest {p} lacks the column(s) {', '.join(missing)}: its header must name "
                         f"{', '.join(REQUIRED)} (and optionally {', '.join(OPTIONAL)})")
    require(rows, f"survey manifest {p} lists no recording: add one line per recording")
    entries, seen = [], set()
    for line, row in enumerate(rows, start=2):
        e = _entry(row, p.parent, line)
        if e.name in seen and e.problem is None:
            e = SurveyEntry(**{**{f: getattr(e, f) for f in e.__slots__}, "name": f"{e.name}-line{line}",
                               "problem": f"manifest line {line}: the name {e.name} is used twice: give a name column"})
        seen.add(e.name)
        entries.append(e)
    return entries


def read_manifests(paths) -> list[SurveyEntry]:
    """Several manifests as one survey, in the order given (each read by :func:`read_manifest`, its paths relative
    to its own folder); a name used twice is the later line's problem, as within one manifest.

    Parameters
    ----------
    paths : sequence of str or Path
        The manifest CSVs (at least one).

    Returns
    -------
    list of SurveyEntry
        Every line of every manifest, names unique.
    """
    require(len(paths) >= 1, "give a survey manifest: --manifest survey.csv")
    entries, seen = [], set()
    for p in paths:
        for e in read_manifest(p):
            if e.name in seen:
                e = SurveyEntry(**{**{f: getattr(e, f) for f in e.__slots__}, "name": f"{e.name}-{Path(p).parent.name}",
                                   "problem": e.problem or f"{p}: the name {e.name} is used by an earlier manifest: "
                                                           "give a name column"})
            seen.add(e.name)
            entries.append(e)
    return entries

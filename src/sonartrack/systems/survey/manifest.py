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

A missing file, a missing column or a line the CSV reader cannot read refuses the whole manifest; a line whose
own values are wrong (a spacing that is no number, a duplicate name, a control character in a cell) is kept
with its problem, so that the survey reports that recording as failed and goes on with the others.

A manifest is a file users receive from others, and its names become folders: ``OUT/recordings/NAME``. A name
must therefore be one plain path component (:func:`name_problem`: no ``/`` or ``\\``, not ``.``, ``..`` or
absolute, no leading dot, no control character, at most :data:`MAX_NAME_BYTES` bytes). A line whose name is not
is that line's problem (the survey goes on with the others, as for any value of a line) and the line is stored
under ``lineN`` instead, which is always plain; a default name (from the recording's file name) that is not
plain becomes ``lineN`` without a problem. Names differing only in case are one name (one folder on a
case-insensitive disk). A byte-order mark at the start (as spreadsheet programs write) is not part of the
first column's name.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path

from sonartrack.core.errors import InputError, require

REQUIRED = ("recording", "navigation", "spacing_m")
#: a name longer than this (in bytes of UTF-8) is refused: a folder name holds 255 bytes, and the survey's
#: temporary sibling folders add a few to it
MAX_NAME_BYTES = 100
#: path separators (on any system the manifest may come from), which a folder name must not hold
_SEPARATORS = ("/", "\\")
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


def _shown(text: str) -> str:
    """A cell as one short line in a message: control characters escaped, cut at 40 characters."""
    r = repr(text)
    return r if len(r) <= 42 else r[:40] + "...'"


def _control(text: str) -> bool:
    return any(ord(ch) < 32 or 127 <= ord(ch) < 160 for ch in text)


def name_problem(name: str) -> str | None:
    """Why ``name`` cannot be a recording's folder name (module doc), or None when it is one plain name.

    Parameters
    ----------
    name : str
        The recording's name.

    Returns
    -------
    str or None
        What is wrong, e.g. ``"holds '/'"``; None for a plain name.
    """
    if not name:
        return "is empty"
    if name in (".", ".."):
        return "is a reference to a folder, not a name"
    if Path(name).is_absolute() or re.match(r"[A-Za-z]:", name):
        return "is an absolute path"
    seps = [s for s in _SEPARATORS if s in name]
    if seps:
        return f"holds {seps[0]!r} (a path, not a name)"
    if _control(name):
        return "holds a control character"
    if name.startswith("."):
        return "starts with a dot (a hidden folder)"
    if len(name.encode("utf-8")) > MAX_NAME_BYTES:
        return f"is {len(name)} characters long (at most {MAX_NAME_BYTES} bytes)"
    return None


def _name(cell: dict, line: int) -> tuple[str, str | None]:
    """The line's name and its problem: the name column's value, else the recording's file or folder name."""
    if cell["name"]:
        why = name_problem(cell["name"])
        if why is None:
            return cell["name"], None
        return f"line{line}", (f"manifest line {line}: the name {_shown(cell['name'])} {why}: give a plain name "
                               "like leg1 (one folder name: letters, digits, - and _)")
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", Path(cell["recording"].rstrip("/*")).stem)
    return (name, None) if name_problem(name) is None else (f"line{line}", None)


def _entry(row: dict, base: Path, line: int) -> SurveyEntry:
    cell = {k: (row.get(k) or "").strip() for k in REQUIRED + OPTIONAL}
    name, name_issue = _name(cell, line)
    problems = [name_issue] if name_issue else []
    problems += [f"manifest line {line}: the {k} cell {_shown(v)} holds a control character: remove it"
                 for k, v in cell.items() if k != "name" and _control(v)]
    problems += [f"manifest line {line}: empty {k}: give it" for k in REQUIRED if not cell[k]]
    spacing, p1 = _number(cell["spacing_m"] or "0", "spacing_m", line)
    tow, p2 = _number(cell["tow_length_m"] or "0", "tow_length_m", line)
    problems += [p for p in (p1, p2) if p]
    recording = _path(base, cell["recording"]) if cell["recording"] else ""
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
    rows, header = _rows(p)
    missing = [c for c in REQUIRED if c not in header]
    require(not missing, f"survey manifest {p} lacks the column(s) {', '.join(missing)}: its header must name "
                         f"{', '.join(REQUIRED)} (and optionally {', '.join(OPTIONAL)})")
    require(rows, f"survey manifest {p} lists no recording: add one line per recording")
    entries, seen = [], set()
    for line, row in rows:
        e = _entry(row, p.parent, line)
        if e.name.casefold() in seen:
            e = _renamed(e, f"{e.name}-line{line}", f"manifest line {line}: the name {e.name} is used twice "
                                                    "(letter case aside): give a name column")
        seen.add(e.name.casefold())
        entries.append(e)
    return entries


def _rows(p: Path) -> tuple[list[tuple[int, dict]], list[str]]:
    """The manifest's (line number, row) pairs and its header; a byte-order mark is not part of the header."""
    try:
        with open(p, newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            header = [h.strip() for h in (reader.fieldnames or [])]
            reader.fieldnames = header
            rows = []
            for row in reader:
                rows.append((reader.line_num, row))
    except UnicodeDecodeError as exc:
        raise InputError(f"survey manifest {p} is not UTF-8 text (byte {exc.start}): save it as a UTF-8 CSV with "
                         f"the columns {', '.join(REQUIRED)}") from None
    except csv.Error as exc:
        # line_num counts the lines of the records read whole: the bad one starts on the next
        raise InputError(f"survey manifest {p} line {reader.line_num + 1}: {exc}: a cell holds a path, a name or a "
                         "number; close the quote left open before it, or shorten the cell") from None
    return rows, header


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
    for k, p in enumerate(paths, start=1):
        for e in read_manifest(p):
            if e.name.casefold() in seen:
                folder = re.sub(r"[^A-Za-z0-9_-]+", "_", Path(p).resolve().parent.name)
                name = f"{e.name}-{folder}" if name_problem(f"{e.name}-{folder}") is None else f"{e.name}-{k}"
                e = _renamed(e, name if name.casefold() not in seen else f"{e.name}-{k}",
                             f"{p}: the name {e.name} is used by an earlier manifest: give a name column")
            seen.add(e.name.casefold())
            entries.append(e)
    return entries


def _renamed(e: SurveyEntry, name: str, problem: str) -> SurveyEntry:
    """``e`` under another name (a name used before), with its own problem or else ``problem``."""
    return SurveyEntry(**{**{f: getattr(e, f) for f in e.__slots__}, "name": name, "problem": e.problem or problem})

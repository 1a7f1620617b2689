"""A survey's files: one folder per recording, written whole or not at all, and the survey's tables.

``OUT/recordings/NAME/``: the passive chain's tables (peaks.csv, bearing_tracks.csv, targets.csv, levels.csv),
whatever the caller adds (the command line: the recording's page and pictures) and, last, ``status.json`` (ok
or failed with the reason, the recording's UTC start, span, recorded seconds, gaps and overlaps, targets, wall
time, the median broadband level in dB re 1 uPa, the warnings). A recording's folder is written whole or not at
all: everything goes into a hidden sibling ``OUT/recordings/.NAME.partial-PID`` (each file atomically,
io/atomic.py, the status last), which is then renamed into place (the old folder, if any, renamed aside first
to ``.NAME.old-PID`` and removed after). A run stopped at any moment leaves either the old folder or the new
one, and perhaps hidden siblings, which the next run removes (:func:`remove_stale`) once the process that made
them is gone. A recording whose status is ok is skipped on a rerun, a failed one is tried again.
``OUT/survey.csv``: one row per recording; ``OUT/survey_targets.csv``: one row per target (its first and last
time, UTC when the recording's start is known).

Nothing outside ``--out`` is ever written or removed. A recording's name is one plain folder name
(manifest.py ``name_problem``; :func:`recording_dir` refuses any other), and the survey refuses to run when
``OUT/recordings`` or a recording's folder in it is a symbolic link (which would take its writes, or the
removal of an old folder, somewhere else); the renames and removals never follow a link either.

Glossary of the parameters: ``out``, the survey's output folder (str or Path); ``name``, a recording's name (its
manifest entry).
"""

from __future__ import annotations

import json
import os
import re
import shutil
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.atomic import write_csv, write_text
from sonartrack.systems.survey.manifest import SurveyEntry, name_problem
from sonartrack.systems.survey.recording import RecordingOutcome

STATUS = "status.json"
RECORDINGS = "recordings"
#: the hidden siblings of a recording's folder while it is written or replaced: .NAME.partial-PID, .NAME.old-PID
_SIBLING = re.compile(r"\..+\.(?:partial|old)-\d+")
#: a local Dask cluster's scratch folder, OUT/.dask-scratch-PID (cluster.py)
_SCRATCH = re.compile(r"\.dask-scratch-\d+")


def _refuse_link(path: Path) -> None:
    """Refuse a symbolic link where the survey writes or removes (module doc)."""
    if path.is_symlink():
        raise InputError(f"{path} is a symbolic link (to {os.readlink(path)}): a survey writes and removes only "
                         "inside --out; remove the link (or give another --out)")


def recordings_dir(out) -> Path:
    """The folder of the recordings' folders, ``OUT/recordings``, checked (module doc): not a symbolic link.

    Returns
    -------
    Path
        ``out / "recordings"`` (not created here).

    Raises
    ------
    InputError
        When it is a symbolic link, or a file.
    """
    folder = Path(out) / RECORDINGS
    _refuse_link(folder)
    require(not folder.exists() or folder.is_dir(), f"{folder} is a file, not a folder: move it away (or give "
                                                    "another --out)")
    return folder


def recording_dir(out, name: str) -> Path:
    """The folder of one recording's outputs: ``OUT/recordings/NAME``, checked to stay there (module doc).

    Parameters
    ----------
    name : str
        The recording's name (its manifest entry): one plain folder name.

    Returns
    -------
    Path
        ``out / "recordings" / name`` (not created here).

    Raises
    ------
    InputError
        When ``name`` is not one plain folder name, or the folder (or ``OUT/recordings``) is a symbolic link.
    """
    why = name_problem(name)
    require(why is None, f"the recording name {name!r} {why}: give a plain name like leg1")
    parent = recordings_dir(out)
    folder = parent / name
    _refuse_link(folder)
    # belt and braces: with a plain name and no link, the resolved folder is a child of the resolved parent
    require(folder.resolve().parent == parent.resolve(), f"{folder} lies outside {parent}: give a plain name")
    return folder


def read_status(out, name: str) -> dict | None:
    """The stored status of recording ``name``, or None when it has not been stored.

    Returns
    -------
    dict or None
        The parsed status.json; None when missing or unreadable.
    """
    p = recording_dir(out, name) / STATUS
    if not p.is_file():
        return None
    try:
        return json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def is_done(out, name: str) -> bool:
    """Whether recording ``name`` was stored complete with status ok (a rerun skips it).

    Returns
    -------
    bool
        True when its status.json is readable and says "ok"; False when missing, unreadable or failed.
    """
    status = read_status(out, name)
    return bool(status) and status.get("status") == "ok"


def _status(entry: SurveyEntry, outcome: RecordingOutcome) -> dict:
    targets = len(outcome.result.targets) if outcome.result is not None else 0
    return {"name": entry.name, "status": "ok" if outcome.ok else "failed", "reason": outcome.reason,
            "recording": str(entry.recording), "navigation": str(entry.navigation),
            "start_utc": outcome.start_utc.isoformat() if outcome.start_utc else None,
            "duration_s": outcome.duration_s, "recorded_s": outcome.recorded_s, "targets": targets,
            "gaps": [g.describe() for g in outcome.gaps], "overlaps": [o.describe() for o in outcome.overlaps],
            "wall_s": outcome.wall_s, "level_db_re_1upa": _median_level(outcome.level_db),
            "warnings": list(outcome.result.warnings) if outcome.result is not None else []}


def _median_level(level_db) -> float | None:
    """The median broadband level of the recorded windows (dB re 1 uPa), None when none was measured."""
    if level_db is None:
        return None
    finite = np.asarray(level_db, float)
    finite = finite[np.isfinite(finite)]
    return round(float(np.median(finite)), 2) if finite.size else None


def store_outcome(out, entry: SurveyEntry, outcome: RecordingOutcome, extra=None) -> Path:
    """Write a recording's folder, whole or not at all (module doc), and return it.

    Parameters
    ----------
    out : path
        The survey's output folder.
    entry : SurveyEntry
        The manifest's line.
    outcome : RecordingOutcome
        What the worker sent back.
    extra : callable, optional
        ``extra(result, folder, name)`` writes more files (pages, pictures) into ``folder`` (the hidden folder
        being written, renamed to the recording's ``name`` once complete) before the status.

    Returns
    -------
    Path
        The recording's folder.
    """
    from sonartrack.systems.passive.files import write_passive_tables

    folder = recording_dir(out, entry.name)
    folder.parent.mkdir(parents=True, exist_ok=True)
    partial = folder.with_name(f".{entry.name}.partial-{os.getpid()}")
    _remove(partial)
    partial.mkdir()
    try:
        if outcome.ok:
            write_passive_tables(outcome.result, partial, outcome.level_db)
            if extra is not None:
                extra(outcome.result, partial, entry.name)
        write_text(partial / STATUS, json.dumps(_status(entry, outcome), indent=1))
        _put_in_place(partial, folder)
    finally:
        _remove(partial)  # gone already unless something above failed
    return folder


def _put_in_place(partial: Path, folder: Path) -> None:
    """Rename the complete ``partial`` folder to ``folder``; an old folder (or a link, never followed) is renamed
    aside first and removed after."""
    _refuse_link(folder)
    old = folder.with_name(f".{folder.name}.old-{os.getpid()}")
    _remove(old)
    try:
        os.rename(folder, old)
    except FileNotFoundError:
        old = None
    os.rename(partial, folder)
    if old is not None:
        _remove(old)


def _remove(path: Path) -> None:
    """Remove a file, a link (not what it points to) or a folder tree (links inside it unfollowed), if present."""
    if path.is_symlink() or path.is_file():
        path.unlink(missing_ok=True)
    elif path.is_dir():
        shutil.rmtree(path, ignore_errors=True)


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process
        return True
    return True


def remove_stale(out) -> list[Path]:
    """Remove the hidden siblings (module doc) left in ``OUT/recordings`` by runs that were stopped, and their Dask
    scratch folders ``OUT/.dask-scratch-PID``, keeping those of a process still running (another survey writing
    into the same folder).

    Returns
    -------
    list of Path
        What was removed.
    """
    parent = recordings_dir(out)
    found = [p for p in parent.iterdir() if _SIBLING.fullmatch(p.name)] if parent.is_dir() else []
    found += [p for p in Path(out).iterdir() if _SCRATCH.fullmatch(p.name)] if Path(out).is_dir() else []
    stale = [p for p in found if not _alive(int(p.name.rpartition("-")[2]))]
    for p in stale:
        _remove(p)
    return stale


def survey_rows(out, entries: list[SurveyEntry]) -> list[dict]:
    """One row per recording from the stored statuses (a recording never stored: status 'not run').

    Parameters
    ----------
    entries : list of SurveyEntry
        The manifest's recordings.

    Returns
    -------
    list of dict
        name, status, start_utc, duration_h and recorded_h (hours), targets, gaps, overlaps, level_db_re_1upa,
        reason, wall_s.
    """
    rows = []
    for e in entries:
        st = read_status(out, e.name) or {"name": e.name, "status": "not run", "reason": "", "targets": 0}
        rows.append({"name": e.name, "status": st.get("status"), "start_utc": st.get("start_utc"),
                     "duration_h": round(st.get("duration_s", 0.0) / 3600.0, 4),
                     "recorded_h": round(st.get("recorded_s", 0.0) / 3600.0, 4), "targets": st.get("targets", 0),
                     "gaps": len(st.get("gaps", [])), "overlaps": len(st.get("overlaps", [])),
                     "level_db_re_1upa": st.get("level_db_re_1upa"), "reason": st.get("reason", ""),
                     "wall_s": round(st.get("wall_s", 0.0), 2)})
    return rows


def survey_targets(out, rows: list[dict]):
    """One row per target of every stored recording: its ML track's first and last time (s from the recording's
    start, and UTC when known) and its side.

    Parameters
    ----------
    rows : list of dict
        :func:`survey_rows` (only recordings with status ok are read).

    Returns
    -------
    pandas.DataFrame
        Columns recording, target_id, first_s, last_s, side, first_utc, last_utc (ISO text; empty when the start
        is unknown).
    """
    import pandas as pd

    parts = []
    for row in rows:
        path = recording_dir(out, row["name"]) / "targets.csv"
        if row["status"] != "ok" or not path.is_file():
            continue
        t = pd.read_csv(path)
        if t.empty:
            continue
        g = t[t["method"] == "ml"].groupby("target_id")
        part = pd.DataFrame({"first_s": g["time_s"].min(), "last_s": g["time_s"].max(),
                             "side": g["side"].first()}).reset_index()
        part.insert(0, "recording", row["name"])
        start = datetime.fromisoformat(row["start_utc"]) if row["start_utc"] else None
        for col in ("first", "last"):
            part[f"{col}_utc"] = [(start + timedelta(seconds=float(s))).isoformat() if start else ""
                                  for s in part[f"{col}_s"]]
        parts.append(part)
    cols = ["recording", "target_id", "first_s", "last_s", "side", "first_utc", "last_utc"]
    return pd.concat(parts, ignore_index=True)[cols] if parts else pd.DataFrame(columns=cols)


def write_survey_tables(out, rows: list[dict]) -> list[Path]:
    """survey.csv and survey_targets.csv (module doc), atomically.

    Parameters
    ----------
    rows : list of dict
        :func:`survey_rows`.

    Returns
    -------
    list of Path
        The two files written.
    """
    import pandas as pd

    out = Path(out)
    return [write_csv(pd.DataFrame(rows), out / "survey.csv"),
            write_csv(survey_targets(out, rows), out / "survey_targets.csv")]

"""A survey's files: one folder per recording, written whole or not at all, and the survey's tables.

``OUT/recordings/NAME/``: the passive chain's tables (peaks.csv, bearing_tracks.csv, targets.csv, levels.csv),
whatever the caller adds (the command line: the recording's page and pictures) and, last, ``status.json`` (ok
or failed with the reason, the recording's UTC start, span, recorded seconds, gaps and overlaps, targets, wall
time, the median broadband level in dB re 1 uPa, the warnings). Each file is written atomically (io/atomic.py)
and the status last, after the old folder is removed, so a folder with a status.json is complete (a run
killed half-way leaves a folder without one, which a rerun computes again); a recording whose status is ok
is skipped on a rerun, a failed one is tried again.
``OUT/survey.csv``: one row per recording; ``OUT/survey_targets.csv``: one row per target (its first and last
time, UTC when the recording's start is known).
"""

from __future__ import annotations

import json
import shutil
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np

from sonartrack.io.atomic import write_csv, write_text
from sonartrack.systems.survey.manifest import SurveyEntry
from sonartrack.systems.survey.recording import RecordingOutcome

STATUS = "status.json"


def recording_dir(out, name: str) -> Path:
    """The folder of one recording's outputs: ``OUT/recordings/NAME``.

    Parameters
    ----------
    out : str or Path
        The survey's output folder.
    name : str
        The recording's name (its manifest entry).

    Returns
    -------
    Path
        ``out / "recordings" / name`` (not created here).
    """
    return Path(out) / "recordings" / name


def read_status(out, name: str) -> dict | None:
    """The stored status of recording ``name``, or None when it has not been stored.

    Parameters
    ----------
    out : str or Path
        The survey's output folder.
    name : str
        The recording's name.

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

    Parameters
    ----------
    out : str or Path
        The survey's output folder.
    name : str
        The recording's name.

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
    """Write a recording's folder (module doc) and return it.

    Parameters
    ----------
    out : path
        The survey's output folder.
    entry : SurveyEntry
        The manifest's line.
    outcome : RecordingOutcome
        What the worker sent back.
    extra : callable, optional
        ``extra(result, folder)`` writes more files (pages, pictures) into the folder before its status.

    Returns
    -------
    Path
        The recording's folder.
    """
    from sonartrack.systems.passive.files import write_passive_tables

    folder = recording_dir(out, entry.name)
    (folder / STATUS).unlink(missing_ok=True)  # from here until the new status is written: not done
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    if outcome.ok:
        write_passive_tables(outcome.result, folder, outcome.level_db)
        if extra is not None:
            extra(outcome.result, folder)
    write_text(folder / STATUS, json.dumps(_status(entry, outcome), indent=1))
    return folder


def survey_rows(out, entries: list[SurveyEntry]) -> list[dict]:
    """One row per recording from the stored statuses (a recording never stored: status 'not run').

    Parameters
    ----------
    out : str or Path
        The survey's output folder.
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
    out : str or Path
        The survey's output folder.
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
    out : str or Path
        The survey's output folder.
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

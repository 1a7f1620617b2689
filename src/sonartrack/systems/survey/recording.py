"""One recording of a survey through the passive chain: the task a worker runs.

The recording (a file, or a sequence of files with its gaps), its calibration and its navigation (a CSV, an
NMEA 0183 log or a GPX track) are read, checked and run exactly as ``sonartrack passive`` does: through
systems/passive/files.py :func:`run_passive_recording`, the one place that knows how.

Bad input (InputError anywhere: a missing file, files of different channel counts, NMEA without one good
checksum, navigation not covering the recording) makes the outcome failed with its one-line reason. So does
an OSError: everything a task opens is the user's (a recording, a navigation log, a calibration or settings
file, a folder of files), so a file that cannot be read (no permission, a folder where a file is expected, a
name too long) is an input problem, named with its path, not a bug. Any other exception makes the outcome
failed too, with the exception's type named, so that one recording never stops a survey.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from datetime import datetime

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.io.recording_sequence import Discontinuity
from sonartrack.systems.survey.manifest import SurveyEntry


@dataclass(frozen=True, slots=True)
class RecordingOutcome:
    """What a worker sends back: the chain's result (None when failed), the one-line reason of a failure, the
    recording's UTC start (None if unknown), its span and recorded seconds, its gaps and overlaps, wall time,
    and the broadband level of each window (dB re 1 uPa; systems/passive/files.py)."""

    name: str
    ok: bool
    reason: str
    result: object | None
    start_utc: datetime | None
    duration_s: float
    recorded_s: float
    gaps: tuple[Discontinuity, ...] = ()
    overlaps: tuple[Discontinuity, ...] = ()
    wall_s: float = 0.0
    level_db: np.ndarray | None = None


def _settings(entry: SurveyEntry):
    from sonartrack.io import toml as toml_io
    from sonartrack.systems.passive.settings import PassiveSettings

    data = toml_io.load(entry.settings) if entry.settings is not None else {}
    source = f"settings {entry.settings}" if entry.settings is not None else "settings"
    return toml_io.validate(PassiveSettings, {**data, "spacing_m": entry.spacing_m}, source=source)


def _run(entry: SurveyEntry, t0: float) -> RecordingOutcome:
    from sonartrack.systems.passive.files import run_passive_recording

    require(entry.problem is None, entry.problem or "")
    run = run_passive_recording(entry.recording, entry.navigation, _settings(entry), calibration=entry.calibration,
                                tow_length_m=entry.tow_length_m, time_source=entry.time_source,
                                name_pattern=entry.name_pattern)
    seq = run.recording
    return RecordingOutcome(entry.name, True, "", run.result, seq.start_utc, seq.duration_s, seq.recorded_s, seq.gaps,
                            seq.overlaps, time.perf_counter() - t0, run.level_db)


def run_recording(entry: SurveyEntry) -> RecordingOutcome:
    """Run the passive chain over one recording of the survey, the manifest's line ``entry`` (module doc); never
    raises.

    Returns
    -------
    RecordingOutcome
        The result, or failed with the one-line reason.
    """
    t0 = time.perf_counter()
    try:
        return _run(entry, t0)
    except InputError as e:
        reason = " ".join(str(e).split())  # one line in the table and the page, whatever the message
    except OSError as e:
        reason = os_reason(e)
    except Exception as e:  # noqa: BLE001 - one recording's bug must not stop the survey; its type is reported
        reason = f"unexpected {type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''} (a bug: please report)"
    return RecordingOutcome(entry.name, False, reason, None, None, 0.0, 0.0, wall_s=time.perf_counter() - t0)


def os_reason(e: OSError) -> str:
    """One line for a user's file that the system refused to read (the refusal ``e``; module doc): the path, why,
    and the fix.

    Returns
    -------
    str
        E.g. ``cannot read nav.csv: permission denied: check its permissions``.
    """
    where = f" {e.filename}" if e.filename is not None else ""
    why = (e.strerror or type(e).__name__).lower()
    if isinstance(e, PermissionError):
        return f"cannot read{where}: {why}: check its permissions (and its folder's)"
    if isinstance(e, IsADirectoryError):
        return f"cannot read{where}: it is a folder where a file is expected: give the file"
    return f"cannot read{where}: {why}: check the path and its permissions"

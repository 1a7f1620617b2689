"""The survey: every recording of a manifest through the passive chain, one task each, locally or on Dask.

Recordings already stored with status ok (systems/survey/files.py) are skipped, so a survey stopped by Ctrl-C
or a killed job resumes where it was and recomputes nothing. The others run as tasks: in this process one
after another (``workers = 1``), on a local Dask cluster of ``workers`` processes, or on the cluster whose
scheduler is at ``scheduler`` (as ``sonartrack reproduce --scheduler``). A task reads its recording and
navigation where the worker runs (so a cluster's workers must see the manifest's paths) and sends its
result back; the client writes each recording's folder as its task finishes, so the workers need no shared
output disk. The results do not depend on where a task ran: the chain is deterministic.

Ctrl-C or SIGTERM (KeyboardInterrupt here) stops the tasks and the local cluster (cluster.py) and propagates:
every recording stored by then is whole, the one being stored is not there at all (files.py), and a rerun does
exactly the rest. Hidden leftovers of a killed run are removed first (files.py ``remove_stale``).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from sonartrack.core.errors import require
from sonartrack.systems.survey.cluster import check_scheduler, dask_client
from sonartrack.systems.survey.files import is_done, remove_stale, store_outcome, survey_rows, write_survey_tables
from sonartrack.systems.survey.manifest import SurveyEntry
from sonartrack.systems.survey.recording import RecordingOutcome, run_recording


@dataclass(frozen=True, slots=True)
class SurveySummary:
    """Counts of a survey run (ran ok, failed, skipped as already done) and the survey's table, one row per
    recording (files.py ``survey_rows``)."""

    ok: int
    failed: int
    skipped: int
    rows: list[dict]

    @property
    def failed_total(self) -> int:
        """Recordings whose stored status is failed (this run's and none else: failed ones are rerun)."""
        return sum(r["status"] == "failed" for r in self.rows)


def _local(entries: list[SurveyEntry]) -> Iterator[tuple[SurveyEntry, RecordingOutcome]]:
    for e in entries:
        yield e, run_recording(e)


def _dask(entries: list[SurveyEntry], workers: int, scheduler: str | None, out: Path):
    from distributed import as_completed

    with dask_client(workers, scheduler, out) as client:
        futures = {client.submit(run_recording, e, pure=False, key=f"survey-{e.name}"): e for e in entries}
        for fut in as_completed(list(futures)):
            yield futures[fut], _outcome(fut, futures[fut])


def _outcome(fut, entry: SurveyEntry) -> RecordingOutcome:
    """The task's outcome; a task that the cluster lost (its worker died) is a failed recording, not a crash."""
    try:
        return fut.result()
    except Exception as e:  # noqa: BLE001 - run_recording never raises: this is the cluster's failure, reported
        reason = f"its task failed on the Dask cluster ({type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''})"
        return RecordingOutcome(entry.name, False, reason, None, None, 0.0, 0.0)


def run_survey(entries: list[SurveyEntry], out, *, workers: int = 1, scheduler: str | None = None, progress=None,
               extra=None) -> SurveySummary:
    """Run the survey (module doc) and write its tables.

    Parameters
    ----------
    entries : list of SurveyEntry
        The manifest (manifest.py ``read_manifest``).
    out : path
        Output folder: recordings/NAME/ per recording, survey.csv, survey_targets.csv.
    workers : int
        1: in this process; more: a local Dask cluster of that many processes.
    scheduler : str, optional
        Address of a Dask scheduler (instead of ``workers``).
    progress : object, optional
        ``start(label, total, done)`` and ``advance(n)`` hooks, one step per recording.
    extra : callable, optional
        ``extra(result, folder, name)`` adds files to a finished recording's folder (files.py ``store_outcome``).

    Returns
    -------
    SurveySummary
        This run's counts and the table of every recording.
    """
    require(workers >= 1, f"--workers must be >= 1, got {workers}")
    if scheduler:
        check_scheduler(scheduler)
    out = Path(out)
    todo = [e for e in entries if not is_done(out, e.name)]
    remove_stale(out)
    skipped = len(entries) - len(todo)
    if progress is not None:
        progress.start("recordings", len(entries), skipped)
    ok = failed = 0
    tasks = _dask(todo, workers, scheduler, out) if (scheduler or workers > 1) and todo else _local(todo)
    with contextlib.closing(tasks):
        for entry, outcome in tasks:
            store_outcome(out, entry, outcome, extra if outcome.ok else None)
            ok, failed = ok + outcome.ok, failed + (not outcome.ok)
            if progress is not None:
                progress.advance(1)
    rows = survey_rows(out, entries)
    write_survey_tables(out, rows)
    return SurveySummary(ok, failed, skipped, rows)

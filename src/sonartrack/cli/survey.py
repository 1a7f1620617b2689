"""``sonartrack survey``: many recordings through the passive chain, locally or on a Dask cluster.

Parses the options and calls the survey system (systems/survey/): the manifest (one line per recording:
recording, navigation, spacing_m[, name, calibration, settings, tow_length_m, name_pattern, time_source]),
one task per recording, each finished recording stored atomically in ``OUT/recordings/NAME/`` with its
tables, page and pictures (report/passive_page.py, report/figures/passive.py) and skipped on a rerun; then
``OUT/survey.csv``, ``OUT/survey_targets.csv`` and the survey page ``OUT/index.html`` (report/survey_page.py).
The exit status is the number of failed recordings (at most 100; 0: all ran), each failure's one-line reason
on stderr and in the page. Ctrl-C or SIGTERM ends it with one line saying how many recordings are done and kept
(a rerun does the others) and status 130 or 143.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer


def _recording_page(result, folder: Path, name: str) -> None:
    from sonartrack.report.figures.passive import write_passive_figures
    from sonartrack.report.passive_page import write_passive_page
    from sonartrack.systems.passive.tables import summary_lines

    figures = write_passive_figures(result, folder)
    write_passive_page(folder / "index.html", result, summary_lines(result), figures, {"folder": name})


def _interrupted(exc: KeyboardInterrupt, entries, out: Path) -> KeyboardInterrupt:
    """The interrupt, carrying its one line: how many recordings are done and kept, how many a rerun does."""
    import signal

    from sonartrack.cli import Interrupted
    from sonartrack.core.errors import InputError

    signum = getattr(exc, "signum", signal.SIGINT)
    if not entries:
        return Interrupted(signum, "interrupted before any recording ran; rerun the same command to run the survey")
    from sonartrack.systems.survey.files import is_done

    try:
        done = sum(is_done(out, e.name) for e in entries)
    except InputError:  # the output folder was refused before anything ran
        done = 0
    return Interrupted(signum, f"interrupted: {done} of {len(entries)} recordings done and kept in {out}; rerun the "
                               f"same command to do the other {len(entries) - done}")


def survey_cmd(
    manifest: Annotated[list[Path], typer.Option(help="Survey manifest CSV: recording, navigation, spacing_m[, name, "
                                                      "calibration, settings, tow_length_m, name_pattern, "
                                                      "time_source]; repeat it to run several manifests as one "
                                                      "survey.")],
    out: Annotated[Path, typer.Option(help="Output folder (a rerun skips the recordings already done).")]
    = Path("survey-results"),
    workers: Annotated[int, typer.Option(help="1: run here, one recording after another; N > 1: a local Dask "
                                              "cluster of N processes.")] = 1,
    scheduler: Annotated[str | None, typer.Option(help="Dask scheduler address, e.g. tcp://host:8786 (the workers "
                                                       "must see the manifest's paths).")] = None,
) -> None:
    """Survey: every recording of a manifest through the passive chain; a page of recordings and targets."""
    entries = []
    try:
        from sonartrack.cli._progress import TrialProgress, make_progress
        from sonartrack.systems.survey.manifest import read_manifests
        from sonartrack.systems.survey.run import run_survey

        entries = read_manifests(manifest)
        out.mkdir(parents=True, exist_ok=True)
        with make_progress() as bar:
            summary = run_survey(entries, out, workers=workers, scheduler=scheduler, progress=TrialProgress(bar),
                                 extra=_recording_page)
        from sonartrack.report.survey_page import write_survey_page

        page = write_survey_page(out, summary.rows)
    except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM: the workers are stopped by now; say what was kept
        raise _interrupted(exc, entries, out) from None
    for r in summary.rows:
        if r["status"] == "failed":
            typer.echo(f"failed: {r['name']}: {r['reason']}", err=True)
    n_targets = sum(r["targets"] for r in summary.rows)
    typer.echo(f"survey: {summary.ok} ran, {summary.skipped} already done, {summary.failed_total} failed; "
               f"{n_targets} targets; open {page}")
    raise typer.Exit(min(summary.failed_total, 100))

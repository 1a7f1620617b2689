"""The survey system: many recordings, each through the passive chain as one task, locally or on a Dask cluster.

    from sonartrack.systems.survey import read_manifest, run_survey
    summary = run_survey(read_manifest("survey.csv"), "survey-out", workers=2)

Modules: manifest.py (the manifest of recordings), recording.py (one recording: a file or a sequence of files,
its calibration and navigation log, through the passive chain: :func:`run_recording`), run.py (the tasks,
local or on a cluster, stored as they finish and skipped on a rerun: :func:`run_survey`), files.py (a
recording's folder, its status written last, and the survey's tables). The survey page is report/survey_page.py.
The names below load on first use, so that importing this package stays light.
"""

from __future__ import annotations

from sonartrack.core.lazy import lazy_exports

_EXPORTS = {
    "SurveyEntry": "sonartrack.systems.survey.manifest", "read_manifest": "sonartrack.systems.survey.manifest",
    "RecordingOutcome": "sonartrack.systems.survey.recording", "run_recording": "sonartrack.systems.survey.recording",
    "SurveySummary": "sonartrack.systems.survey.run", "run_survey": "sonartrack.systems.survey.run",
}
__getattr__, __all__ = lazy_exports(__name__, _EXPORTS)

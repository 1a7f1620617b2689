"""
A survey on Dask
================

``sonartrack survey`` runs many recordings through the passive chain, one task each, on a local Dask cluster
(``--workers``) or on a cluster's scheduler (``--scheduler tcp://HOST:8786``), and writes a page of the
recordings and the targets they found. A finished recording is stored atomically and skipped on a rerun, and a
recording that cannot run is reported with its reason while the others go on.
"""

# %%
# 1. Two recordings as recorders write them
# -----------------------------------------
# One 32-bit float WAV with its navigation CSV, and one folder of 24-bit WAV files named by their UTC start, with a
# 10 s gap between them, a calibration file (the samples are volts) and the navigation as NMEA 0183 sentences.
# ``--manifest`` writes each recording's line of a survey manifest. Four minutes each keep this page quick.
import contextlib
import shutil
import sys
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import pandas as pd

from sonartrack.cli import main

work = Path(tempfile.mkdtemp(prefix="sonartrack-survey-"))


def sonartrack(*args: str) -> None:
    """``sonartrack ARGS`` in the work folder, as in a shell there."""
    with contextlib.chdir(work), contextlib.redirect_stderr(sys.stdout):
        status = main(list(args))
    assert status == 0, f"sonartrack {' '.join(args)} exited with {status}"


sonartrack("simulate", "--duration-s", "240", "--only", "passive", "--manifest", "--out", "survey-a")
sonartrack("simulate", "--duration-s", "240", "--seed", "2", "--only", "passive", "--format", "wav24",
           "--split-s", "120", "--gap-s", "10", "--nmea", "--manifest", "--out", "survey-b")
pd.read_csv(work / "survey-b" / "manifest.csv")

# %%
# 2. The survey on a local Dask cluster of two workers
# ----------------------------------------------------
# ``--workers 2`` starts two single-threaded worker processes; each recording is one task, run where the worker
# is, and its results come back to this process, which writes them (the workers need no shared disk).
sonartrack("survey", "--manifest", "survey-a/manifest.csv", "--manifest", "survey-b/manifest.csv",
           "--workers", "2", "--out", "survey")

# %%
# ``survey.csv``: one row per recording (its status, UTC start, span and recorded hours, gaps, median level,
# targets, and the reason of a failure); ``survey_targets.csv`` one row per target.
survey = pd.read_csv(work / "survey" / "survey.csv")
survey.drop(columns="wall_s")

# %%
pd.read_csv(work / "survey" / "survey_targets.csv")

# %%
# ``survey_targets.png`` shows when each recording held each target; ``recordings/NAME/`` holds each recording's
# own tables, pictures and page, and ``index.html`` links them.
fig, ax = plt.subplots(figsize=(10, 4))
ax.imshow(plt.imread(work / "survey" / "survey_targets.png"))
ax.set_axis_off()

# %%
shutil.rmtree(work)

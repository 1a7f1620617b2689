"""
A recording through ``passive``
===============================

The passive system takes a line-array recording and the ship's navigation and gives the targets: bearing tracks,
the side of each, and a target motion analysis (TMA) with a verdict on whether its range is determined. Here a
5-minute scene from ``sonartrack simulate`` stands in for your recording; with your own, start at step 2 with your
WAV and navigation files.
"""

# %%
# 1. A recording
# --------------
# ``sonartrack simulate`` writes the default scene (16 hydrophones 2.5 m apart towed 200 m astern, four ships,
# the ownship turning 45° to port half-way through) as a 32-bit float WAV in pascals, its navigation and its
# truth. ``sonartrack.cli.main`` runs a command exactly as the shell does and returns its exit status; here
# each command runs in a temporary folder, its messages shown below it.
import contextlib
import shutil
import sys
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import pandas as pd

from sonartrack.cli import main

work = Path(tempfile.mkdtemp(prefix="sonartrack-passive-"))


def sonartrack(*args: str) -> None:
    """``sonartrack ARGS`` in the work folder, as in a shell there."""
    with contextlib.chdir(work), contextlib.redirect_stderr(sys.stdout):
        status = main(list(args))
    assert status == 0, f"sonartrack {' '.join(args)} exited with {status}"


sonartrack("simulate", "--duration-s", "300", "--seed", "1", "--only", "passive", "--out", "scene")
sorted(p.name for p in (work / "scene").iterdir())

# %%
# The navigation gives the ownship and the array centre every second (``--nav``); the truth is for scoring.
pd.read_csv(work / "scene" / "nav.csv").iloc[::60]

# %%
# 2. The passive chain
# --------------------
# Beamforming on 1 s blocks, peaks, JPDA_A bearing tracks, then per confirmed track its side (the ownship's turn
# makes one mirror bearing fit a constant-velocity target and the other fail), the batch ML and the IMM-MGEKF.
# One line per target on stdout; a range the record does not determine is never printed as a number.
sonartrack("passive", "--wav", "scene/recording.wav", "--nav", "scene/nav.csv", "--spacing", "2.5", "--out", "passive")

# %%
# ``targets.csv`` holds every solution with its standard deviations, ``range_determined`` and, where not, why.
targets = pd.read_csv(work / "passive" / "targets.csv")
columns = ["target_id", "origin", "method", "side", "time_s", "bearing_deg", "range_m", "range_std_m", "course_deg",
           "speed_kn", "range_determined", "undetermined_reason", "frequency_hz"]
targets.groupby(["target_id", "method"]).tail(1)[columns].round(2)

# %%
# 3. The tactical picture
# -----------------------
# The ownship, the array, each target's track with its 95 % ellipse, and the rejected mirror bearings dotted
# (``tactical.png``; ``bearing_time.png`` is the record with the tracks over it, ``index.html`` ties them
# together).
fig, axes = plt.subplots(1, 2, figsize=(12, 6))
for ax, name in zip(axes, ["tactical.png", "bearing_time.png"], strict=True):
    ax.imshow(plt.imread(work / "passive" / name))
    ax.set_axis_off()
fig.tight_layout()

# %%
# Compare with the truth: the simulated ships' true bearings and ranges from the array at the end.
truth = pd.read_csv(work / "scene" / "truth.csv")
truth[truth.time_s == truth.time_s.max()][["ship", "bearing_deg", "range_m", "side", "snr_db"]]

# %%
shutil.rmtree(work)

"""
An active scene through ``active``
==================================

The active system takes the pings of a towed source received on a towed line array, with the navigation, and
gives tracks: beams and matched filter per ping, CFAR and multi-frame detection (paper P1), each detection to two
mirror bistatic contacts, IMM-IPDA tracking (paper P4), and after the ownship's turn each track's side.
"""

# %%
# 1. Ten minutes of pings
# -----------------------
# ``sonartrack simulate --kind active`` writes paper P4's geometry: the ownship at 5 kn tows the source 300 m and
# the array 450 m astern and pings an LFM every 30 s; five targets sit in noise and seabed and volume
# reverberation. The default hour turns at 1500 s; a scene file (any subset of ``--print-config``'s settings)
# moves the turn to 150 s and makes it quicker, so that 10 minutes (20 pings) decide a side.
import contextlib
import shutil
import sys
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import pandas as pd

from sonartrack.cli import main

work = Path(tempfile.mkdtemp(prefix="sonartrack-active-"))


def sonartrack(*args: str) -> None:
    """``sonartrack ARGS`` in the work folder, as in a shell there."""
    with contextlib.chdir(work), contextlib.redirect_stderr(sys.stdout):
        status = main(list(args))
    assert status == 0, f"sonartrack {' '.join(args)} exited with {status}"


(work / "turn.toml").write_text("[ownship]\nturn_start_s = 150.0\nturn_rate_deg_s = 0.5\n")
sonartrack("simulate", "--kind", "active", "--scene", "turn.toml", "--duration-s", "600", "--out", "active-scene")

# %%
# The truth: each target's echo SNR per ping (dB, on the beam's axis after the matched filter), least and most:
truth = pd.read_csv(work / "active-scene" / "truth.csv")
truth.groupby("target")[["snr_db"]].agg(["min", "max"]).round(1)

# %%
# 2. The active chain
# -------------------
# One line per confirmed track: its state, existence and IMM mode probabilities, and its side once decided by
# the likelihood ratio of its contacts and their mirrors.
sonartrack("active", "--pings", "active-scene/pings", "--nav", "active-scene/nav.csv", "--spacing", "0.5",
           "--out", "active")

# %%
# ``sides.csv`` holds one row per target (a mirror pair once, both positions); ``tracks.csv`` every track at
# every ping with its target and hypothesis.
pd.read_csv(work / "active" / "sides.csv")

# %%
# 3. The pictures
# ---------------
# The B-scan of the detections and the tactical picture of the confirmed tracks.
fig, axes = plt.subplots(1, 2, figsize=(12, 6))
for ax, name in zip(axes, ["bscan.png", "tactical.png"], strict=True):
    ax.imshow(plt.imread(work / "active" / name))
    ax.set_axis_off()
fig.tight_layout()

# %%
shutil.rmtree(work)

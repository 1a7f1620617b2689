"""
TMA with legs: a zigging target
===============================

Bearings-only target motion analysis assumes a target at constant velocity. When the target zigs, that model is
wrong for the whole record. :func:`sonartrack.tma.zig.detect_zigs` finds the changes of velocity from the
bearings alone (a sequential generalised likelihood-ratio test at a stated false-alarm rate) and
:func:`sonartrack.tma.legs.fit_legs` solves the target as legs of constant velocity joined at those times, each
leg with its course, speed and range uncertainty and a verdict. ``sonartrack advise`` then proposes the ownship's
next leg for the target's current leg.
"""

# %%
# 1. A record with a zig
# ----------------------
# Times in s, bearings in rad clockwise from north, positions in m (x east, y north). The ownship steams at 6 kn
# on three legs (north, 080°, north); the target, 8 km off at 10 kn on 270°, turns to 210° at 1805 s. Bearings
# every 20 s for an hour with 0.5° noise, seeded.
import contextlib
import shutil
import sys
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from sonartrack.cli import main
from sonartrack.tma.legs import fit_legs
from sonartrack.tma.zig import detect_zigs

KNOT_MPS = 1852.0 / 3600.0


def track(t, start_xy, change_times_s, courses_deg, speed_kn):
    """Positions (n, 2) of a platform at constant speed whose course changes at the given times."""
    edges = np.r_[t[0], change_times_s, np.inf]
    time_on_leg = np.clip(t[:, None] - edges[:-1], 0.0, edges[1:] - edges[:-1])
    course = np.radians(courses_deg)
    velocity = speed_kn * KNOT_MPS * np.stack([np.sin(course), np.cos(course)], axis=1)
    return np.asarray(start_xy, float) + time_on_leg @ velocity


t = np.arange(0.0, 3600.0, 20.0)
own = track(t, [0.0, 0.0], [900.0, 2700.0], [0.0, 80.0, 0.0], 6.0)
target = track(t, [6000.0, 5500.0], [1805.0], [270.0, 210.0], 10.0)
sigma_rad = np.radians(0.5)
rng = np.random.default_rng(60)
bearing_rad = np.arctan2(target[:, 0] - own[:, 0], target[:, 1] - own[:, 1]) + rng.normal(0.0, sigma_rad, t.size)

# %%
# 2. The zigs, then the legs
# --------------------------
# The test's threshold follows from the stated rate of false zigs per hour of constant-velocity motion (0.1 by
# default) and the bearing interval. Each zig has its estimated time, the profile-likelihood 95 % interval of that
# time (on the grid of midpoints between bearings) and the time at which the test crossed its threshold.
report = detect_zigs(t, bearing_rad, own, sigma_rad, false_alarm_per_hour=0.1)
print(f"threshold {report.threshold:.1f} on GLR*; {len(report.zigs)} zig(s)")
for zig in report.zigs:
    print(f"zig at {zig.time_s:.0f} s (interval {zig.interval_s[0]:.0f}..{zig.interval_s[1]:.0f} s), "
          f"detected at {zig.detected_s:.0f} s, GLR {zig.glr:.1f}")

# %%
# ``report.legs`` is the leg-wise ML over the whole record with the change times refined
# (:func:`~sonartrack.tma.legs.fit_legs`); the sds include the uncertainty of the change times.
legs = pd.DataFrame([{"start_s": leg.start_s, "end_s": leg.end_s, "end_sd_s": leg.end_sd_s,
                      "course_deg": leg.course_deg, "course_sd_deg": leg.course_sd_deg, "speed_kn": leg.speed_kn,
                      "speed_sd_kn": leg.speed_sd_kn, "range_at_end_m": leg.range_m, "range_sd_m": leg.range_sd_m,
                      "determined": leg.determined} for leg in report.legs.legs])
legs.round(1)

# %%
# The same fit can be asked for directly with given change times; with none it is the constant-velocity batch
# ML, whose cost against the legs' shows what the zig costs a single-leg solution.
cv = fit_legs(t, bearing_rad, own, sigma_rad, [])
print(f"chi-square cost: constant velocity {cv.objective:.0f}, two legs {report.legs.objective:.0f} "
      f"({t.size} bearings)")

# %%
# The picture: the ownship, the true target, and the legs' positions with their 95 % ellipses at a few times.
fig, (ax, ax_glr) = plt.subplots(1, 2, figsize=(12, 5.5))
ax.plot(own[:, 0] / 1e3, own[:, 1] / 1e3, "k-", label="ownship")
ax.plot(target[:, 0] / 1e3, target[:, 1] / 1e3, "g--", label="target (truth)")
times = np.arange(0.0, 3600.0, 600.0)
position, covariance = report.legs.position_at(times)
ax.plot(position[:, 0] / 1e3, position[:, 1] / 1e3, "bo", label="legs fit, every 10 min")
angle = np.linspace(0.0, 2.0 * np.pi, 60)
for p, c in zip(position, covariance, strict=True):
    ellipse = p[:, None] + np.linalg.cholesky(c) @ np.stack([np.cos(angle), np.sin(angle)]) * np.sqrt(5.991)
    ax.plot(ellipse[0] / 1e3, ellipse[1] / 1e3, "b-", lw=0.8)
ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal", title="geometry")
ax.legend(loc="lower right")
ax_glr.plot(t, report.statistic, "b.", label="GLR* at each bearing")
ax_glr.axhline(report.threshold, color="r", label="threshold")
for zig in report.zigs:
    ax_glr.axvline(zig.time_s, color="k", ls=":", label="zig (estimated time)")
ax_glr.set(xlabel="time (s)", ylabel="GLR*", title="sequential test")
ax_glr.legend()
fig.tight_layout()

# %%
# 3. Where to steer next: ``sonartrack advise``
# ---------------------------------------------
# The target's current leg starts after the last zig. ``advise`` solves the bearings of that leg (constant-velocity
# batch ML), predicts the range sd each candidate ownship leg would give at the horizon, and proposes the best.
work = Path(tempfile.mkdtemp(prefix="sonartrack-legs-"))
current = t > report.zigs[-1].interval_s[1]
pd.DataFrame({"time_s": t[current], "bearing_deg": np.degrees(bearing_rad[current])}).to_csv(
    work / "bearings.csv", index=False)
pd.DataFrame({"time_s": t, "x_m": own[:, 0], "y_m": own[:, 1]}).to_csv(work / "ownship.csv", index=False)
with contextlib.chdir(work), contextlib.redirect_stderr(sys.stdout):
    status = main(["advise", "--bearings", "bearings.csv", "--ownship", "ownship.csv", "--sigma-bearing-deg", "0.5",
                   "--out", "advice"])
assert status == 0

# %%
fig, ax = plt.subplots(figsize=(8, 6))
ax.imshow(plt.imread(work / "advice" / "advice.png"))
ax.set_axis_off()

# %%
shutil.rmtree(work)

"""``sonartrack track --peaks``: JPDA / JPDA_A bearing tracking of a peaks file with automatic initiation.

Tracks start on strong unassociated peaks and are confirmed M-of-N (tracking/bearing_tracker.py);
JPDA_A uses the track strength of eq. 9. Output (atomic): ``bearing_tracks.csv`` (time_s, track_id,
bearing_deg, bearing_rate_deg_s, bearing_std_deg, strength, confirmed: a row per live track per scan) and
``bearing_tracks.png`` (the waterfall with the confirmed tracks drawn over the peaks).
"""

from __future__ import annotations

import functools
from pathlib import Path

from sonartrack.core.errors import InputError


@functools.lru_cache(maxsize=1)
def peaks_config_model():
    from pydantic import BaseModel, ConfigDict, Field

    class PeakTrackerConfig(BaseModel):
        """Settings of ``sonartrack track --peaks`` (TOML keys); defaults are paper P0's and the study's."""

        model_config = ConfigDict(frozen=True, extra="forbid")

        q: float = Field(0.01, gt=0)
        gate_deg: float = Field(10.0, gt=0)
        p_detect: float = Field(1.0, gt=0, le=1)
        clutter_density_per_deg: float = Field(0.027, gt=0)
        false_amplitude_rate: float = Field(4e-4, gt=0)
        amplitude_threshold: float = Field(5000.0, ge=0)
        init_amplitude: float = Field(7_000.0, ge=0)
        init_sigma_p_deg: float = Field(1.5, gt=0)
        init_amplitude_sd: float = Field(3000.0, gt=0)
        confirm_m: int = Field(3, ge=1)
        confirm_n: int = Field(4, ge=1)
        delete_after: int = Field(5, ge=1)

    return PeakTrackerConfig


def track_peaks_command(peaks: Path, *, tracker: str, config: Path | None, out: Path) -> str:
    import numpy as np
    import pandas as pd

    from sonartrack.io import toml as toml_io
    from sonartrack.io.peaks import read_peaks_csv
    from sonartrack.tracking.bearing_tracker import BearingTracker, BearingTrackerConfig

    if tracker not in ("jpda", "jpda-a"):
        raise InputError(f"unknown --tracker '{tracker}' for --peaks: choose jpda or jpda-a")
    data = toml_io.load(config) if config is not None else {}
    cfg = toml_io.validate(peaks_config_model(), data, source="peak tracker config" if config is None else f"config {config}")
    rec = read_peaks_csv(peaks)
    tc = BearingTrackerConfig(amplitude=tracker == "jpda-a", strength="adaptive", **cfg.model_dump())
    trk = BearingTracker(tc, auto=True)
    rows = []
    for t, b, a in rec.by_scan():
        tr = trk.step(b, a)
        for i in range(len(tr.x)):
            rows.append((t, int(tr.ids[i]), tr.x[i, 0], tr.x[i, 1], float(np.sqrt(tr.P[i, 0, 0])), tr.strength[i],
                         bool(tr.confirmed[i])))
    cols = ["time_s", "track_id", "bearing_deg", "bearing_rate_deg_s", "bearing_std_deg", "strength", "confirmed"]
    table = pd.DataFrame(rows, columns=cols)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    from sonartrack.io.atomic import write_csv

    csv = write_csv(table, out / "bearing_tracks.csv", float_format="%.6g")
    from sonartrack.report.figures.bearings import waterfall_png

    conf = table[table["confirmed"]]
    lines = [(g["time_s"].to_numpy(), g["bearing_deg"].to_numpy(), f"track {tid}") for tid, g in conf.groupby("track_id")]
    png = waterfall_png(out / "bearing_tracks.png", rec, lines, title=f"{peaks.name}: {tracker.upper()} tracks")
    n_scans = len(np.unique(rec.time_s))
    return (f"track {tracker}: {n_scans} scans, {len(rec.time_s)} peaks, {conf['track_id'].nunique()} confirmed track(s) "
            f"({table['track_id'].nunique()} started); wrote {csv} and {png}")

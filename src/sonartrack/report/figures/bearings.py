"""Bearing-time pictures: peaks as a waterfall (amplitude as colour) with bearing tracks drawn over them."""

from __future__ import annotations

from pathlib import Path

from sonartrack.io.atomic import save_figure


def waterfall_png(path: Path, rec, tracks=None, title: str = "") -> Path:
    """Bearing-time picture of the peaks (amplitude as colour), optionally with tracks [(t, bearing, label)]."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 7))
    sc = ax.scatter(rec.bearing_deg, rec.time_s, c=rec.amplitude, s=5, cmap="viridis")
    for t, b, label in tracks or ():
        ax.plot(b, t, "-", lw=1.5, label=label)
    if tracks:
        ax.legend(fontsize=7)
    fig.colorbar(sc, ax=ax, label="amplitude")
    ax.set(xlabel="cone angle (deg from the array axis)", ylabel="time (s)", xlim=(0, 180), title=title)
    ax.invert_yaxis()
    return save_figure(fig, path, dpi=100, bbox_inches="tight")


def bearing_tracks_png(path: Path, rec, table, title: str = "") -> Path:
    """The waterfall of the peaks with the confirmed bearing tracks of ``table`` (tracking/run.py's
    track_peaks) drawn over them."""
    conf = table[table["confirmed"].astype(bool)]
    lines = [(g["time_s"].to_numpy(), g["bearing_deg"].to_numpy(), f"track {tid}")
             for tid, g in conf.groupby("track_id")]
    return waterfall_png(path, rec, lines, title=title)

"""``sonartrack bearings``: a two-channel recording -> cross-correlation peaks (paper P0's estimator).

Writes atomically into ``--out``: ``peaks.csv`` (time_s, bearing_deg, amplitude: one row per peak,
the cone angle from the array axis in 0..180 deg, time at the window centre) and ``waterfall.png``
(bearing against time, amplitude as colour), and prints a one-line summary.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.core.errors import require


def register(app: typer.Typer) -> None:
    app.command("bearings")(bearings_cmd)


def bearings_cmd(
    wav: Annotated[Path, typer.Option(help="Two-channel WAV (one channel per sensor or half-array).")],
    spacing: Annotated[float, typer.Option(help="Sensor (or half-array centre) spacing d (m).")],
    sound_speed: Annotated[float, typer.Option(help="Sound speed c (m/s).")] = 1500.0,
    window: Annotated[float, typer.Option(help="Observation window (s).")] = 1.0,
    threshold: Annotated[float | None, typer.Option(help="Peak amplitude threshold (default 5000 of 30000 = "
                                                            "normalised correlation 1/6).")] = None,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("bearings"),
) -> None:
    """Cross-correlation bearings: WAV -> peaks CSV and waterfall PNG."""
    import numpy as np

    from sonartrack.acoustics.xcorr_bearing import estimate_peaks
    from sonartrack.io.peaks import write_peaks_csv
    from sonartrack.io.wav import read_two_channel_wav
    from sonartrack.report.figures.bearings import waterfall_png

    require(spacing > 0, f"--spacing must be positive (metres), got {spacing:g}")
    require(sound_speed > 0, f"--sound-speed must be positive (m/s), got {sound_speed:g}")
    require(window > 0, f"--window must be positive (s), got {window:g}")
    x, fs = read_two_channel_wav(wav)
    require(x.shape[1] >= window * fs, f"{wav.name} is {x.shape[1] / fs:.2f} s long, shorter than one {window:g} s window")
    rec = estimate_peaks(x, fs, spacing, sound_speed, window, threshold)
    out.mkdir(parents=True, exist_ok=True)
    csv = write_peaks_csv(out / "peaks.csv", rec)
    png = waterfall_png(out / "waterfall.png", rec, title=f"{wav.name}: d = {spacing:g} m, c = {sound_speed:g} m/s")
    n_win = int(x.shape[1] // round(window * fs))
    typer.echo(f"bearings: {n_win} windows of {window:g} s at {fs:g} Hz, {len(rec.time_s)} peaks "
               f"({len(rec.time_s) / max(n_win, 1):.1f} a window, median amplitude "
               f"{np.median(rec.amplitude) if len(rec.amplitude) else 0:.0f}); wrote {csv} and {png}")

"""``sonartrack detect``: multi-frame track-before-detect (paper P1) on a user's range-Doppler frames.

Input: a K x Nr x Nd stack of square-law cell values (``--frames``, .npy or .npz, io/frames.py).
Settings: :class:`sonartrack.detection.detect.DetectSettings` (``--config`` TOML with ``[plane]``,
``[detector]`` and ``[decision]`` tables; ``--print-config`` shows them resolved). The library call is
:func:`sonartrack.detection.detect.detect_frames`.

Outputs (atomic): ``detection.csv`` (the best track, a row per frame), ``detection.png`` (the
frames with the best track drawn over them) and a one-line decision.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.cli._settings import (
    PRINT_CONFIG_HELP,
    option_help,
    output_folder,
    print_config_and_exit,
    resolve,
)
from sonartrack.detection.mftd import MftdSettings
from sonartrack.detection.threshold import ThresholdSettings

CSV_NAME = "detection.csv"
PNG_NAME = "detection.png"


def register(app: typer.Typer) -> None:
    app.command("detect")(detect_cmd)


def detect_cmd(
    frames: Annotated[Path | None, typer.Option(help="K x Nr x Nd square-law frames, .npy or .npz.")] = None,
    config: Annotated[Path | None, typer.Option(help="TOML settings: plane, detector, decision tables.")] = None,
    threshold: Annotated[float | None, typer.Option(help=option_help(ThresholdSettings, "threshold"))] = None,
    pfa: Annotated[float | None, typer.Option(help=option_help(ThresholdSettings, "pfa"))] = None,
    snr_db: Annotated[float | None, typer.Option(help=option_help(MftdSettings, "snr_db"))] = None,
    sigma_a: Annotated[float | None, typer.Option(help=option_help(MftdSettings, "sigma_a_mps2"))] = None,
    n_tracks: Annotated[int | None, typer.Option(help=option_help(MftdSettings, "n_tracks"))] = None,
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("detect-results"),
) -> None:
    """Multi-frame track-before-detect: frames -> decision, statistic, best track (CSV and PNG)."""
    from sonartrack.core.errors import require
    from sonartrack.detection.detect import DetectSettings, detect_frames
    from sonartrack.io.frames import read_frames, write_detection_csv
    from sonartrack.report.figures.detection import detection_png

    s = resolve(DetectSettings, config, source="detect config" if config is None else f"detect config {config}",
                decision__threshold=threshold, decision__pfa=pfa, detector__snr_db=snr_db,
                detector__sigma_a_mps2=sigma_a, detector__n_tracks=n_tracks)
    if print_config:
        print_config_and_exit(s)
    require(frames is not None, "give the frames: --frames FILE (a K x Nr x Nd .npy or .npz stack)")
    y = read_frames(frames)
    with output_folder(out):
        det = detect_frames(y, s)
        csv_path = write_detection_csv(out / CSV_NAME, det)
        png_path = detection_png(out / PNG_NAME, det)
    typer.echo(f"detect: {_verdict(det)}; wrote {csv_path} and {png_path}")


def _verdict(det) -> str:
    """The decision in one line: statistic against threshold, the plane, where the best track runs."""
    K, nr, nd = det.frames.shape
    c = det.best_track_centres()
    return (f"{'TARGET PRESENT' if det.present else 'no target'}: statistic {det.statistic:.3f} vs threshold "
            f"{det.threshold:.3f} ({det.threshold_source}); {K} frames of {nr} x {nd} cells; best track from range "
            f"{c[0, 0]:.0f} m, {c[0, 1]:+.2f} m/s to {c[-1, 0]:.0f} m, {c[-1, 1]:+.2f} m/s")

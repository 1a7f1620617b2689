"""``sonartrack detect``: multi-frame track-before-detect (paper P1) on a user's range-Doppler frames.

Input: a K x Nr x Nd stack of square-law cell values (``--frames``, .npy or .npz, systems/detect/files.py).
Settings: the detect system's tree, :class:`sonartrack.detection.detect.DetectSettings` (``--config`` TOML with
``[plane]``, ``[detector]`` and ``[decision]`` tables; ``--print-config`` shows them resolved). The system call
is :func:`sonartrack.systems.detect.run.run_detect`.

Outputs (atomic): ``detection.csv`` (the best track, a row per frame), ``detection.png`` (the
frames with the best track drawn over them) and a one-line decision.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.cli._settings import PRINT_CONFIG_HELP, option_help, output_folder, print_config_and_exit, resolve
from sonartrack.systems.detect.settings import MftdSettings, ThresholdSettings


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
    from sonartrack.report.figures.detection import detection_png
    from sonartrack.systems.detect.files import PNG_NAME, read_frames_file, write_detection
    from sonartrack.systems.detect.run import run_detect, verdict
    from sonartrack.systems.detect.settings import DetectSettings

    s = resolve(DetectSettings, config, source="detect config" if config is None else f"detect config {config}",
                decision__threshold=threshold, decision__pfa=pfa, detector__snr_db=snr_db,
                detector__sigma_a_mps2=sigma_a, detector__n_tracks=n_tracks)
    if print_config:
        print_config_and_exit(s)
    require(frames is not None, "give the frames: --frames FILE (a K x Nr x Nd .npy or .npz stack)")
    y = read_frames_file(frames)
    with output_folder(out):
        det = run_detect(y, s)
        csv_path = write_detection(det, out)
        png_path = detection_png(out / PNG_NAME, det)
    typer.echo(f"detect: {verdict(det)}; wrote {csv_path} and {png_path}")


"""``sonartrack bearings``: a two-channel recording -> cross-correlation peaks (paper P0's estimator).

Writes atomically into ``--out``: ``peaks.csv`` (time_s, bearing_deg, amplitude: one row per peak,
the cone angle from the array axis in 0..180 deg, time at the window centre) and ``waterfall.png``
(bearing against time, amplitude as colour), and prints a one-line summary. The estimator's settings
are :class:`sonartrack.acoustics.xcorr_bearing.BearingSettings` (``--config``, ``--print-config``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.acoustics.xcorr_bearing import BearingSettings
from sonartrack.cli._settings import PRINT_CONFIG_HELP, output_folder, print_config_and_exit, resolve, settings_help

_help = settings_help(BearingSettings)


def _config_keys(config: Path | None) -> set[str]:
    """The top-level keys of the ``--config`` TOML file (none without one)."""
    from sonartrack.io import toml as toml_io

    return set(toml_io.load(config)) if config is not None else set()


def bearings_cmd(
    wav: Annotated[Path | None, typer.Option(help="Two-channel WAV (one channel per sensor or half-array).")] = None,
    spacing: Annotated[float | None, typer.Option(help=_help("spacing_m"))] = None,
    sound_speed: Annotated[float | None, typer.Option(help=_help("sound_speed_mps"))] = None,
    window: Annotated[float | None, typer.Option(help=_help("window_s"))] = None,
    threshold: Annotated[float | None, typer.Option(help=_help("threshold"))] = None,
    max_peaks: Annotated[int | None, typer.Option(help=_help("max_peaks"))] = None,
    config: Annotated[Path | None, typer.Option(help="TOML file of estimator settings (see --print-config).")] = None,
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("bearings"),
) -> None:
    """Cross-correlation bearings: WAV -> peaks CSV and waterfall PNG."""
    from sonartrack.acoustics.xcorr_bearing import bearings_from_recording, peaks_summary
    from sonartrack.core.errors import require
    from sonartrack.io.peaks import write_peaks_csv
    from sonartrack.io.wav import read_two_channel_wav
    from sonartrack.report.figures.bearings import waterfall_png

    options = dict(spacing_m=spacing, sound_speed_mps=sound_speed, window_s=window, threshold=threshold,
                   max_peaks=max_peaks)
    if print_config and spacing is None and "spacing_m" not in _config_keys(config):
        # the spacing has no default (it is the user's array's): the other settings are printed with it marked
        # "(not set)", as `passive --print-config` does, instead of refusing to print
        s = resolve(BearingSettings, config, **(options | {"spacing_m": 1.0}))
        print_config_and_exit(s.model_copy(update={"spacing_m": None}))
    s = resolve(BearingSettings, config, **options)
    if print_config:
        print_config_and_exit(s)
    require(wav is not None, "give the recording: --wav FILE (a two-channel WAV)")
    x, fs = read_two_channel_wav(wav)
    with output_folder(out):
        rec = bearings_from_recording(x, fs, s)
        csv = write_peaks_csv(out / "peaks.csv", rec)
        title = f"{wav.name}: d = {s.spacing_m:g} m, c = {s.sound_speed_mps:g} m/s"
        png = waterfall_png(out / "waterfall.png", rec, title=title)
    typer.echo(f"bearings: {peaks_summary(rec, x.shape[1], fs, s.window_s)}; wrote {csv} and {png}")

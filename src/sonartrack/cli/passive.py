"""``sonartrack passive``: the passive chain on a user's array recording and navigation.

Parses the options and calls the passive system: :func:`sonartrack.systems.passive.files.run_passive_recording`
reads the recording in blocks (one file, or a folder or glob of consecutive files as one recording, gaps left
blank), its calibration and its navigation (CSV, NMEA 0183 or GPX) and runs the chain (front end, JPDA_A
bearing tracks, narrowband lines, side decision, batch ML and IMM-MGEKF TMA per confirmed track and per line
source no track explains); :func:`~sonartrack.systems.passive.write_passive_tables` writes peaks.csv,
bearing_tracks.csv, targets.csv, levels.csv (dB re 1 uPa) and lines.csv atomically into ``--out``, and the report
writes bearing_time.png, tactical.png and lofar.png (report/figures/passive.py) and index.html
(report/passive_page.py); one summary line per target on stdout (a narrowband target marked with its line).

Settings: :class:`sonartrack.systems.passive.settings.PassiveSettings`, from its defaults, then a ``--config``
TOML file, then the options; ``--print-config`` prints the resolved settings.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.cli._settings import PRINT_CONFIG_HELP, output_folder, print_config_and_exit, resolve, settings_help
from sonartrack.systems.passive.settings import FrontEndSettings, PassiveSettings

_help = settings_help(PassiveSettings)


def passive_cmd(
    wav: Annotated[Path | None, typer.Option(help="N-channel recording of the line array (element 0 = front): a "
                                                  "WAV/RF64/W64/FLAC file, or a folder or quoted glob of consecutive "
                                                  "files named by their start (rec_YYYYmmdd_HHMMSS.wav); gaps are "
                                                  "left blank.")] = None,
    nav: Annotated[Path | None, typer.Option(help="Navigation: a CSV (time_s, x_m, y_m, heading_deg[, array_x_m, "
                                                  "array_y_m, array_heading_deg]), an NMEA 0183 log (.nmea: RMC/GGA, "
                                                  "HDT/VTG, UTC) or a GPX track (.gpx).")] = None,
    calibration: Annotated[Path | None, typer.Option(help="Hydrophone calibration TOML/CSV: sensitivity_db (dB re 1 "
                                                          "V/uPa), gain_db[, full_scale_v]; not given: the samples "
                                                          "are pascals.")] = None,
    tow_length: Annotated[float, typer.Option("--tow-length", help="For an NMEA/GPX log of the ship: the array "
                                                                   "centre this far behind it along its track (m).")]
    = 0.0,
    spacing: Annotated[float | None, typer.Option("--spacing", help=_help("spacing_m"))] = None,
    elements: Annotated[int | None, typer.Option(help=_help("elements"))] = None,
    method: Annotated[str | None, typer.Option(help=_help("method", FrontEndSettings))] = None,
    band_hz: Annotated[tuple[float, float] | None, typer.Option(help=_help("band_hz", FrontEndSettings)
                                                              + " Two numbers: LOW HIGH.")] = None,
    allow_grating_lobes: Annotated[bool | None, typer.Option("--allow-grating-lobes/--no-grating-lobes",
                                                             help=_help("allow_grating_lobes",
                                                                        FrontEndSettings))] = None,
    config: Annotated[Path | None, typer.Option(help="TOML file of passive settings (see --print-config).")] = None,
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
    out: Annotated[str, typer.Option(help="Output folder.")] = "passive-results",
) -> None:
    """Passive chain: array recording + navigation -> bearing tracks, targets.csv, pictures and an HTML page."""
    settings = resolve(PassiveSettings, config, spacing_m=spacing, elements=elements, front_end__method=method,
                       front_end__band_hz=list(band_hz) if band_hz else None,
                       front_end__allow_grating_lobes=allow_grating_lobes)
    if print_config:
        print_config_and_exit(settings)
    from sonartrack.cli._progress import TrialProgress, make_progress
    from sonartrack.core.errors import require
    from sonartrack.io.run_outputs import check_out_path, discard_on_failure
    from sonartrack.report.figures.passive import write_passive_figures
    from sonartrack.report.passive_page import write_passive_page
    from sonartrack.systems.passive.files import passive_summary, run_passive_recording, write_passive_tables

    require(wav is not None and nav is not None, "give the inputs: --wav RECORDING.wav --nav NAV.csv")
    folder = check_out_path(out)
    try:  # --out made first (a bad one fails at once, in one line); a failed run leaves none of its files
        with output_folder(folder), discard_on_failure(folder):
            with make_progress() as bar:
                run = run_passive_recording(wav, nav, settings, calibration=calibration, tow_length_m=tow_length,
                                            progress=TrialProgress(bar))
            result = run.result
            lines = passive_summary(result)
            tables = write_passive_tables(result, folder, run.level_db)
            figures = write_passive_figures(result, folder)
            page = write_passive_page(folder / "index.html", result, lines, figures,
                                      {"recording": str(wav), "navigation": str(nav)})
    except KeyboardInterrupt as exc:
        raise _interrupted(exc, folder) from None
    for warning in result.warnings:
        typer.echo(warning, err=True)
    for line in lines:
        typer.echo(line)
    typer.echo(f"passive: wrote {len(tables) + len(figures) + 1} files in {folder} (open {page.name})")


def _interrupted(exc: KeyboardInterrupt, folder: Path) -> KeyboardInterrupt:
    """The interrupt with passive's own line: its outputs are written at the end, so an unfinished run keeps none."""
    import signal

    from sonartrack.cli import Interrupted

    return Interrupted(getattr(exc, "signum", signal.SIGINT),
                       f"interrupted: passive keeps no part of an unfinished run (its tables, figures and page are "
                       f"written at the end; nothing of this run is left in {folder}); run the same command again")

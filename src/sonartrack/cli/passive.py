"""``sonartrack passive``: the passive chain on a user's array recording and navigation.

Reads the N-channel WAV in blocks (io/wav_blocks.py) and the navigation (io/navigation.py), runs
:func:`sonartrack.passive.run_passive_files` (front end, JPDA_A bearing tracks, side decision, batch ML and
IMM-MGEKF TMA per confirmed track), and writes atomically into ``--out``: peaks.csv, bearing_tracks.csv,
targets.csv (passive/tables.py), bearing_time.png and tactical.png (report/figures/passive.py) and
index.html (report/passive_page.py); one summary line per target on stdout.

Settings: :class:`sonartrack.passive.settings.PassiveSettings`, from its defaults, then a ``--config`` TOML
file, then the options; ``--print-config`` prints the resolved settings.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.acoustics.beamforming import BeamformerSettings
from sonartrack.cli._settings import PRINT_CONFIG_HELP, option_help, output_folder, print_config_and_exit, resolve
from sonartrack.passive.settings import PassiveSettings


def register(app: typer.Typer) -> None:
    app.command("passive")(passive_cmd)


def _help(name: str, model=PassiveSettings) -> str:
    return option_help(model, name)


def passive_cmd(
    wav: Annotated[Path | None, typer.Option(help="N-channel WAV recording of the line array (element 0 = front).")]
    = None,
    nav: Annotated[Path | None, typer.Option(help="Navigation CSV: time_s, x_m, y_m, heading_deg[, array_x_m, "
                                                  "array_y_m, array_heading_deg].")] = None,
    spacing: Annotated[float | None, typer.Option("--spacing", help=_help("spacing_m"))] = None,
    elements: Annotated[int | None, typer.Option(help=_help("elements"))] = None,
    method: Annotated[str | None, typer.Option(help=_help("method", BeamformerSettings))] = None,
    band_hz: Annotated[tuple[float, float] | None, typer.Option(help=_help("band_hz", BeamformerSettings)
                                                              + " Two numbers: LOW HIGH.")] = None,
    allow_grating_lobes: Annotated[bool | None, typer.Option("--allow-grating-lobes/--no-grating-lobes",
                                                             help=_help("allow_grating_lobes",
                                                                        BeamformerSettings))] = None,
    config: Annotated[Path | None, typer.Option(help="TOML file of passive settings (see --print-config).")] = None,
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("passive-results"),
) -> None:
    """Passive chain: array recording + navigation -> bearing tracks, targets.csv, pictures and an HTML page."""
    from sonartrack.cli._progress import TrialProgress, make_progress
    from sonartrack.core.errors import require
    from sonartrack.passive import run_passive_files, write_passive_tables
    from sonartrack.passive.tables import summary_lines
    from sonartrack.report.figures.passive import write_passive_figures
    from sonartrack.report.passive_page import write_passive_page

    settings = resolve(PassiveSettings, config, spacing_m=spacing, elements=elements, front_end__method=method,
                       front_end__band_hz=list(band_hz) if band_hz else None,
                       front_end__allow_grating_lobes=allow_grating_lobes)
    if print_config:
        print_config_and_exit(settings)
    require(wav is not None and nav is not None, "give the inputs: --wav RECORDING.wav --nav NAV.csv")
    with output_folder(out), make_progress() as bar:  # --out made first: a bad one fails at once, in one line
        result = run_passive_files(wav, nav, settings, progress=TrialProgress(bar))
    from sonartrack.io.navigation import read_navigation

    lines = summary_lines(result)
    tables = write_passive_tables(result, out)
    figures = write_passive_figures(result, read_navigation(nav), out)
    page = write_passive_page(out / "index.html", result, lines, figures, {"recording": str(wav), "navigation":
                                                                              str(nav)})
    for line in lines:
        typer.echo(line)
    typer.echo(f"passive: wrote {len(tables) + len(figures) + 1} files in {out} (open {page.name})")

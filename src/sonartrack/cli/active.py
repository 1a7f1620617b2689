"""``sonartrack active``: the active chain on a scene folder of pings and its navigation.

Parses the options and calls the active system: :func:`sonartrack.systems.active.files.run_active_files` reads
the ping table and the pings one at a time (systems/active/scene_files.py) and runs the chain (front end,
single-ping and MFTD detection, mirror-pair bistatic contacts, range-rate gate, IMM-IPDA);
:func:`~sonartrack.systems.active.files.write_active_tables` writes detections.csv, contacts.csv, tracks.csv,
the pictures (report/figures/active.py: bscan.png, tactical.png) and index.html (report/active_page.py) into
``--out``, all or nothing (an interrupted or failed run changes none of its files there); on stdout a count line
and one line per target (a decided target once, an undecided mirror pair once with both positions: files.py
``summary_lines``); a scene folder holding the simulator's truth.csv gets the held fraction and the false targets
on the page's summary line.

Settings: :class:`sonartrack.systems.active.settings.ActiveSettings`, from its defaults, then a ``--config``
TOML file, then the options; ``--print-config`` prints the resolved settings.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.cli._settings import PRINT_CONFIG_HELP, output_folder, print_config_and_exit, resolve, settings_help
from sonartrack.systems.active.settings import ActiveSettings

_help = settings_help(ActiveSettings)


def active_cmd(
    pings: Annotated[Path | None, typer.Option(help="Scene folder holding ping_table.csv and pings/ (or the pings/ "
                                                    "folder itself).")] = None,
    nav: Annotated[Path | None, typer.Option(help="Navigation CSV: time_s, x_m, y_m, heading_deg, source_x_m, "
                                                  "source_y_m, array_x_m, array_y_m, array_heading_deg.")] = None,
    spacing: Annotated[float | None, typer.Option("--spacing", help=_help("spacing_m"))] = None,
    elements: Annotated[int | None, typer.Option(help=_help("elements"))] = None,
    detector: Annotated[str | None, typer.Option(help=_help("detector"))] = None,
    pfa: Annotated[float | None, typer.Option(help=_help("pfa"))] = None,
    config: Annotated[Path | None, typer.Option(help="TOML file of active settings (see --print-config).")] = None,
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("active-results"),
) -> None:
    """Active chain: pings + navigation -> detections, bistatic contacts, IMM-IPDA tracks, pictures, HTML page."""
    settings = resolve(ActiveSettings, config, spacing_m=spacing, elements=elements, detector=detector, pfa=pfa)
    if print_config:
        print_config_and_exit(settings)
    from sonartrack.cli._progress import TrialProgress, make_progress
    from sonartrack.core.errors import require
    from sonartrack.report.active_page import active_page
    from sonartrack.report.figures.active import active_pngs
    from sonartrack.systems.active.files import run_active_files, summary_lines, write_active_tables
    from sonartrack.systems.active.scene_files import read_active_nav

    require(pings is not None and nav is not None, "give the inputs: --pings SCENE_FOLDER --nav NAV.csv")
    try:
        with output_folder(out), make_progress() as bar:  # --out made first: a bad one fails at once, in one line
            result = run_active_files(pings, nav, settings, progress=TrialProgress(bar))
            lines = summary_lines(result)
            pngs = active_pngs(result, read_active_nav(nav))
            page = active_page(result, lines, pngs, {"pings": str(pings), "navigation": str(nav)},
                               truth=_scene_truth(pings))
            files = write_active_tables(result, out, extra={**pngs, "index.html": page})
    except BaseException as exc:
        _reraise_interrupt(exc, out)
        raise
    for line in lines:
        typer.echo(line)
    typer.echo(f"active: wrote {len(files)} files in {out} (open index.html)")


def _scene_truth(pings: Path):
    """The truth of a simulated scene (its truth.csv, written by ``sonartrack simulate --kind active``), or None: the
    page then states the held fraction and the false targets against it."""
    from sonartrack.systems.active.files import scene_folder
    from sonartrack.systems.active.scene_files import TRUTH_FILE, read_truth

    path = scene_folder(pings) / TRUTH_FILE
    return read_truth(path) if path.is_file() else None


def _reraise_interrupt(exc: BaseException, out: Path) -> None:
    """An interrupt (whatever it became on the way: cli ``interrupt_of``) with active's own line: its outputs are
    written all at once at the end (systems/active/files.py), so an interrupted run wrote none."""
    from sonartrack.cli import Interrupted, interrupt_of

    intr = interrupt_of(exc)
    if intr is not None:
        raise Interrupted(getattr(intr, "signum", 2), f"interrupted: nothing written in {out} (active writes its "
                                                      "files only when the run is complete); rerun the same command"
                          ) from None

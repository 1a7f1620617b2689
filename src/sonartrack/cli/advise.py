"""``sonartrack advise``: the next ownship leg that most reduces the predicted range uncertainty (systems/advise/).

Reads the targets (``tma_solution.csv`` files of ``sonartrack tma`` or bearings files, solved by the
constant-velocity batch ML) and the ownship file, finds the ownship's legs and its velocity now, and weighs every
candidate leg (course every 10 deg x turning now, in 5 or in 10 min, speed kept) by the predicted range sd at the
horizon from the Fisher information (tma/advice.py). Prints the advice in one line and writes atomically into
``--out``: ``advice.csv`` (every candidate) and ``advice.png`` (report/figures/advice.py).

Settings: :class:`sonartrack.systems.advise.settings.AdviceSettings`, from its defaults, then a ``--config`` TOML
file, then the options; ``--print-config`` prints the resolved settings.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.cli._settings import PRINT_CONFIG_HELP, output_folder, print_config_and_exit, resolve, settings_help
from sonartrack.systems.advise.settings import AdviceSettings

_help = settings_help(AdviceSettings)


def advise_cmd(
    ownship: Annotated[Path | None, typer.Option(help="Ownship navigation file (CSV/Parquet): time_s, x_m, y_m.")]
    = None,
    solution: Annotated[list[Path] | None, typer.Option(help="A tma_solution.csv of sonartrack tma (its last row is "
                                                            "the target now); repeat for several targets.")] = None,
    bearings: Annotated[list[Path] | None, typer.Option(help="A bearings file (time_s, bearing_deg), solved by the "
                                                            "constant-velocity batch ML; repeat for several.")] = None,
    sigma_bearing_deg: Annotated[float | None, typer.Option(help=_help("sigma_bearing_deg"))] = None,
    interval_s: Annotated[float | None, typer.Option(help=_help("interval_s"))] = None,
    horizon_s: Annotated[float | None, typer.Option(help=_help("horizon_s"))] = None,
    objective: Annotated[str | None, typer.Option(help=_help("objective"))] = None,
    config: Annotated[Path | None, typer.Option(help="TOML file of advise settings (see --print-config).")] = None,
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("advice-results"),
) -> None:
    """Observer advice: target solutions (or bearings) and ownship navigation -> the next leg, CSV and picture."""
    from sonartrack.core.errors import require
    from sonartrack.io.tma_files import read_ownship
    from sonartrack.report.figures.advice import write_advice_picture
    from sonartrack.systems.advise.files import PNG_NAME, read_targets, write_advice_csv
    from sonartrack.systems.advise.run import run_advice

    settings = resolve(AdviceSettings, config, sigma_bearing_deg=sigma_bearing_deg, interval_s=interval_s,
                       horizon_s=horizon_s, objective=objective)
    if print_config:
        print_config_and_exit(settings)
    require(ownship is not None, "give the ownship file: --ownship FILE (time_s, x_m, y_m)")
    own = read_ownship(ownship)
    targets, warnings, interval = read_targets(solution or [], bearings or [], own, settings.sigma_bearing_deg)
    result = run_advice(targets, own, settings, interval_s=interval)
    with output_folder(out):
        csv = write_advice_csv(result, out)
        png = write_advice_picture(out / PNG_NAME, result)
    for w in (*warnings, *result.warnings):
        typer.echo(f"warning: {w}", err=True)
    typer.echo(f"{result.advice.line()}; wrote {csv} and {png}")

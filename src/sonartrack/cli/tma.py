"""``sonartrack tma``: target motion analysis of a user's bearing (and frequency) record (systems/tma/).

Reads the bearings and ownship files (systems/tma/files.py), solves with
:func:`sonartrack.systems.tma.run.run_tma` (every method: sequential ``ekf``, ``mgekf``, ``imm-ekf``,
``imm-mgekf`` on bearings or bearings + frequency, paper P2; batch ``ml`` and ``em-map`` with a propagation
model, paper P3), and writes atomically into ``--out``: ``tma_solution.csv`` (the target solution over time
with standard deviations, ``range_determined`` and ``undetermined_reason``, and the bearing noise: the sd used and
the record's residual sd with its 95 % interval) and ``tactical_picture.png`` (report/figures/tma.py), plus a
one-line summary on stdout, which prints "range NOT DETERMINED (reason)" instead of a range the solution does not
determine (tma/verdict.py) and says what the record says of the bearing noise. Every method's answer is judged by
its record (tma/motion_verdict.py): a target the bearings show changing course or speed is "target manoeuvred"
with the time span the residuals point at; without ``--sigma-bearing-deg`` (or a ``bearing_sd_deg`` column, each
bearing's own sd) the bearing sd is estimated from the record; a given one that the residuals contradict is
reported.

Every record's zigs and legs are found too (tma/leg_solution.py: the sequential GLR zig detector and the leg-wise
ML with its own residual verdict): printed after the summary, one line for the zigs and one per leg (span, course,
speed, range at its end with sds, or "range not determined (reason)"), written as ``tma_legs.csv`` and drawn on the
tactical picture; when the method's answer is not determined (a target that manoeuvred) and the current leg is,
the current leg's solution is printed as the answer, and from a determined current leg the observer advice (the
next ownship leg that most reduces the predicted range sd, tma/advice.py).

Settings: :class:`sonartrack.tma.settings.TmaSettings`, from its defaults, then a ``--config`` TOML file,
then the options; ``--print-config`` prints the resolved settings.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.cli._settings import PRINT_CONFIG_HELP, output_folder, print_config_and_exit, resolve, settings_help
from sonartrack.systems.tma.settings import BatchSettings, TmaSettings

_help = settings_help(TmaSettings)


def tma_cmd(
    bearings: Annotated[Path | None, typer.Option(help="Bearings file (CSV/Parquet): time_s, bearing_deg[, "
                                                       "frequency_hz, snr_db, bearing_sd_deg].")] = None,
    ownship: Annotated[Path | None, typer.Option(help="Ownship navigation file (CSV/Parquet): time_s, x_m, "
                                                      "y_m.")] = None,
    method: Annotated[str | None, typer.Option(help=_help("method"))] = None,
    frequency: Annotated[bool | None, typer.Option("--frequency/--no-frequency", help=_help("frequency"))] = None,
    sigma_bearing_deg: Annotated[float | None, typer.Option(help=_help("sigma_bearing_deg"))] = None,
    sigma_freq_hz: Annotated[float | None, typer.Option(help=_help("sigma_freq_hz"))] = None,
    env: Annotated[str | None, typer.Option(help=_help("env", BatchSettings))] = None,
    sl: Annotated[float | None, typer.Option("--sl", help=_help("sl_db", BatchSettings))] = None,
    batch_window_s: Annotated[float | None, typer.Option(help=_help("window_s", BatchSettings))] = None,
    config: Annotated[Path | None, typer.Option(help="TOML file of tma settings (see --print-config).")] = None,
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("tma-results"),
) -> None:
    """Target motion analysis: bearings (+ frequency) and ownship navigation -> target solution CSV and picture."""
    from sonartrack.core.errors import require
    from sonartrack.io.environment import TLDiskCache
    from sonartrack.report.figures.tma import write_tactical_picture
    from sonartrack.systems.tma.files import PNG_NAME, read_tma_inputs, write_tma_legs, write_tma_solution
    from sonartrack.systems.tma.run import run_tma

    settings = resolve(TmaSettings, config, method=method, frequency=frequency,
                       sigma_bearing_deg=sigma_bearing_deg, sigma_freq_hz=sigma_freq_hz, batch__env=env,
                       batch__sl_db=sl, batch__window_s=batch_window_s)
    if print_config:
        print_config_and_exit(settings)
    require(bearings is not None and ownship is not None, "give the input files: --bearings FILE --ownship FILE")
    inputs = read_tma_inputs(bearings, ownship, settings)
    with output_folder(out):
        result = run_tma(inputs.record, inputs.ownship, settings, environment=inputs.environment,
                         tl_store=TLDiskCache(), legs=True)
        for w in result.warnings:
            typer.echo(f"warning: {w}", err=True)
        csv = write_tma_solution(result, out)
        legs_csv = write_tma_legs(result, out)
        png = write_tactical_picture(out / PNG_NAME, result)
    wrote = ", ".join(str(p) for p in (csv, legs_csv) if p is not None)
    typer.echo(f"{result.summary()}; wrote {wrote} and {png}")
    for line in result.leg_lines():
        typer.echo(line)

"""``sonartrack tl``: transmission loss of a shipped environment or a user profile (paper P3's acoustics).

Computes the RAM TL field for a source at ``--zs`` (cached on disk, io/environment.py), the TL and the
passive SNR = SL - TL + DI - NL against range at ``--zr`` (1 km averaged), the detection ranges and
convergence zones (acoustics/performance.py), and writes atomically into ``--out``: ``tl_field.png``
(the field), ``tl_range.png`` (TL and SNR against range, detection ranges shaded) and ``tl.csv``
(range_m, tl_db, tl_avg_db, snr_db). ``--list`` prints the shipped environments. The settings are
:class:`sonartrack.acoustics.performance.TLSettings` (``--config``, ``--print-config``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.acoustics.performance import TLSettings
from sonartrack.cli._settings import PRINT_CONFIG_HELP, output_folder, print_config_and_exit, resolve, settings_help

_help = settings_help(TLSettings)


def _list_environments() -> None:
    from sonartrack.acoustics.environment import list_environments, load_environment

    for name in list_environments():
        typer.echo(f"{name}: {load_environment(name).description}")


def tl_cmd(
    env: Annotated[str | None, typer.Option(help="Shipped environment (see --list).")] = None,
    profile: Annotated[Path | None, typer.Option(help="User profile: TOML, or CSV with depth_m and sound_speed_mps "
                                                        "(or temperature_c and salinity_psu).")] = None,
    water_depth: Annotated[float | None, typer.Option(help="Water depth (m) for a CSV profile (default: its last "
                                                            "depth).")] = None,
    freq: Annotated[float | None, typer.Option(help=_help("freq_hz"))] = None,
    zs: Annotated[float | None, typer.Option(help=_help("source_depth_m"))] = None,
    zr: Annotated[float | None, typer.Option(help=_help("receiver_depth_m"))] = None,
    rmax: Annotated[float | None, typer.Option(help=_help("rmax_km"))] = None,
    sl: Annotated[float | None, typer.Option("--sl", help=_help("sl_db"))] = None,
    nl: Annotated[float | None, typer.Option("--nl", help=_help("nl_db"))] = None,
    di: Annotated[float | None, typer.Option("--di", help=_help("di_db"))] = None,
    threshold: Annotated[float | None, typer.Option(help=_help("threshold_db"))] = None,
    average: Annotated[float | None, typer.Option(help=_help("average_m"))] = None,
    config: Annotated[Path | None, typer.Option(help="TOML file of TL settings (see --print-config).")] = None,
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
    list_: Annotated[bool, typer.Option("--list", help="List the shipped environments and exit.")] = False,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("tl-results"),
) -> None:
    """Transmission loss (RAM), SNR against range, detection ranges and convergence zones."""
    import pandas as pd

    from sonartrack.acoustics.environment import load_environment
    from sonartrack.acoustics.performance import performance_summary, tl_performance
    from sonartrack.core.errors import InputError
    from sonartrack.io.atomic import write_csv
    from sonartrack.io.environment import TLDiskCache, read_profile
    from sonartrack.report.figures.acoustics import save_tl_pictures

    if list_:
        return _list_environments()
    s = resolve(TLSettings, config, freq_hz=freq, source_depth_m=zs, receiver_depth_m=zr, rmax_km=rmax, sl_db=sl,
                nl_db=nl, di_db=di, threshold_db=threshold, average_m=average)
    if print_config:
        print_config_and_exit(s)
    if (env is None) == (profile is None):
        raise InputError("give exactly one of --env NAME or --profile FILE (see sonartrack tl --list)")
    e = load_environment(env) if env is not None else read_profile(profile, water_depth)
    with output_folder(out):
        field, perf = tl_performance(e, s, store=TLDiskCache())
        csv = write_csv(pd.DataFrame(perf.columns()), out / "tl.csv", float_format="%.4f")
        png_field, png_range = save_tl_pictures(out, e, field, perf)
    typer.echo(f"{performance_summary(e.name, s, perf)}; wrote {csv}, {png_field} and {png_range}")

"""``sonartrack track``: the trackers on a user's own data.

* ``--contacts FILE`` (with ``--nav FILE`` for raw bistatic columns): IPDA / IMM-IPDA position
  tracking with track management (the P4 tracker; tracking/run.py ``track_contacts``); writes
  ``tracks.csv`` (one row per live track per scan, with existence and status) and ``tracks.png``
  (tracks over contacts).
* ``--peaks FILE``: JPDA / JPDA_A bearing tracking of cross-correlation peaks (the P0 tracker;
  cli/_track_peaks.py).

Settings: io/track_config.py (``--config`` TOML with a ``[tracker]`` table; ``--print-config``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.cli._settings import PRINT_CONFIG_HELP, option_help, output_folder, print_config_and_exit, resolve
from sonartrack.core.errors import InputError
from sonartrack.io.track_config import ContactsTrackSettings, PeaksTrackSettings

CONTACTS_HELP = ("Contacts CSV/Parquet: time_s, x_m, y_m [+ var_x_m2, var_y_m2, cov_xy_m2] or raw bistatic time_s, "
                 "travel_time_s, bearing_deg.")


def register(app: typer.Typer) -> None:
    app.command("track")(track_cmd)


def track_cmd(
    contacts: Annotated[Path | None, typer.Option(help=CONTACTS_HELP)] = None,
    nav: Annotated[Path | None, typer.Option(help="Navigation CSV/Parquet for raw bistatic contacts: time_s, tx_x_m, "
                                                  "tx_y_m, rx_x_m, rx_y_m, array_heading_deg.")] = None,
    peaks: Annotated[Path | None, typer.Option(help="Bearing peaks CSV (time_s, bearing_deg, amplitude) for JPDA "
                                                    "tracking.")] = None,
    tracker: Annotated[str | None, typer.Option(help="For --peaks: jpda or jpda-a. "
                                                     + option_help(PeaksTrackSettings, "associator"))] = None,
    config: Annotated[Path | None, typer.Option(help="TOML file of settings (see --print-config).")] = None,
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("tracks"),
    confirmed_only: Annotated[bool, typer.Option("--confirmed-only", help="Write confirmed tracks only.")] = False,
) -> None:
    """Track a user's contacts (IPDA / IMM-IPDA) or bearing peaks (JPDA / JPDA_A)."""
    if (contacts is None) == (peaks is None):
        raise InputError("give exactly one of --contacts FILE or --peaks FILE")
    if peaks is not None:
        from sonartrack.cli._track_peaks import track_peaks_command

        typer.echo(track_peaks_command(peaks, tracker=tracker, config=config, out=out, print_config=print_config))
        return
    settings = resolve(ContactsTrackSettings, config)
    if print_config:
        print_config_and_exit(settings)
    typer.echo(track_contacts_command(contacts, settings, nav=nav, out=out, confirmed_only=confirmed_only))


def track_contacts_command(contacts: Path, settings: ContactsTrackSettings, *, nav: Path | None, out: Path,
                           confirmed_only: bool = False) -> str:
    """Read the contacts, track them (tracking/run.py), write tracks.csv and tracks.png; the one-line summary."""
    from sonartrack.io.atomic import write_csv
    from sonartrack.io.contacts import read_contacts
    from sonartrack.report.figures.tracks import tracks_png
    from sonartrack.tracking.run import track_contacts

    b = settings.bistatic
    data = read_contacts(contacts, nav_path=nav, default_sigma_m=settings.default_sigma_m,
                         bistatic_errors=b.errors(), sound_speed_mps=b.sound_speed_mps, max_range_m=b.max_range_m)
    with output_folder(out):
        table = track_contacts(data.time_s, data.z, data.R, settings.tracker, confirmed_only=confirmed_only)
        csv = write_csv(table, out / "tracks.csv")
        png = tracks_png(out / "tracks.png", data.z, table)
    n_confirmed = table.loc[table.status == "confirmed", "track_id"].nunique()
    return (f"{len(set(data.time_s.tolist()))} scans, {len(data.time_s)} contacts -> {n_confirmed} confirmed "
            f"track(s); wrote {csv} and {png}")

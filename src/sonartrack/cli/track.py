"""``sonartrack track``: the trackers on a user's own data (the track system, systems/track/).

* ``--contacts FILE`` (with ``--nav FILE`` for raw bistatic columns): IPDA / IMM-IPDA position
  tracking with track management (the P4 tracker; systems/track/run.py ``run_contacts``); writes
  ``tracks.csv`` (one row per live track per scan, with existence and status) and ``tracks.png``
  (tracks over contacts).
* ``--peaks FILE``: JPDA / JPDA_A bearing tracking of cross-correlation peaks with automatic initiation
  (the P0 tracker; ``run_peaks``); writes ``bearing_tracks.csv`` and ``bearing_tracks.png`` (the waterfall
  with the confirmed tracks drawn over the peaks).

Settings: systems/track/settings.py (``--config`` TOML with a ``[tracker]`` table; ``--print-config``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.cli._settings import PRINT_CONFIG_HELP, option_help, output_folder, print_config_and_exit, resolve
from sonartrack.core.errors import InputError
from sonartrack.systems.track.settings import ContactsTrackSettings, PeaksTrackSettings

CONTACTS_HELP = ("Contacts CSV/Parquet: time_s, x_m, y_m [+ var_x_m2, var_y_m2, cov_xy_m2] or raw bistatic time_s, "
                 "travel_time_s, bearing_deg.")
#: --tracker values -> the associator setting
TRACKER_CHOICES = {"jpda": "jpda", "jpda-a": "jpda_a", "jpda_a": "jpda_a"}


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
        if tracker is not None and tracker not in TRACKER_CHOICES:
            raise InputError(f"unknown --tracker '{tracker}' for --peaks: choose jpda or jpda-a")
        peak_settings = resolve(PeaksTrackSettings, config, associator=TRACKER_CHOICES.get(tracker))
        if print_config:
            print_config_and_exit(peak_settings)
        typer.echo(track_peaks_command(peaks, peak_settings, out=out))
        return
    settings = resolve(ContactsTrackSettings, config)
    if print_config:
        print_config_and_exit(settings)
    typer.echo(track_contacts_command(contacts, settings, nav=nav, out=out, confirmed_only=confirmed_only))


def track_contacts_command(contacts: Path, settings: ContactsTrackSettings, *, nav: Path | None, out: Path,
                           confirmed_only: bool = False) -> str:
    """Read the contacts, track them (systems/track), write tracks.csv and tracks.png; the one-line summary."""
    from sonartrack.report.figures.tracks import tracks_png
    from sonartrack.systems.track.files import read_contacts_file, write_contact_tracks
    from sonartrack.systems.track.run import run_contacts

    data = read_contacts_file(contacts, settings, nav=nav)
    with output_folder(out):
        result = run_contacts(data, settings, confirmed_only=confirmed_only)
        csv = write_contact_tracks(result, out)
        png = tracks_png(out / "tracks.png", data.z, result.tracks.to_frame())
    return f"{result.summary()}; wrote {csv} and {png}"


def track_peaks_command(peaks: Path, settings: PeaksTrackSettings, *, out: Path) -> str:
    """Read the peaks, track them (systems/track), write bearing_tracks.csv and .png; the one-line summary."""
    from sonartrack.report.figures.bearings import bearing_tracks_png
    from sonartrack.systems.track.files import read_peaks_file, write_peak_tracks
    from sonartrack.systems.track.run import run_peaks

    rec = read_peaks_file(peaks)
    out = Path(out)
    with output_folder(out):
        result = run_peaks(rec, settings)
        csv = write_peak_tracks(result, out)
        png = bearing_tracks_png(out / "bearing_tracks.png", rec, result.tracks.to_frame(),
                                 title=f"{peaks.name}: {result.name} tracks")
    return f"{result.summary()}; wrote {csv} and {png}"

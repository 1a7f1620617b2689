"""``sonartrack track``: the trackers on a user's own data.

* ``--contacts FILE`` (with ``--nav FILE`` for raw bistatic columns): IPDA / IMM-IPDA position
  tracking with track management (the P4 tracker); writes ``tracks.csv`` (one row per live track per
  scan, with existence and status) and ``tracks.png`` (tracks over contacts).
* ``--peaks FILE``: JPDA / JPDA_A bearing tracking of cross-correlation peaks (the P0 tracker).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated

import typer

from sonartrack.core.errors import InputError


def register(app: typer.Typer) -> None:
    app.command("track")(track_cmd)


def track_cmd(
    contacts: Annotated[Path | None, typer.Option(help="Contacts CSV/Parquet: time_s, x_m, y_m [+ var_x_m2, var_y_m2, cov_xy_m2] or raw bistatic time_s, travel_time_s, bearing_deg.")] = None,
    nav: Annotated[Path | None, typer.Option(help="Navigation CSV/Parquet for raw bistatic contacts: time_s, tx_x_m, tx_y_m, rx_x_m, rx_y_m, array_heading_deg.")] = None,
    peaks: Annotated[Path | None, typer.Option(help="Bearing peaks CSV (time_s, bearing_deg, amplitude) for JPDA tracking.")] = None,
    tracker: Annotated[str, typer.Option(help="For --peaks: jpda or jpda-a.")] = "jpda-a",
    config: Annotated[Path | None, typer.Option(help="TOML file with tracker settings.")] = None,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("tracks"),
    confirmed_only: Annotated[bool, typer.Option("--confirmed-only", help="Write confirmed tracks only.")] = False,
) -> None:
    """Track a user's contacts (IPDA / IMM-IPDA) or bearing peaks (JPDA / JPDA_A)."""
    if (contacts is None) == (peaks is None):
        raise InputError("give exactly one of --contacts FILE or --peaks FILE")
    if peaks is not None:
        try:
            from sonartrack.cli._track_peaks import track_peaks_command
        except ImportError:
            raise InputError("bearing-peak tracking is not available in this installation") from None
        typer.echo(track_peaks_command(peaks, tracker=tracker, config=config, out=out))
        return
    typer.echo(track_contacts(contacts, nav=nav, config=config, out=out, confirmed_only=confirmed_only))


def track_contacts(contacts: Path, *, nav: Path | None, config: Path | None, out: Path, confirmed_only: bool = False) -> str:
    """Run the IPDA / IMM-IPDA tracker over a contacts file; return the one-line summary."""
    import numpy as np
    import pandas as pd

    from sonartrack.io import toml as toml_io
    from sonartrack.io.contacts import read_contacts
    from sonartrack.io.track_config import TrackCommandConfig
    from sonartrack.tracking.tracker import CONFIRMED, Tracker

    cfg = toml_io.validate(TrackCommandConfig, toml_io.load(config) if config else {}, source=f"config {config}")
    data = read_contacts(contacts, nav_path=nav, default_sigma_m=cfg.default_sigma_m,
                         bistatic_errors=cfg.bistatic.errors(), sound_speed_mps=cfg.bistatic.sound_speed_mps)
    trk = Tracker(cfg.tracker_config())
    rows = []
    n_scans = 0
    for t, z, R in data.scans():
        snap = trk.step(t, z, R)
        n_scans += 1
        keep = snap.confirmed if confirmed_only else np.ones(len(snap.track_id), bool)
        for i in np.nonzero(keep)[0]:
            row = {"time_s": t, "track_id": int(snap.track_id[i]),
                   "status": "confirmed" if snap.status[i] == CONFIRMED else "tentative",
                   "existence": float(snap.existence[i]), "x_m": snap.x[i, 0], "y_m": snap.x[i, 1],
                   "vx_mps": snap.x[i, 2], "vy_mps": snap.x[i, 3],
                   "sd_x_m": float(np.sqrt(snap.P[i, 0, 0])), "sd_y_m": float(np.sqrt(snap.P[i, 1, 1]))}
            for j, m in enumerate(snap.mu[i]):
                row[f"mode_prob_{j}"] = float(m)
            rows.append(row)
    cols = ["time_s", "track_id", "status", "existence", "x_m", "y_m", "vx_mps", "vy_mps", "sd_x_m", "sd_y_m"] + \
           [f"mode_prob_{j}" for j in range(len(cfg.q))]
    table = pd.DataFrame(rows, columns=cols)
    out.mkdir(parents=True, exist_ok=True)
    csv_tmp, png_tmp = out / f".tracks.csv.{os.getpid()}.tmp", out / f".tracks.png.{os.getpid()}.tmp"
    table.to_csv(csv_tmp, index=False)
    _plot(data, table, png_tmp)
    os.replace(csv_tmp, out / "tracks.csv")
    os.replace(png_tmp, out / "tracks.png")
    confirmed_ids = table.loc[table.status == "confirmed", "track_id"].unique()
    return (f"{n_scans} scans, {len(data.time_s)} contacts -> {len(confirmed_ids)} confirmed track(s); "
            f"wrote {out / 'tracks.csv'} and {out / 'tracks.png'}")


def _plot(data, table, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 7))
    ax.plot(data.z[:, 0] / 1e3, data.z[:, 1] / 1e3, ".", color="0.7", ms=2, label="contacts")
    conf = table[table.status == "confirmed"]
    for tid, g in conf.groupby("track_id"):
        ax.plot(g.x_m / 1e3, g.y_m / 1e3, "-", lw=1.5, label=f"track {tid}")
    ax.set(xlabel="x east (km)", ylabel="y north (km)", title="Confirmed tracks over contacts", aspect="equal")
    if conf.track_id.nunique() <= 12:
        ax.legend(fontsize=7)
    fig.savefig(path, dpi=110, bbox_inches="tight", format="png")
    plt.close(fig)

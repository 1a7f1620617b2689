"""``sonartrack track --peaks``: JPDA / JPDA_A bearing tracking of a peaks file with automatic initiation.

Tracks start on strong unassociated peaks and are confirmed M-of-N (tracking/run.py ``track_peaks``);
JPDA_A uses the track strength of eq. 9. Output (atomic): ``bearing_tracks.csv`` (time_s, track_id,
bearing_deg, bearing_rate_deg_s, bearing_std_deg, strength, confirmed: a row per live track per scan) and
``bearing_tracks.png`` (the waterfall with the confirmed tracks drawn over the peaks).
"""

from __future__ import annotations

from pathlib import Path

from sonartrack.cli._settings import output_folder, print_config_and_exit, resolve
from sonartrack.core.errors import InputError
from sonartrack.io.track_config import PeaksTrackSettings

#: --tracker values -> the associator setting
TRACKER_CHOICES = {"jpda": "jpda", "jpda-a": "jpda_a", "jpda_a": "jpda_a"}


def track_peaks_command(peaks: Path, *, tracker: str | None, config: Path | None, out: Path,
                        print_config: bool = False) -> str:
    """Resolve the settings, track the peaks, write the table and the picture; the one-line summary."""
    if tracker is not None and tracker not in TRACKER_CHOICES:
        raise InputError(f"unknown --tracker '{tracker}' for --peaks: choose jpda or jpda-a")
    settings = resolve(PeaksTrackSettings, config, associator=TRACKER_CHOICES.get(tracker))
    if print_config:
        print_config_and_exit(settings)
    from sonartrack.io.atomic import write_csv
    from sonartrack.io.peaks import read_peaks_csv
    from sonartrack.report.figures.bearings import bearing_tracks_png
    from sonartrack.tracking.run import track_peaks

    rec = read_peaks_csv(peaks)
    name = settings.associator.upper().replace("_", "-")
    out = Path(out)
    with output_folder(out):
        table = track_peaks(rec.time_s, rec.bearing_deg, rec.amplitude, settings.tracker,
                            amplitude_aided=settings.associator == "jpda_a")
        csv = write_csv(table, out / "bearing_tracks.csv", float_format="%.6g")
        png = bearing_tracks_png(out / "bearing_tracks.png", rec, table, title=f"{peaks.name}: {name} tracks")
    n_confirmed = table.loc[table["confirmed"].astype(bool), "track_id"].nunique()
    return (f"track {name.lower()}: {len(set(rec.time_s.tolist()))} scans, {len(rec.time_s)} peaks, {n_confirmed} "
            f"confirmed track(s) ({table['track_id'].nunique()} started); wrote {csv} and {png}")

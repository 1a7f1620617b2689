"""The chain on files: a WAV recording (io/wav_blocks.py, read in blocks) and a navigation CSV
(io/navigation.py) in; the tables of passive/tables.py out (written atomically)."""

from __future__ import annotations

from pathlib import Path

from sonartrack.core.errors import require
from sonartrack.io.atomic import write_csv
from sonartrack.io.navigation import check_navigation_covers, read_navigation
from sonartrack.io.wav_blocks import iter_wav_blocks, read_wav_info
from sonartrack.passive.chain import PassiveResult, check_inputs, run_passive
from sonartrack.passive.settings import PassiveSettings
from sonartrack.passive.tables import peaks_table, targets_table


def run_passive_files(wav_path, nav_path, settings: PassiveSettings, *, progress=None) -> PassiveResult:
    """Check the recording against the array and the navigation, then run the chain over it."""
    info = read_wav_info(wav_path)
    check_inputs(info.channels, info.sample_rate_hz, settings)
    settings = settings.model_copy(update={"elements": info.channels})
    window = int(round(settings.front_end.window_s * info.sample_rate_hz))
    n_windows = info.frames // window
    require(n_windows >= 1, f"{Path(wav_path).name} lasts {info.duration_s:.2f} s, less than one "
                            f"{settings.front_end.window_s:g} s window")
    nav = read_navigation(nav_path)
    check_navigation_covers(nav, 0.0, n_windows * settings.front_end.window_s, path=f"navigation file {nav_path}")
    return run_passive(lambda: iter_wav_blocks(info, window, stop_frame=n_windows * window), info.sample_rate_hz,
                       n_windows, nav, settings, progress=progress)


def write_passive_tables(result: PassiveResult, out: Path) -> list[Path]:
    """peaks.csv, bearing_tracks.csv and targets.csv in ``out``."""
    out = Path(out)
    return [write_csv(peaks_table(result.record), out / "peaks.csv"),
            write_csv(result.tracks, out / "bearing_tracks.csv"),
            write_csv(targets_table(result), out / "targets.csv")]

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
    if info.channels == 2:
        settings = two_sensor_settings(settings, info.sample_rate_hz)
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


def two_sensor_settings(settings: PassiveSettings, fs_hz: float) -> PassiveSettings:
    """A 2-channel recording is two sensors, as in paper P0: their cross-correlation (the split-array method with one
    element per half) over a broad band, [fs / 80, fs / 4] (50-1000 Hz at 4 kHz) unless ``band_hz`` is given. A
    time delay of broadband noise is unambiguous over the physical lags, so the sensor spacing may exceed half a
    wavelength (P0's 20 m does) and grating lobes are accepted."""
    fe = settings.front_end
    band = fe.band_hz if fe.band_hz is not None else [fs_hz / 80.0, fs_hz / 4.0]
    front_end = fe.model_copy(update={"method": "split-array", "band_hz": band, "allow_grating_lobes": True})
    return settings.model_copy(update={"front_end": front_end})


def write_passive_tables(result: PassiveResult, out: Path) -> list[Path]:
    """peaks.csv, bearing_tracks.csv and targets.csv in ``out``."""
    out = Path(out)
    return [write_csv(peaks_table(result.record), out / "peaks.csv"),
            write_csv(result.tracks, out / "bearing_tracks.csv"),
            write_csv(targets_table(result), out / "targets.csv")]

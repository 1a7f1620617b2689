"""The passive sonar chain: an array recording and its navigation in, target tracks and solutions out.

Stages (each a library function of its own; this module only joins them):

1. front end (acoustics/beamforming.py): per window, beam powers over cone angle, normalised against the
   background across bearing, peaks above the threshold -> bearing-time record and peaks;
2. bearing tracking (tracking/run.py :func:`track_peaks`): JPDA_A on the peaks (paper P0), tracks started
   on strong peaks and confirmed M-of-N, dropped after a run of empty gates;
3. each confirmed track's raw peaks (passive/measurements.py; two tracks on the same peaks joined, scans
   where two targets share a beam left out) and, in a second pass over the recording,
   its tonal line on its own beam (passive/tonal_pass.py);
4. per track: the array side from the two mirror hypotheses, batch ML and IMM-MGEKF TMA
   (passive/targets.py).

The recording arrives as blocks of ``window_s`` (``blocks()`` is called once per pass, and must give the
same blocks each time), so memory does not grow with the recording's length.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from sonartrack.acoustics.beamforming import BearingTimeRecord, bearing_time_record, check_array
from sonartrack.core.errors import require
from sonartrack.passive.measurements import drop_unresolved, merge_duplicates, track_measurements
from sonartrack.passive.settings import PassiveSettings
from sonartrack.passive.targets import Target, solve_target
from sonartrack.passive.tonal_pass import measure_tonals
from sonartrack.tracking.run import track_peaks


@dataclass(frozen=True, slots=True)
class PassiveResult:
    """Everything the chain produced (the faces write and draw it)."""

    record: BearingTimeRecord
    tracks: object  # DataFrame of tracking/run.py PEAK_TRACK_COLUMNS
    targets: list[Target]
    #: confirmed tracks too short for TMA (ids)
    short_tracks: list[int]
    duration_s: float
    settings: PassiveSettings


class _Stage:
    """``progress`` hooks (start(label, total, done), advance(n)) around one pass, or nothing."""

    def __init__(self, progress, label: str, total: int):
        self.progress = progress
        if progress is not None:
            progress.start(label, total, 0)

    def __call__(self, _k: int) -> None:
        if self.progress is not None:
            self.progress.advance(1)


def run_passive(blocks: Callable[[], Iterable[np.ndarray]], fs_hz: float, n_windows: int, nav,
                settings: PassiveSettings, *, progress=None, amplitude_aided: bool = True) -> PassiveResult:
    """Run the chain over ``n_windows`` blocks of ``settings.front_end.window_s`` (module docstring).

    ``nav`` is an :class:`~sonartrack.io.navigation.Navigation` covering the recording. ``amplitude_aided``
    False tracks with plain JPDA (for comparison)."""
    s = settings
    require(s.spacing_m is not None, "the element spacing is not set: give --spacing (metres)")
    fe = s.front_end
    btr = bearing_time_record(blocks(), fs_hz, s.spacing_m, fe, progress=_Stage(progress, "beamforming", n_windows))
    pk = btr.peaks
    tracks = track_peaks(pk.time_s, pk.bearing_deg, pk.amplitude, s.tracker, amplitude_aided=amplitude_aided)
    meas = merge_duplicates(track_measurements(tracks, pk, s.max_peak_offset_deg), s.max_peak_offset_deg)
    meas = drop_unresolved(meas, s.min_separation_for(fs_hz))
    long_enough = [m for m in meas if m.duration_s >= s.min_track_s and len(m.time_s) >= 10]
    short = [m.track_id for m in meas if m not in long_enough]
    tonals = [None] * len(long_enough)
    if long_enough:
        tonals = measure_tonals(blocks(), fs_hz, s.spacing_m, long_enough, s.tonal, n_windows,
                                progress=_Stage(progress, "tonal lines", n_windows))
    targets = [solve_target(i + 1, m, tonal, nav, s) for i, (m, tonal) in enumerate(zip(long_enough, tonals,
                                                                                       strict=True))]
    return PassiveResult(btr, tracks, targets, short, n_windows * fe.window_s, s)


def check_inputs(channels: int, fs_hz: float, settings: PassiveSettings) -> None:
    """The recording must match the declared array, and the array must not alias the band."""
    s = settings
    require(s.spacing_m is not None, "the element spacing is not set: give --spacing (metres)")
    if s.elements is not None:
        require(channels == s.elements, f"the recording has {channels} channels but --elements is {s.elements}: "
                                        "give the recording of the whole array, or the right --elements")
    require(channels >= 2, f"the recording has {channels} channel(s): a line array needs at least two")
    check_array(channels, s.spacing_m, s.front_end, fs_hz=fs_hz)

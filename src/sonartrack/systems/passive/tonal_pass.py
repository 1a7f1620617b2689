"""Second pass over the recording: each confirmed track's tonal line, measured on its own beam.

The tracks are known only after the whole recording has been tracked, so the tonal measurement reads the
recording a second time (block by block, memory flat): at each window, a conventional beam is steered at
every live track's cone angle (acoustics/tonal.py :func:`beam_spectra`) and its spectrum goes to that
track's :class:`~sonartrack.acoustics.tonal.TonalAccumulator`, which keeps the mean spectrum (to find the
line) and a few candidate frequencies per window (to follow it). The chain runs it on the track fragments
before they are joined (systems/passive/chain.py), so that the lines can take part in the join.

Why a second read rather than keeping the first pass's spectra: the beams need each window's spectra of the
tonal band (at 32 channels x 8 kHz, 32 x 953 bins x 8 bytes in single precision = 0.24 MB a window, 0.15 GB per
10 minutes: a temporary file), which would cost the first pass the very transform this pass makes; the second read
adds only the decoding of the file (~0.2 ms a window of a float32 file, 0.1 s per 10 minutes at 32 x 8 kHz), less
than writing and reading back 0.15 GB.

Cost per window (32 x 8 kHz, 4 live tracks): the transform of every channel in the blocks' own precision
(float32 for float32 and PCM files: 0.4 ms, less than half a double copy's, with a rounding far below a
periodogram's noise: acoustics/tonal.py :func:`beam_spectra`), the live tracks' beams (0.2 ms), and their peaks
found together (:func:`~sonartrack.acoustics.tonal.window_peak_bins`: one running median for all beams).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np

from sonartrack.acoustics.line_array import LineArray
from sonartrack.acoustics.tonal import TonalAccumulator, TonalSettings, TonalTrack, beam_spectra, window_peak_bins
from sonartrack.systems.passive.measurements import TrackMeasurements


def live_cones(measurements: list[TrackMeasurements], window_s: float,
               n_windows: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The tracks alive in each window.

    Parameters
    ----------
    measurements : list of TrackMeasurements
        The tracks (their filtered cone angle at every scan they lived).
    window_s : float
        The window (s): a track time t falls in window floor(t / window_s).
    n_windows : int
        Number of windows of the recording.

    Returns
    -------
    list of (ndarray, ndarray)
        Per window: indices into ``measurements`` and the tracks' cone angles (deg) there.
    """
    ks, ids, cones = [np.empty(0, np.int64)], [np.empty(0, np.int64)], [np.empty(0)]
    for i, m in enumerate(measurements):
        k = np.floor(np.asarray(m.track_time_s) / window_s).astype(np.int64)
        ok = (k >= 0) & (k < n_windows)
        ks.append(k[ok])
        ids.append(np.full(int(ok.sum()), i, np.int64))
        cones.append(np.asarray(m.track_cone_deg, dtype=float)[ok])
    # grouped by window with a stable sort: within a window the tracks keep their order, each its scans' order
    order = np.argsort(np.concatenate(ks), kind="stable")
    k_sorted = np.concatenate(ks)[order]
    bounds = np.searchsorted(k_sorted, np.arange(n_windows + 1), side="left")
    id_sorted, cone_sorted = np.concatenate(ids)[order], np.concatenate(cones)[order]
    return [(id_sorted[a:b], cone_sorted[a:b]) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def measure_tonals(blocks: Iterable[np.ndarray], fs_hz: float, array: LineArray,
                   measurements: list[TrackMeasurements], settings: TonalSettings, n_windows: int,
                   progress: Callable[[int], None] | None = None) -> list[TonalTrack | None]:
    """The tonal line of each track, measured on its own beam in a second pass over the recording (module doc).

    Parameters
    ----------
    blocks : iterable of ndarray (N, window_s fs)
        The recording's windows, the same as the front end's.
    fs_hz : float
        Sample rate (Hz).
    array : LineArray
        The line array (the beams' steering).
    measurements : list of TrackMeasurements
        The tracks.
    settings : TonalSettings
        The tonal measurement; its ``window_s`` is the windows' length, and window k's spectrum is stamped at
        its centre (k + 0.5) window_s.
    n_windows : int
        Number of windows to read.
    progress : callable, optional
        Called with k after window k.

    Returns
    -------
    list of (TonalTrack or None)
        Per track, its tonal line, or None where it carries none.
    """
    live = live_cones(measurements, settings.window_s, n_windows)
    acc: list[TonalAccumulator | None] = [None] * len(measurements)
    for k, block in enumerate(blocks):
        if k >= n_windows:
            break
        idx, cones = live[k]
        if len(idx):
            # the block as read: a float32 block is transformed in single precision (acoustics/tonal.py
            # beam_spectra), five times faster than a double copy, on the file's layout as it comes
            freqs, power = beam_spectra(block, fs_hz, array, cones, settings)
            # every live beam's peaks at once (one running-median call): those each beam's accumulator would find
            peaks = window_peak_bins(power, freqs[1] - freqs[0], settings) if freqs.size >= 3 else [None] * len(idx)
            for row, i in enumerate(idx):
                if acc[i] is None:
                    acc[i] = TonalAccumulator(settings, len(freqs))
                acc[i].add((k + 0.5) * settings.window_s, power[row], freqs, peak_bins=peaks[row])
        if progress is not None:
            progress(k)
    others = [a for a in acc if a is not None]
    # a loud line leaks into every beam: a line counts for a track only if it stands highest on that track's
    # own beam (acoustics/tonal.py TonalAccumulator.result)
    return [a.result(others=[o for o in others if o is not a]) if a is not None else None for a in acc]

"""Second pass over the recording: each confirmed track's tonal line, measured on its own beam.

The tracks are known only after the whole recording has been tracked, so the tonal measurement reads the
recording a second time (block by block, memory flat): at each window, a conventional beam is steered at
every live track's cone angle (acoustics/tonal.py :func:`beam_spectra`) and its spectrum goes to that
track's :class:`~sonartrack.acoustics.tonal.TonalAccumulator`, which keeps the mean spectrum (to find the
line) and a few candidate frequencies per window (to follow it). The chain runs it on the track fragments
before they are joined (systems/passive/chain.py), so that the lines can take part in the join.

The windows' spectra of the tonal band come from the front end's own transforms when the chain keeps them
(:class:`SpectraSpill`: acoustics/beamforming.py hands each batch's rectangular spectra to it, a slice of the
transforms it makes anyway): at 32 channels x 8 kHz, 32 x 955 bins x 8 bytes = 0.24 MB a window, 0.15 GB per 10
minutes in a temporary file (memory flat), written and read back for ~0.1 s of CPU against the 0.35 s transform and
0.15 s decoding of a second read. Without them (another front end method, or blocks of another precision than
the front end's, whose spectra it rounds) the recording is read and transformed a second time.

Cost per window (32 x 8 kHz, 4 live tracks): without a spill, the transform of every channel in the blocks' own
precision (float32 for float32 and PCM files: 0.4 ms, less than half a double copy's, with a rounding far below a
periodogram's noise: acoustics/tonal.py :func:`beam_spectra`), the live tracks' beams (0.2 ms), and their peaks
found together (:func:`~sonartrack.acoustics.tonal.window_peak_bins`: one running median for all beams).
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from sonartrack.acoustics.line_array import LineArray
from sonartrack.acoustics.tonal import (
    TonalAccumulator,
    TonalSettings,
    TonalTrack,
    beam_spectra,
    beam_spectra_of_rect,
    tonal_rect_bins,
    window_peak_bins,
)
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


@dataclass(frozen=True)
class RectWindow:
    """One window given by its rectangular rfft spectra (N, F + 2) over the tonal band's bins and one beyond each
    edge (acoustics/tonal.py ``tonal_rect_bins``), and its length in samples."""

    spectra: np.ndarray
    n_samples: int


#: largest temporary spill of the tonal band's spectra (bytes; about 147 MB per 10 minutes at 32 channels x 8 kHz,
#: so 2 GB holds 2 hours at 32 channels, 1 hour at 64): a longer recording's tonal pass reads it again instead
SPILL_LIMIT_BYTES = 2 * 1024**3


class SpectraSpill:
    """The front end's rectangular spectra of every window over the tonal band (acoustics/tonal.py
    ``tonal_rect_bins``), kept in a temporary file for the tonal pass (module doc): the front end's
    ``spectra_sink`` (acoustics/beamforming.py ``bearing_time_record``), read back by :meth:`windows`.

    Parameters
    ----------
    n_samples : int
        The windows' length (samples).
    fs_hz : float
        Sample rate (Hz).
    settings : TonalSettings
        ``band_hz``.
    """

    def __init__(self, n_samples: int, fs_hz: float, settings: TonalSettings):
        self.n_samples = int(n_samples)
        #: the bins kept (None: the band has none to keep, and nothing is written)
        self.bins = tonal_rect_bins(self.n_samples, fs_hz, settings)
        self.count, self.exact = 0, True
        self._shape: tuple[int, ...] | None = None
        self._dtype: np.dtype | None = None
        self._file = tempfile.TemporaryFile()  # noqa: SIM115 - open across the two passes; close() removes it

    def write(self, spectra: np.ndarray, exact: bool) -> None:
        """Append K windows' spectra (K, N, bins) (``exact``: False once a window was rounded to the front end's
        precision; the spill then stands for no second read). Past :data:`SPILL_LIMIT_BYTES`, or when the disk
        refuses the bytes (full, quota), spilling stops and the tonal pass reads the recording again: the spill
        saves time, never a run."""
        if not self.exact:
            return
        spectra = np.ascontiguousarray(spectra)
        if self._file.tell() + spectra.nbytes > SPILL_LIMIT_BYTES:
            self._give_up()
            return
        self._shape, self._dtype = spectra.shape[1:], spectra.dtype
        try:
            self._file.write(spectra.tobytes())
        except OSError:
            self._give_up()
            return
        self.count += spectra.shape[0]
        self.exact = bool(exact)

    def _give_up(self) -> None:
        """No spill: free its disk at once (the second read makes the tonal spectra)."""
        self.exact = False
        self._file.close()
        self._file = tempfile.TemporaryFile()  # noqa: SIM115 - an empty stand-in, closed by close()

    def usable(self, n_windows: int) -> bool:
        """Whether the spill holds the first ``n_windows`` windows exactly as a second read would transform them."""
        return self.bins is not None and self.exact and self.count >= n_windows > 0

    def windows(self) -> Iterator[RectWindow]:
        """The windows in order, through one reused buffer (each is done with when the next is asked for)."""
        if self._shape is None:
            return
        self._file.seek(0)
        buf = np.empty(self._shape, dtype=self._dtype)
        view = memoryview(buf).cast("B")
        for _ in range(self.count):
            if self._file.readinto(view) != buf.nbytes:
                raise OSError("tonal spill: the temporary file ended early")
            yield RectWindow(buf, self.n_samples)

    def close(self) -> None:
        """Remove the temporary file."""
        self._file.close()


def measure_tonals(blocks: Iterable[np.ndarray], fs_hz: float, array: LineArray,
                   measurements: list[TrackMeasurements], settings: TonalSettings, n_windows: int,
                   progress: Callable[[int], None] | None = None, first_window: int = 0) -> list[TonalTrack | None]:
    """The tonal line of each track, measured on its own beam in a second pass over the recording (module doc).

    Parameters
    ----------
    blocks : iterable of ndarray (N, window_s fs) or of RectWindow, or an object with ``tonals_of``
        The recording's windows, the same as the front end's, or their rectangular spectra
        (:meth:`SpectraSpill.windows`); or the live chain's accumulators kept as the windows came
        (systems/live/tonals.py :class:`~sonartrack.systems.live.tonals.LiveTonals`), whose ``tonals_of(measurements)``
        is then the answer.
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
    first_window : int
        The index of the first window ``blocks`` gives (the live chain keeps the last hour's spectra: systems/live/);
        ``n_windows`` are read from it.

    Returns
    -------
    list of (TonalTrack or None)
        Per track, its tonal line, or None where it carries none.
    """
    if hasattr(blocks, "tonals_of"):  # the live chain's accumulators, kept as the windows came (systems/live/)
        return blocks.tonals_of(measurements)
    live = live_cones(measurements, settings.window_s, first_window + n_windows)
    acc: list[TonalAccumulator | None] = [None] * len(measurements)

    def acc_of(i: int, n_bins: int) -> TonalAccumulator:
        if acc[i] is None:
            acc[i] = TonalAccumulator(settings, n_bins)
        return acc[i]

    for k, block in enumerate(blocks, start=first_window):
        if k >= first_window + n_windows:
            break
        idx, cones = live[k]
        if len(idx):
            add_window(acc_of, k, block, fs_hz, array, idx, cones, settings)
        if progress is not None:
            progress(k)
    return tonal_results(acc)


def add_window(acc_of: Callable[[int, int], TonalAccumulator], k: int, block, fs_hz: float, array: LineArray,
               ids, cones_deg: np.ndarray, settings: TonalSettings) -> None:
    """Window k's beams at the tracks' cone angles into their accumulators (``acc_of(id, n_bins)`` gives track id's).

    The block as read: a float32 block is transformed in single precision (acoustics/tonal.py beam_spectra), five
    times faster than a double copy, on the file's layout as it comes; a RectWindow's spectra are steered as they
    are. Every beam's peaks are found at once (one running-median call): those each accumulator would find.
    """
    freqs, power = (beam_spectra_of_rect(block.spectra, block.n_samples, fs_hz, array, cones_deg, settings)
                    if isinstance(block, RectWindow) else beam_spectra(block, fs_hz, array, cones_deg, settings))
    peaks = window_peak_bins(power, freqs[1] - freqs[0], settings) if freqs.size >= 3 else [None] * len(ids)
    for row, i in enumerate(ids):
        acc_of(i, len(freqs)).add((k + 0.5) * settings.window_s, power[row], freqs, peak_bins=peaks[row])


def tonal_results(acc: list[TonalAccumulator | None]) -> list[TonalTrack | None]:
    """Each accumulator's line (None where none): a loud line leaks into every beam, so a line counts for a track
    only if it stands highest on that track's own beam (acoustics/tonal.py TonalAccumulator.result)."""
    others = [a for a in acc if a is not None]
    return [a.result(others=[o for o in others if o is not a]) if a is not None else None for a in acc]

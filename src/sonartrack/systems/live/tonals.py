"""The tonal measurement of the live chain kept as the windows arrive: per-track accumulators, so that a refresh
costs the same after an hour as after a minute.

The file chain measures each track's tonal line in a second pass over the recording once the tracks are known
(systems/passive/tonal_pass.py :func:`~sonartrack.systems.passive.tonal_pass.measure_tonals`). A live refresh that
did the same re-read the whole history every time: 4 s of the 6 s refresh at 15 minutes of history, 16 s at an
hour, growing with it. Here each scan's confirmed tracks get window k's beam spectra at their filtered cone angles
as the scan is made (the same beams, peaks and :class:`~sonartrack.acoustics.tonal.TonalAccumulator` as the file
pass: :func:`~sonartrack.systems.passive.tonal_pass.add_window`, on the window's spectra in the ring,
systems/live/windows.py), and a refresh reads the accumulators' lines. Cost: the live tracks' beams and one
running median per window (~4 ms at 16 x 4 kHz with 3 tracks), on the window's path.

Bounded state: a track's accumulator is cut into chunks of ``chunk_windows`` (10 minutes); chunks older than the
history are dropped and a track's line is that of its chunks merged (power sums added, per-window candidates
joined), so a track followed all day holds the last ``history_s`` (plus at most one chunk) like the TMA.

What differs from the file pass (a refresh's preview only: :meth:`LivePassive.finish` runs the file pass on the
spectra ring when it holds the whole history): a track is fed from the scan it is confirmed at (the file pass also
reads its tentative scans), by the tracker's id (duplicates the finishing merges keep the earlier id's line), and its
provisional lines are renewed per chunk. After a restore from a checkpoint the accumulators come back with it while
the ring starts empty: the finish then uses them too.
"""

from __future__ import annotations

from array import array
from collections import deque

import numpy as np

from sonartrack.acoustics.tonal import TonalAccumulator, TonalTrack
from sonartrack.systems.passive.tonal_pass import add_window, tonal_results

#: windows per accumulator chunk (10 minutes of 1 s windows)
CHUNK_WINDOWS = 600


class LiveTonals:
    """Per-track tonal accumulators fed scan by scan (module doc).

    Parameters
    ----------
    stages : PassiveStages
        The chain's settings (sample rate, array, tonal settings).
    spill : RingSpill
        The ring of the windows' spectra over the tonal band (systems/live/windows.py).
    chunk_windows : int
        Windows per chunk.
    """

    def __init__(self, stages, spill, chunk_windows: int = CHUNK_WINDOWS):
        self.stages, self.spill, self.chunk_windows = stages, spill, int(chunk_windows)
        #: track id -> deque of (chunk index, TonalAccumulator)
        self.tracks: dict[int, deque] = {}

    def add_scan(self, k: int, rows: dict) -> None:
        """Window k's beams at the scan's confirmed tracks into their accumulators."""
        ok = np.asarray(rows["confirmed"], bool)
        if self.spill.bins is None or not ok.any():
            return
        block = next(iter(self.spill.windows(k, k + 1)), None)
        if block is None:  # the window's spectra are gone (or were never written): nothing to add
            return
        chunk = k // self.chunk_windows

        def acc_of(track_id: int, n_bins: int) -> TonalAccumulator:
            parts = self.tracks.setdefault(int(track_id), deque())
            if not parts or parts[-1][0] != chunk:
                parts.append((chunk, TonalAccumulator(self.stages.tonal, n_bins)))
            return parts[-1][1]

        s = self.stages
        add_window(acc_of, k, block, s.fs_hz, s.array, np.asarray(rows["track_id"])[ok],
                   np.asarray(rows["bearing_deg"], float)[ok], s.tonal)

    def trim(self, first_window: int) -> None:
        """Drop the chunks that end before ``first_window`` (and the tracks left with none)."""
        for tid in list(self.tracks):
            parts = self.tracks[tid]
            while parts and (parts[0][0] + 1) * self.chunk_windows <= first_window:
                parts.popleft()
            if not parts:
                del self.tracks[tid]

    def snapshot(self) -> TonalSnapshot:
        """Each track's chunks merged into one accumulator (copies: the stream goes on adding to the originals)."""
        return TonalSnapshot({tid: _merged([a for _, a in parts]) for tid, parts in self.tracks.items()})


class TonalSnapshot:
    """The accumulators at a moment, answering the tonal pass (systems/passive/tonal_pass.py ``measure_tonals``)."""

    def __init__(self, accumulators: dict[int, TonalAccumulator]):
        self.accumulators = accumulators

    def tonals_of(self, measurements) -> list[TonalTrack | None]:
        """Per measured track, its line (None without an accumulator or a line)."""
        return tonal_results([self.accumulators.get(int(m.track_id)) for m in measurements])


def _merged(parts: list[TonalAccumulator]) -> TonalAccumulator:
    """One accumulator of consecutive chunks: the power sums added, the window times and candidates joined (the
    attributes acoustics/tonal.py's TonalAccumulator.add fills)."""
    first = parts[0]
    out = TonalAccumulator(first.settings, first.n_bins)
    out._freqs_hz = first._freqs_hz  # noqa: SLF001 - the merged state of the same class
    out._power_sum = np.sum([p._power_sum for p in parts], axis=0)  # noqa: SLF001
    out._times, out._candidates = array("d"), array("d")  # noqa: SLF001
    for p in parts:
        out._times.extend(p._times)  # noqa: SLF001
        out._candidates.extend(p._candidates)  # noqa: SLF001
    return out

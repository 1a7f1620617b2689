"""Sample blocks of any size -> the chain's windows, and the tonal band's spectra of the last hour in a ring.

:class:`WindowAssembler`: blocks of a stream (in order, contiguous, gaps reported: io/stream/types.py) are cut into
the chain's windows of ``window_s fs`` samples on the stream's own index, window k holding samples [k M, (k + 1) M).
A window that a gap touches is handed on as zeros (None), as the file chain hands a recording's gap
(systems/passive/files.py): a blank stretch of the bearing-time record, empty scans for the tracker (a track coasts
through a short gap and is dropped after a long one), and the window after the gap starts clean on its own index.
A block that overlaps what was already taken (a duplicate) gives only its new samples.

:class:`RingSpill`: the tonal pass (systems/passive/tonal_pass.py) reads each window's rectangular spectra over the
tonal band once the tracks are known. The file chain keeps every window's in a temporary file (SpectraSpill); the
live chain keeps the last ``capacity`` windows' in a ring of fixed slots in one temporary file (disk bounded: 16
channels x 953 bins x 8 bytes = 122 kB a window at 4 kHz, 0.44 GB per hour), written and read with positional I/O
so a refresh on a worker thread reads while the stream writes. Over a run no longer than the ring, the tonal pass
reads exactly the spectra the file chain's spill holds: the same lines.
"""

from __future__ import annotations

import os
import tempfile

import numpy as np

from sonartrack.acoustics.tonal import TonalSettings, tonal_rect_bins
from sonartrack.systems.passive.tonal_pass import RectWindow


class WindowAssembler:
    """Blocks -> windows (module doc).

    Parameters
    ----------
    channels : int
        Channels of the stream.
    n_samples : int
        Samples of one window.
    """

    def __init__(self, channels: int, n_samples: int):
        self.n = int(n_samples)
        self.buf = np.zeros((int(channels), self.n), np.float32)
        self.fill, self.k, self.touched = 0, None, False
        #: the stream index of the next sample expected (None before the first block)
        self.next_index: int | None = None

    def _start(self, first_index: int) -> None:
        """A stream joined at ``first_index``: its window starts clean at the next window boundary's start, the
        samples before ``first_index`` in it a gap."""
        self.k = first_index // self.n
        self.next_index = self.k * self.n
        if first_index > self.next_index:
            self.touched = True
            self.fill = first_index - self.next_index
            self.next_index = first_index

    def add(self, first_index: int, samples: np.ndarray) -> list[tuple[int, np.ndarray | None]]:
        """Take a block: the windows it completes, (k, samples (channels, M) or None for zeros)."""
        x = np.asarray(samples, np.float32)
        if self.next_index is None:
            self._start(int(first_index))
        out = []
        if first_index > self.next_index:  # samples missing that no event reported: a gap all the same
            out += self.gap(self.next_index, int(first_index) - self.next_index)
        skip = max(0, self.next_index - int(first_index))  # a duplicate's samples already taken
        x = x[skip:]
        pos = 0
        while pos < len(x):
            take = min(len(x) - pos, self.n - self.fill)
            self.buf[:, self.fill:self.fill + take] = x[pos:pos + take].T
            self.fill, pos = self.fill + take, pos + take
            self.next_index += take
            if self.fill == self.n:
                out.append(self._emit())
        return out

    def gap(self, first_index: int, count: int) -> list[tuple[int, np.ndarray | None]]:
        """Samples [first_index, first_index + count) lost: the windows they touch, as zeros."""
        if self.next_index is None:
            self._start(int(first_index) + int(count))
            return []
        end = int(first_index) + int(count)
        out = []
        while self.next_index < end:
            self.touched = True
            take = min(end - self.next_index, self.n - self.fill)
            self.fill += take
            self.next_index += take
            if self.fill == self.n:
                out.append(self._emit())
        return out

    def _emit(self) -> tuple[int, np.ndarray | None]:
        k, block = self.k, None if self.touched else self.buf.copy()
        self.k, self.fill, self.touched = self.k + 1, 0, False
        return k, block

    def state(self) -> dict:
        """What a checkpoint keeps (the part-filled window's samples too)."""
        return {"buf": self.buf[:, :self.fill].copy(), "fill": self.fill, "k": self.k, "touched": self.touched,
                "next_index": self.next_index}

    def restore(self, state: dict) -> None:
        """Back to a checkpoint's :meth:`state`."""
        self.fill, self.k, self.touched = int(state["fill"]), state["k"], bool(state["touched"])
        self.next_index = state["next_index"]
        self.buf[:, :self.fill] = state["buf"]


class RingSpill:
    """The tonal band's rectangular spectra of the last ``capacity`` windows (module doc): the front end's
    ``spectra_sink`` (acoustics/beamforming.py), read back by :meth:`windows`.

    Parameters
    ----------
    n_samples : int
        Samples of a window.
    fs_hz : float
        Sample rate (Hz).
    settings : TonalSettings
        ``band_hz``.
    capacity : int
        Windows kept.
    first_window : int
        The index of the first window written.
    """

    def __init__(self, n_samples: int, fs_hz: float, settings: TonalSettings, capacity: int, first_window: int = 0):
        self.n_samples, self.capacity = int(n_samples), int(capacity)
        self.bins = tonal_rect_bins(self.n_samples, fs_hz, settings)
        self.next_window = int(first_window)
        self.first_window = int(first_window)
        self._shape: tuple[int, ...] | None = None
        self._dtype = None
        self._file = tempfile.TemporaryFile()  # noqa: SIM115 - open for the run; close() removes it

    def write(self, spectra: np.ndarray, exact: bool) -> None:  # noqa: ARG002 - the ring keeps what it is given
        """Append K windows' spectra (K, N, bins)."""
        spectra = np.ascontiguousarray(spectra)
        self._shape, self._dtype = spectra.shape[1:], spectra.dtype
        size = spectra[0].nbytes
        for row in spectra:
            os.pwrite(self._file.fileno(), row.tobytes(), (self.next_window % self.capacity) * size)
            self.next_window += 1
        self.first_window = max(self.first_window, self.next_window - self.capacity)

    def skip_to(self, window: int) -> None:
        """The next window written is ``window`` (the ring restarts empty, e.g. after a restore)."""
        self.next_window = self.first_window = int(window)

    def windows(self, first: int, stop: int):
        """RectWindow of windows first..stop - 1 (those held), through one reused buffer."""
        if self._shape is None:
            return
        buf = np.empty(self._shape, dtype=self._dtype)
        for k in range(max(first, self.first_window), min(stop, self.next_window)):
            data = os.pread(self._file.fileno(), buf.nbytes, (k % self.capacity) * buf.nbytes)
            if len(data) != buf.nbytes:
                raise OSError("live tonal spill: a slot ended early")
            buf[...] = np.frombuffer(data, dtype=self._dtype).reshape(self._shape)
            if k < self.first_window:  # overwritten while read (a refresh slower than the ring's margin): blank
                buf[...] = 0
            yield RectWindow(buf, self.n_samples)

    def close(self) -> None:
        """Remove the temporary file."""
        self._file.close()

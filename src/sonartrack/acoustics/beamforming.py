"""Bearing-time record of a uniform line array: each window's beam powers, normalised across bearing, and peaks.

The front end window by window (:class:`FrontEnd`, :func:`bearing_time_record`), built from its parts:

* acoustics/beamformer_settings.py -- :class:`BeamformerSettings`, :class:`BearingTimeRecord`;
* acoustics/beam_powers.py -- the beam powers over the band (CBF by lag products, split array; MVDR in
  acoustics/mvdr.py), the band (:func:`front_end_band`);
* acoustics/beam_peaks.py -- the normaliser across bearing and the peaks of each window;
* acoustics/beam_pattern.py -- the peaks refined with the array's own beam pattern, hidden peaks.

Their public names are importable from here too (the passive and live chains import them from this module).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Protocol

import numpy as np

from sonartrack.acoustics.beam_pattern import (
    PATTERN_DELTAS,
    PATTERN_ITERATIONS,
    PATTERN_STEP_U,
    BeamPattern,
    add_hidden_peaks,
    beam_pattern,
    pattern_sum,
    resolve_peaks,
    resolve_peaks_batch,
)
from sonartrack.acoustics.beam_peaks import (
    MAD_TO_SIGMA,
    normalise_across_bearing,
    pick_beam_peaks,
    pick_beam_peaks_rows,
)
from sonartrack.acoustics.beam_powers import (
    LAG_CHUNK_WINDOWS,
    Steering,
    _band_steering,
    _cbf_from_spectra,
    _dtypes,
    _rfft_bins,
    alias_free_octave,
    beam_powers,
    cbf_powers,
    combined_statistic,
    front_end_band,
    lag_bin_products,
    split_array_powers,
)
from sonartrack.acoustics.beamformer_settings import BeamformerSettings, BearingTimeRecord
from sonartrack.acoustics.line_array import Band, LineArray
from sonartrack.acoustics.lofar import LofarAccumulator, LofarGram, LofarSettings
from sonartrack.acoustics.xcorr_bearing import PeakRecord
from sonartrack.core.errors import require

__all__ = [
    "BATCH_WINDOWS", "LAG_CHUNK_WINDOWS", "MAD_TO_SIGMA", "PATTERN_DELTAS", "PATTERN_ITERATIONS", "PATTERN_STEP_U",
    "BeamPattern", "BeamformerSettings", "BearingTimeRecord", "FrontEnd", "RecordBuilder", "SpectraSink", "Steering",
    "add_hidden_peaks", "alias_free_octave", "beam_pattern", "beam_powers", "bearing_time_record", "cbf_powers",
    "combined_statistic", "front_end_band", "lag_bin_products", "normalise_across_bearing", "pattern_sum",
    "pick_beam_peaks", "pick_beam_peaks_rows", "resolve_peaks", "resolve_peaks_batch", "split_array_powers",
]

#: windows per batched steering product (memory: batch x 2 Q float64, Q the band's lag-bin products: ~7 MB at 32
#: elements over 50-1000 Hz)
BATCH_WINDOWS = 32


def _batches(blocks: Iterable[np.ndarray], size: int):
    batch: list[np.ndarray] = []
    for b in blocks:
        batch.append(np.asarray(b, dtype=float))
        if len(batch) == size:
            yield np.stack(batch)
            batch = []
    if batch:
        yield np.stack(batch)


def _check_block(shape: tuple[int, ...], n: int, nw: int) -> None:
    require(tuple(shape) == (n, nw), f"blocks must be (elements, window_s * fs) = ({n}, {nw}), got {tuple(shape)}")


def _spectra_batches(blocks: Iterable[np.ndarray], n: int, nw: int, bins: slice, real_dtype: type, size: int,
                     exact: list[bool] | None = None):
    """Batches (K <= size, N, bins) of the windows' rectangular rfft spectra over ``bins``, each window transformed
    as it arrives (only the band's bins are kept: a batch's samples are never held together). The batch is one
    buffer, reused for the next: its consumer is done with it when it asks for the next. ``exact``: set to
    [False] once a block arrives in another precision than ``real_dtype`` (its spectra are rounded to it)."""
    width = bins.stop - bins.start
    buf, k = np.empty((size, n, width), dtype=np.result_type(real_dtype, np.complex64)), 0
    for block in blocks:
        _check_block(np.shape(block), n, nw)
        if exact is not None and np.asarray(block).dtype != real_dtype:
            exact[0] = False
        buf[k] = _rfft_bins(block, bins, real_dtype)
        k += 1
        if k == size:
            yield buf
            k = 0
    if k:
        yield buf[:k]


class SpectraSink(Protocol):
    """Where the CBF front end hands each batch's rectangular rfft spectra over ``bins`` (:func:`bearing_time_record`).
    ``exact`` is False once a window arrived in another precision than the front end's (its spectra were rounded)."""

    bins: slice

    def write(self, spectra: np.ndarray, exact: bool) -> None:
        """Take K windows' rectangular spectra (K, N, bins of :attr:`bins`), in time order (a view of the front
        end's buffer, reused for the next batch: copy what is kept)."""


def _cbf_batches(blocks: Iterable[np.ndarray], fs_hz: float, array: LineArray, s: BeamformerSettings, band: Band,
                 octave: Band | None, lofar: LofarAccumulator | None, sink: SpectraSink | None = None):
    """CBF beam powers (K, B) per batch of windows (the band's, or with ``octave`` the combined statistic of the
    band and that octave: :func:`combined_statistic`), each window transformed once; the same spectra feed the
    LOFAR gram (``lofar``), so the narrowband gram costs no pass of its own, and the ``sink`` (its bins added to
    the span transformed)."""
    n, nw = array.elements, int(round(s.window_s * fs_hz))
    steering = [_band_steering(n, nw, fs_hz, array, s, b) for b in [band] + ([octave] if octave else [])]
    spans = [(int(i[0]), int(i[-1]) + 1) if i.size else (0, 0) for i, _ in steering]
    spans += [(lofar.bins.start, lofar.bins.stop)] if lofar is not None else []
    spans += [(sink.bins.start, sink.bins.stop)] if sink is not None else []
    lo, hi = min(a for a, _ in spans), max(b for _, b in spans)
    exact = [True]
    for spectra in _spectra_batches(blocks, n, nw, slice(lo, hi), _dtypes(s)[0], BATCH_WINDOWS, exact):
        if sink is not None:
            sink.write(spectra[:, :, sink.bins.start - lo: sink.bins.stop - lo], exact[0])
        if lofar is not None:
            lofar.add(spectra[:, :, lofar.bins.start - lo: lofar.bins.stop - lo])
        powers = [_cbf_from_spectra(spectra[:, :, a - lo: b - lo], st, s.whiten)  # the LOFAR's span left out
                  for (a, b), (_, st) in zip(spans, steering, strict=False)]
        yield powers[0] if octave is None else combined_statistic(normalise_across_bearing(powers[0], s),
                                                                  normalise_across_bearing(powers[1], s))


def _other_batches(blocks: Iterable[np.ndarray], fs_hz: float, array: LineArray, s: BeamformerSettings, band: Band,
                   mvdr, lofar: LofarAccumulator | None):
    """Beam powers (K, B) per batch of windows of the ``split-array`` (a batch of one) and ``mvdr`` methods; the
    LOFAR gram (``lofar``) from the same windows' spectra."""
    nw = int(round(s.window_s * fs_hz))
    for batch in _batches(blocks, 1 if s.method == "split-array" else BATCH_WINDOWS):
        _check_block(batch.shape[1:], array.elements, nw)
        if lofar is not None:
            lofar.add(_rfft_bins(batch, lofar.bins, np.float64))
        if s.method == "mvdr":
            from sonartrack.acoustics.mvdr import mvdr_powers

            yield mvdr_powers(batch, fs_hz, array, s, band, mvdr)
        else:
            yield split_array_powers(batch[0], fs_hz, array, s, band)[None]


class FrontEnd:
    """The front end window by window: beam powers, the normaliser and the peaks of each window as it comes, with the
    LOFAR accumulator and the spectra sink fed from the same transforms (:func:`bearing_time_record` runs it over a
    whole recording; the live chain, systems/live/, over the windows of a stream as they complete). A window's row
    and peaks do not depend on the windows batched with it (to rounding: the batched products)."""

    def __init__(self, fs_hz: float, array: LineArray, settings: BeamformerSettings, *, band: Band | None = None,
                 mvdr=None, narrowband: LofarSettings | None = None, spectra_sink: SpectraSink | None = None):
        s = self.settings = settings
        self.fs_hz, self.array, self.mvdr, self.sink = float(fs_hz), array, mvdr, spectra_sink
        self.band = front_end_band(array, s, fs_hz) if band is None else band
        self.n_samples = int(round(s.window_s * fs_hz))
        self.lofar = None if narrowband is None else LofarAccumulator(fs_hz, array, narrowband, self.n_samples)
        self.octave = alias_free_octave(array, s, fs_hz, self.band) if s.method == "cbf" else None
        # the pattern is the CBF's over one band (the octave's sum of two statistics has another shape)
        exact = s.peak_interpolation == "pattern" and s.method == "cbf" and self.octave is None
        self.pattern = beam_pattern(array, s, fs_hz, self.band) if exact else None

    def windows(self, blocks: Iterable[np.ndarray]):
        """(z (B,), peak angles (deg), peak heights) of each window of ``blocks`` (N, window_s fs), in order, read as
        they are asked for (CBF windows batched by ``BATCH_WINDOWS``)."""
        s = self.settings
        if s.method == "cbf":
            batches = _cbf_batches(blocks, self.fs_hz, self.array, s, self.band, self.octave, self.lofar, self.sink)
        else:
            batches = _other_batches(blocks, self.fs_hz, self.array, s, self.band, self.mvdr, self.lofar)
        for power in batches:
            z = normalise_across_bearing(power, s)
            yield from ((row, a, h) for row, (a, h) in zip(z, self._peaks(z), strict=True))

    def _peaks(self, z: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        picked = pick_beam_peaks_rows(z, self.settings.cone_deg, self.settings)
        if self.pattern is not None:  # the batch's windows refined at once (resolve_peaks_batch)
            angles = resolve_peaks_batch(z, [a for a, _ in picked], self.pattern)
            picked = [(a, h) for a, (_, h) in zip(angles, picked, strict=True)]
            if self.settings.hidden_peaks:
                picked = add_hidden_peaks(z, picked, self.pattern, self.settings)
        return picked


class RecordBuilder:
    """The bearing-time record's rows and peaks, window by window (``progress`` called with k after window k)."""

    def __init__(self, s: BeamformerSettings, progress: Callable[[int], None] | None):
        self.s, self.progress, self.k = s, progress, 0
        self.levels, self.ts, self.bs, self.amps = [], [], [], []

    def add(self, row: np.ndarray, angle: np.ndarray, height: np.ndarray) -> None:
        """Append the next window's row z (B,) and its peaks (angles in deg, heights)."""
        self.ts.append(np.full(len(angle), (self.k + 0.5) * self.s.window_s))
        self.bs.append(angle)
        self.amps.append(height)
        self.levels.append(row.astype(np.float32))
        if self.progress is not None:
            self.progress(self.k)
        self.k += 1

    def record(self, lofar: LofarGram | None) -> BearingTimeRecord:
        """The record of the windows added, with ``lofar`` as its gram."""
        s, cone = self.s, self.s.cone_deg
        level = np.stack(self.levels) if self.levels else np.zeros((0, cone.size), dtype=np.float32)
        cat = (lambda parts: np.concatenate(parts)) if self.ts else (lambda parts: np.zeros(0))
        return BearingTimeRecord(np.arange(self.k) * s.window_s + 0.5 * s.window_s, cone, level,
                                 PeakRecord(cat(self.ts), cat(self.bs), cat(self.amps)), lofar)


def bearing_time_record(blocks: Iterable[np.ndarray], fs_hz: float, array: LineArray, settings: BeamformerSettings,
                        *, band: Band | None = None, progress: Callable[[int], None] | None = None,
                        mvdr=None, narrowband: LofarSettings | None = None,
                        spectra_sink: SpectraSink | None = None) -> BearingTimeRecord:
    """Beamform, normalise and pick peaks in every window of ``blocks``; CBF windows in batches of
    ``BATCH_WINDOWS`` (one matrix product each); with ``narrowband``, the LOFAR gram per beam from the same
    windows' spectra (acoustics/lofar.py :class:`~sonartrack.acoustics.lofar.LofarAccumulator`: no pass of its own).

    Parameters
    ----------
    blocks : iterable of ndarray (N, window_s fs)
        The recording's windows in order (e.g. io/wav_blocks.py ``iter_wav_blocks``), N = ``array.elements``.
    fs_hz : float
        Sample rate (Hz).
    array : LineArray
        The line array.
    settings : BeamformerSettings
        The front end's settings.
    band : Band, optional
        The processing band, resolved and checked once by the caller (:func:`front_end_band`); None resolves
        and checks it here.
    progress : callable, optional
        Called with k after window k.
    mvdr : MvdrSettings, optional
        Segment and loading of the ``mvdr`` method (acoustics/mvdr.py; its defaults when None).
    narrowband : LofarSettings, optional
        The narrowband settings (band, beams, integration, normaliser; any subclass, such as the passive chain's):
        when given, the record's ``lofar`` is the gram :func:`~sonartrack.acoustics.lofar.lofar_gram` makes of
        the same windows (None when they hold no whole integration period).
    spectra_sink : SpectraSink, optional
        Given each batch's rectangular spectra over its ``bins`` (the CBF method only), for a later pass that needs
        them (systems/passive/tonal_pass.py ``SpectraSpill``): they cost no transform of their own.

    Returns
    -------
    BearingTimeRecord
        Window centres time_s = (k + 0.5) window_s (s), the beams' cone angles (deg), the normalised level z per
        window and beam, the peaks, and the LOFAR gram (or None).
    """
    fe = FrontEnd(fs_hz, array, settings, band=band, mvdr=mvdr, narrowband=narrowband, spectra_sink=spectra_sink)
    rows = RecordBuilder(settings, progress)
    for row in fe.windows(blocks):
        rows.add(*row)
    return rows.record(None if fe.lofar is None else fe.lofar.gram(settings.window_s))

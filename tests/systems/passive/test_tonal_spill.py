"""The tonal pass on the front end's own spectra (systems/passive/tonal_pass.py ``SpectraSpill``): the beams of a
window's rectangular spectra against the plain Hann-windowed, steered sum; the spectra the front end hands out
against scipy's transform of each window; and the tonal lines measured from the spill equal to those of a second
read, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.fft

from sonartrack.acoustics.beamforming import BeamformerSettings, bearing_time_record
from sonartrack.acoustics.line_array import LineArray
from sonartrack.acoustics.lofar import LofarSettings
from sonartrack.acoustics.tonal import TonalSettings, beam_spectra, beam_spectra_of_rect, tonal_rect_bins
from sonartrack.systems.passive.measurements import TrackMeasurements
from sonartrack.systems.passive.tonal_pass import RectWindow, SpectraSpill, measure_tonals

FS, N_EL, N = 2000.0, 16, 2000
ARRAY = LineArray(N_EL, 2.5, 1500.0)
TONAL = TonalSettings(band_hz=[50.0, 800.0])


def _blocks(dtype, n_windows: int, seed: int = 8) -> list[np.ndarray]:
    """Two plane-wave tones (150.3 Hz from 60 deg, 310.7 Hz from 120 deg) in white noise, one window a second."""
    rng = np.random.default_rng(seed)
    s_n = ((N_EL - 1) / 2.0 - np.arange(N_EL)) * ARRAY.spacing_m
    out = []
    for k in range(n_windows):
        t = k + np.arange(N) / FS
        x = rng.standard_normal((N_EL, N)) * 3.0
        for f0, cone in ((150.3, 60.0), (310.7, 120.0)):
            tau = -s_n * np.cos(np.deg2rad(cone)) / ARRAY.sound_speed_mps
            x += np.cos(2.0 * np.pi * f0 * (t[None, :] - tau[:, None]))
        out.append(x.astype(dtype))
    return out


def plain_beam_psd(x: np.ndarray, cone_deg, band_hz) -> tuple[np.ndarray, np.ndarray]:
    """2 |sum_n exp(+2 pi i f tau_n) Y_n(f) / N|^2 / (fs sum w^2), Y_n the rfft of the Hann-windowed samples (periodic
    Hann w), tau_n = -s_n cos(theta) / c, s_n = ((N - 1) / 2 - n) d: written out in double."""
    w = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(N) / N)
    y = np.fft.rfft(x.astype(float) * w, axis=1)
    f = np.fft.rfftfreq(N, 1 / FS)
    keep = (f >= band_hz[0]) & (f <= band_hz[1])
    s_n = ((N_EL - 1) / 2.0 - np.arange(N_EL)) * ARRAY.spacing_m
    out = []
    for cone in cone_deg:
        tau = -s_n * np.cos(np.deg2rad(cone)) / ARRAY.sound_speed_mps
        beam = (np.exp(2j * np.pi * f[keep][None, :] * tau[:, None]) * y[:, keep]).sum(axis=0) / N_EL
        out.append(2.0 * np.abs(beam) ** 2 / (FS * np.sum(w**2)))
    return f[keep], np.array(out)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_beams_of_rectangular_spectra_equal_the_beams_of_the_samples(dtype):
    """beam_spectra_of_rect on the rfft over tonal_rect_bins: the same bits as beam_spectra on the samples, and the
    plain windowed, steered sum to the precision's rounding."""
    x = _blocks(dtype, 1)[0]
    cones = [60.0, 95.0, 120.0]
    bins = tonal_rect_bins(N, FS, TONAL)
    assert bins == slice(49, 802)  # band 50..800 Hz in 1 Hz bins, one beyond each edge
    f, got = beam_spectra_of_rect(scipy.fft.rfft(x, axis=1, workers=1)[:, bins], N, FS, ARRAY, cones, TONAL)
    f2, want = beam_spectra(x, FS, ARRAY, cones, TONAL)
    np.testing.assert_array_equal(f, f2)
    np.testing.assert_array_equal(got, want)
    f3, plain = plain_beam_psd(x, cones, TONAL.band_hz)
    np.testing.assert_array_equal(f, f3)
    np.testing.assert_allclose(got, plain, rtol=0, atol=(2e-5 if dtype == np.float32 else 1e-12) * plain.max())
    assert plain[0, 100] > 100 * np.median(plain[0])  # the 150.3 Hz tone (bin 150, the band's 100th) on its beam


def test_rect_bins_none_where_no_bin_lies_beyond_the_band():
    """A band from 0 Hz, or up to fs / 2, leaves no rectangular bin beyond its edge: no spill."""
    assert tonal_rect_bins(N, FS, TonalSettings(band_hz=[0.0, 800.0])) is None
    assert tonal_rect_bins(N, FS, TonalSettings(band_hz=[50.0, 1000.0])) is None
    assert tonal_rect_bins(N, FS, TonalSettings(band_hz=[50.0, 998.0])) == slice(49, 1000)


def test_spill_gives_back_the_windows_in_order():
    """Batches of 3 and 2 windows written, read back one by one (bit for bit); usable only for as many windows as
    written, all exact."""
    rng = np.random.default_rng(1)
    spill = SpectraSpill(N, FS, TONAL)
    width = spill.bins.stop - spill.bins.start
    data = (rng.standard_normal((5, N_EL, width)) + 1j * rng.standard_normal((5, N_EL, width))).astype(np.complex64)
    spill.write(data[:3], True)
    spill.write(data[3:], True)
    got = [w.spectra.copy() for w in spill.windows()]
    assert len(got) == 5 and all(isinstance(w, RectWindow) and w.n_samples == N for w in spill.windows())
    for a, b in zip(got, data, strict=True):
        np.testing.assert_array_equal(a, b)
    assert spill.usable(5) and spill.usable(4) and not spill.usable(6) and not spill.usable(0)
    spill.write(data[:1], False)  # a window rounded to the front end's precision: a second read is needed
    assert not spill.usable(5)
    spill.close()


def test_front_end_hands_out_each_windows_spectra_and_keeps_its_record():
    """The sink's spectra are scipy's rfft of each float32 window over its bins, bit for bit (its bins widen the
    span transformed: the bearing-time record and the LOFAR gram stay the same to the bit); a float64 window,
    rounded to the single precision front end, marks the spill inexact."""
    blocks = _blocks(np.float32, 40)
    s = BeamformerSettings(band_hz=[60.0, 290.0], beams=31)
    spill = SpectraSpill(N, FS, TONAL)
    nb = LofarSettings(band_hz=[80.0, 280.0], beams=21, integration=8)
    with_sink = bearing_time_record(iter(blocks), FS, ARRAY, s, spectra_sink=spill, narrowband=nb)
    without = bearing_time_record(iter(blocks), FS, ARRAY, s, narrowband=nb)
    np.testing.assert_array_equal(with_sink.level, without.level)
    np.testing.assert_array_equal(with_sink.lofar.power, without.lofar.power)  # the gram from its own bins
    np.testing.assert_array_equal(with_sink.peaks.bearing_deg, without.peaks.bearing_deg)
    got = [w.spectra.copy() for w in spill.windows()]
    assert len(got) == 40 and spill.usable(40)
    for spec, x in zip(got, blocks, strict=True):
        np.testing.assert_array_equal(spec, scipy.fft.rfft(x, axis=-1)[:, spill.bins])
    mixed = SpectraSpill(N, FS, TONAL)
    bearing_time_record(iter(blocks[:5] + [blocks[5].astype(np.float64)]), FS, ARRAY, s, spectra_sink=mixed)
    assert mixed.count == 6 and not mixed.usable(6)


def _track(track_id: int, t_s, cone_deg) -> TrackMeasurements:
    t = np.asarray(t_s, dtype=float)
    c = np.broadcast_to(np.asarray(cone_deg, dtype=float), t.shape).copy()
    return TrackMeasurements(track_id, t, c, np.ones(t.size), t, c)


def test_tonal_lines_from_the_spill_equal_those_of_a_second_read():
    """Two tracks on the two tones: the lines, per-window frequencies and sigmas from the front end's spill equal
    those of the windows read again, bit for bit."""
    blocks = _blocks(np.float32, 30)
    spill = SpectraSpill(N, FS, TONAL)
    bearing_time_record(iter(blocks), FS, ARRAY, BeamformerSettings(band_hz=[60.0, 290.0], beams=31),
                        spectra_sink=spill)
    tracks = [_track(1, np.arange(30) + 0.5, 60.0), _track(2, np.arange(5, 30) + 0.5, 120.0)]
    again = measure_tonals(iter(blocks), FS, ARRAY, tracks, TONAL, 30)
    spilled = measure_tonals(spill.windows(), FS, ARRAY, tracks, TONAL, 30)
    for one, two, f0 in zip(spilled, again, (150.3, 310.7), strict=True):
        assert one is not None and abs(one.line_hz - f0) < 0.1
        assert (one.line_hz, one.line_snr_db, one.sigma_hz) == (two.line_hz, two.line_snr_db, two.sigma_hz)
        np.testing.assert_array_equal(one.frequency_hz, two.frequency_hz)
        np.testing.assert_array_equal(one.time_s, two.time_s)


def test_spill_past_its_limit_or_on_a_full_disk_stands_down(monkeypatch):
    """Past SPILL_LIMIT_BYTES, or when the disk refuses a write, the spill is not usable (the tonal pass reads the
    recording again) and keeps no bytes; nothing is raised."""
    import sonartrack.systems.passive.tonal_pass as tp

    rng = np.random.default_rng(2)
    spill = SpectraSpill(N, FS, TONAL)
    width = spill.bins.stop - spill.bins.start
    data = (rng.standard_normal((4, N_EL, width)) + 1j * rng.standard_normal((4, N_EL, width))).astype(np.complex64)
    monkeypatch.setattr(tp, "SPILL_LIMIT_BYTES", data[:3].nbytes)
    spill.write(data[:2], True)
    assert spill.usable(2)
    spill.write(data[2:], True)  # 4 windows would pass the limit of 3
    assert not spill.usable(2) and spill._file.seek(0, 2) == 0
    spill.close()

    class FullDisk:
        def tell(self):
            return 0

        def write(self, _):
            raise OSError(28, "No space left on device")

        def close(self):
            pass

    monkeypatch.setattr(tp, "SPILL_LIMIT_BYTES", 2 * 1024**3)
    spill = SpectraSpill(N, FS, TONAL)
    spill._file = FullDisk()
    spill.write(data[:1], True)
    assert not spill.usable(1)
    spill.close()

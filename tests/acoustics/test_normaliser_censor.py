"""The front end's normaliser with censoring (acoustics/beamforming.py :func:`normalise_across_bearing`,
``censor_passes``): two loud ships near endfire, whose wide lobes cover much of the cone-angle grid, no longer set
the background that weaker ships are measured against; noise alone is normalised as before."""

import sys
from pathlib import Path

import numpy as np
import pytest

from sonartrack.acoustics.beamforming import BeamformerSettings, cbf_powers, normalise_across_bearing, pick_beam_peaks
from sonartrack.acoustics.line_array import LineArray

sys.path.insert(0, str(Path(__file__).parent))
from test_peak_resolve import noise_from  # noqa: E402  (plane waves synthesised here, not by the simulator)

C = 1500.0
N, D, FS, M = 24, 1.25, 6000.0, 6000
ARRAY = LineArray(N, D, C)


def _element_noise(rng, power=1.0):
    """Independent white noise of the given power on each element, 50-2000 Hz."""
    f = np.fft.rfftfreq(M, 1 / FS)
    spec = (rng.standard_normal((N, f.size)) + 1j * rng.standard_normal((N, f.size))) * ((f >= 50) & (f < 2000))
    w = np.fft.irfft(spec, M, axis=1)
    return w * np.sqrt(power) / w.std()


def _z(x, passes):
    s = BeamformerSettings(censor_passes=passes)
    band = ARRAY.band(FS, None, False, s.auto_band_hz)
    return normalise_across_bearing(cbf_powers(x[None], FS, ARRAY, s, band), s)[0], s


@pytest.mark.parametrize("seed", range(4))
def test_weak_ships_beside_two_loud_ones_near_endfire_are_detected(seed):
    """24 x 1.25 m at 6 kHz (an array and scene the chain was not tuned on): ships at 20 and 25 deg with per-element
    SNR +0.8 and -2.2 dB, two at 49 and 62.5 deg at -5 and -4.2 dB, one at 135 deg at -7.2 dB (a scene seen by the
    chain on a recording made for it: the pair lost for 300 s). The lobes lift most of the grid, so the plain median /
    MAD puts the weak pair below the threshold; censored, both are peaks at their cone angles."""
    rng = np.random.default_rng(seed)
    ships = ((20.0, 1.2), (25.0, 0.6), (49.0, 0.32), (62.5, 0.38), (135.0, 0.19))
    x = sum(noise_from(rng, cone, N, D, FS, M, (50.0, 2000.0), p) for cone, p in ships) + _element_noise(rng)
    plain, s = _z(x, 0)
    censored, _ = _z(x, 5)
    assert plain[[49, 62]].max() < s.threshold
    angle, amplitude = pick_beam_peaks(censored, s.cone_deg, s)
    for cone in (49.0, 62.5):
        near = np.abs(angle - cone) < 1.5
        assert near.any() and amplitude[near].max() >= s.threshold


def test_noise_alone_is_normalised_as_before():
    """Element noise only (50 windows): where no beam reaches the threshold the censored z is the plain z exactly;
    the peaks at or above it are the same in number within one, and no z moves by more than 0.3."""
    rng = np.random.default_rng(11)
    count = {0: 0, 5: 0}
    for _ in range(50):
        x = _element_noise(rng)
        plain, s = _z(x, 0)
        censored, _ = _z(x, 5)
        if plain.max() < s.threshold:
            np.testing.assert_array_equal(censored, plain)
        assert np.abs(censored - plain).max() < 0.3
        for passes, z in ((0, plain), (5, censored)):
            count[passes] += len(pick_beam_peaks(z, s.cone_deg, s)[0])
    assert abs(count[5] - count[0]) <= 1


def test_a_row_mostly_above_threshold_keeps_its_plain_statistic():
    """A window whose beams are mostly raised (a short array, two ships covering most of the grid): fewer than a
    quarter would stay as background, so the row is not censored."""
    s = BeamformerSettings(censor_passes=5)
    p = np.ones(181)
    p[:150] = 50.0 + np.arange(150)  # 150 of 181 beams high
    np.testing.assert_array_equal(normalise_across_bearing(p, s), normalise_across_bearing(p, BeamformerSettings()))

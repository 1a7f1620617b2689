"""A uniform line array as one object: its element count, spacing and the sound speed around it, and what follows
from them (aliasing frequency, beamwidth, the processing band).

Element n (0 = front) sits s_n = ((N - 1)/2 - n) d ahead of the array centre (as sim/array_signals.py). A plane
wave of frequency f from cone angle theta gives the element-to-element phase step 2 pi f d cos(theta) / c; it is
unambiguous over 0..180 deg while d <= lambda / 2, i.e. below the aliasing frequency

    f_a = c / (2 d)                                       (grating lobes above it; Van Trees, Optimum Array
                                                           Processing, sec. 2.4)

and the conventional beam's half-power width at broadside is about 0.89 lambda / (N d) rad (Van Trees, sec.
2.4.1, uniform weighting). The band a front end processes is resolved once, here (:meth:`LineArray.band`): the
band given, or an automatic one (the band the ships radiate capped at fs / 2, or the octave below the aliasing
frequency), checked against the array and the sample rate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require

#: the automatic band (the octave below aliasing) must reach at least this: a lower one means a spacing in the
#: wrong unit (centimetres as metres), not an array
MIN_AUTO_BAND_HZ = 10.0
#: uniform-weighting half-power beamwidth at broadside, in units of lambda / (N d) (Van Trees, sec. 2.4.1)
BEAMWIDTH_FACTOR = 0.89


@dataclass(frozen=True, slots=True)
class Band:
    """A processing band [low_hz, high_hz) (Hz)."""

    low_hz: float
    high_hz: float

    @property
    def centre_hz(self) -> float:
        """The band's centre frequency (low + high) / 2 (Hz)."""
        return 0.5 * (self.low_hz + self.high_hz)

    def as_tuple(self) -> tuple[float, float]:
        """(low, high) in Hz.

        Returns
        -------
        tuple of float
            (low_hz, high_hz).
        """
        return self.low_hz, self.high_hz


@dataclass(frozen=True, slots=True)
class LineArray:
    """A uniform line array of ``elements`` hydrophones ``spacing_m`` apart in water of sound speed
    ``sound_speed_mps`` (module doc). Refuses a spacing or sound speed that is not positive and fewer than two
    elements (:class:`~sonartrack.core.errors.InputError`)."""

    elements: int
    spacing_m: float
    sound_speed_mps: float = 1500.0

    def __post_init__(self):
        require(self.spacing_m > 0, f"element spacing must be positive, got {self.spacing_m:g} m (--spacing)")
        require(self.sound_speed_mps > 0, f"sound speed must be positive, got {self.sound_speed_mps:g} m/s")
        require(self.elements >= 2, f"a line array needs at least 2 elements, got {self.elements}: give a "
                                    "line-array recording (or use `sonartrack bearings` for 2 channels)")

    def aliasing_hz(self, fs_hz: float | None = None) -> float:
        """The aliasing frequency f_a = c / (2 d), capped at the Nyquist frequency.

        Parameters
        ----------
        fs_hz : float, optional
            Sample rate (Hz); when given, f_a is at most fs / 2.

        Returns
        -------
        float
            min(c / (2 d), fs / 2) in Hz.
        """
        f_alias = self.sound_speed_mps / (2.0 * self.spacing_m)
        return f_alias if fs_hz is None else min(f_alias, fs_hz / 2.0)

    def beamwidth_deg(self, f_hz: float) -> float:
        """Broadside half-power beamwidth 0.89 lambda / (N d) of a conventional beam (module doc).

        Parameters
        ----------
        f_hz : float
            Frequency (Hz); lambda = c / f.

        Returns
        -------
        float
            The beamwidth in degrees.
        """
        wavelength_m = self.sound_speed_mps / f_hz
        return float(np.rad2deg(BEAMWIDTH_FACTOR * wavelength_m / (self.elements * self.spacing_m)))

    def band(self, fs_hz: float | None, band_hz=None, allow_grating_lobes: bool = False, auto_hz=None) -> Band:
        """The processing band, resolved and checked once: ``band_hz`` as given; else, with ``auto_hz``, that band
        (the band the ships radiate) from at least c / (N d) (an aperture of one wavelength) up to at most fs / 2,
        grating lobes accepted above f_a (over a band of several
        octaves they smear; measured in acoustics/beamforming.py :class:`BeamformerSettings`); else the octave
        below the aliasing frequency, [f_a / 2, f_a] with f_a = :meth:`aliasing_hz`.

        Parameters
        ----------
        fs_hz : float or None
            Sample rate (Hz); the band must then lie below fs / 2. None: not checked against a sample rate.
        band_hz : sequence of 2 floats, optional
            [low, high) in Hz; None for the automatic band.
        allow_grating_lobes : bool
            Accept a band reaching above c / (2 d) instead of refusing it (``band_hz`` given).
        auto_hz : sequence of 2 floats, optional
            [low, high) in Hz of the automatic band when ``band_hz`` is None; None: the octave below aliasing.

        Returns
        -------
        Band
            The band. Raises :class:`~sonartrack.core.errors.InputError` with a one-line fix when the band is
            empty, above fs / 2, aliased (and grating lobes are not allowed), or when the automatic band lies
            below 10 Hz (a spacing in the wrong unit).
        """
        if band_hz is not None:
            lo, hi = float(band_hz[0]), float(band_hz[1])
        elif auto_hz is not None:
            # below c / (N d) the aperture is shorter than a wavelength: beams wider than ~50 deg only raise the
            # background (measured on an 8 x 0.5 m array: BeamformerSettings)
            lo = max(float(auto_hz[0]), self.sound_speed_mps / (self.elements * self.spacing_m))
            hi = float(auto_hz[1]) if fs_hz is None else min(float(auto_hz[1]), fs_hz / 2)
            allow_grating_lobes = True
            aperture_m = self.elements * self.spacing_m
            require(lo < hi, f"the array's aperture {aperture_m:g} m is shorter than a wavelength below {hi:g} Hz "
                             f"(no automatic band in {list(auto_hz)} Hz): is the spacing in metres (--spacing)? "
                             "Or give band_hz")
        else:
            f_a = self.aliasing_hz(fs_hz)
            lo, hi = 0.5 * f_a, f_a
        require(0 < lo < hi, f"band_hz {[lo, hi]} must satisfy 0 < low < high: fix the beamformer's band_hz")
        if fs_hz is not None:
            require(hi <= fs_hz / 2, f"band_hz {[lo, hi]} reaches above half the sample rate ({fs_hz / 2:g} Hz): "
                                     "lower the band's upper edge")
        f_alias = self.aliasing_hz()
        d = self.spacing_m
        require(band_hz is not None or f_alias >= MIN_AUTO_BAND_HZ,
                f"element spacing {d:g} m leaves no band free of grating lobes above {f_alias:.2g} Hz: is the "
                "spacing in metres (--spacing)? Or give band_hz and allow_grating_lobes")
        require(allow_grating_lobes or hi <= f_alias * (1 + 1e-9),
                f"element spacing {d:g} m aliases above {f_alias:.1f} Hz (grating lobes: d > c / (2 f)): set "
                f"band_hz upper edge <= {f_alias:.0f} Hz or check --spacing (or accept grating lobes: "
                "--allow-grating-lobes, allow_grating_lobes = true)")
        return Band(lo, hi)

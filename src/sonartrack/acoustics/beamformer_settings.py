"""The line-array front end's settings and its output, the bearing-time record (acoustics/beamforming.py)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from sonartrack.acoustics.lofar import LofarGram
from sonartrack.acoustics.xcorr_bearing import PeakRecord
from sonartrack.core.settings import Settings, setting


class BeamformerSettings(Settings):
    """Front end of ``sonartrack passive`` for an N-element line array (module doc).

    Default ``cbf`` over the automatic band: the band the ships radiate (``auto_band_hz``, 50-1000 Hz) from at least
    c / (N d) up to at most fs / 2, every bin steered at its own frequency and whitened, so the narrow beams of the
    upper bins set the picture and the grating lobes above f_a = c / (2 d), which move with frequency, smear out.
    Measured (chain of ``sonartrack passive``, one target per ship wanted; per ship: fraction of its detectable
    windows held, targets, side) on the default scene of ``sonartrack simulate`` (16 x 2.5 m, 4 kHz, 1200 s) and
    two scenes not tuned to (B: 32 x 1.25 m, 8 kHz, ships radiating 50-2000 Hz, turn +60 deg; C: 24 x 5 m, 6 kHz,
    turn -60 deg; 900 s each):

    ===================  ========================================  ==========================================
    scene                old default: octave [f_a/2, f_a]          automatic band (this default)
    ===================  ========================================  ==========================================
    default              5 targets for 3 ships (trawler, tanker    3 targets for 3 ships, sides right,
                         in 2 fragments, 2 sides unresolved)       held 0.99/0.99/1.00
    B (f_a 600 Hz)       4 targets for 3 ships (yacht, -10 dB,     2 targets, ferry/coaster held 0.99/1.00;
                         in 2 fragments, side wrong/unresolved)    the yacht missed (detectable 16 s)
    C (f_a 150 Hz)       3 for 3, sides right                      3 for 3, sides right, ranges within 1 %
    ===================  ========================================  ==========================================

    Per-window detection (first 300 s; fraction of windows with a peak within 2 deg of the true cone angle),
    default scene merchant/trawler/tanker: whole band 1.00/1.00/1.00; per-octave z (octaves from 50 Hz)
    combined by their mean 1.00/0.99/0.91, sqrt(bins)-weighted mean 1.00/1.00/0.85, max 0.97/0.76/0.24; the
    alias-free octave alone 0.96/0.77/0.96. Scene B's yacht: whole band 0.00, octave alone 0.54, the whole band's
    z plus the octave's (``add_alias_free_octave``) 0.53, which in the chain holds it 0.63 (one fragment, side
    unresolved) but on the default scene breaks the trawler's track at the crossing (its wider beams pull the
    crossing ships together): off by default. Known limit: an array of a few wavelengths (8 x 0.5 m) with two ships
    whose beams cover most of 0..180 deg gives no z above 4 (the median and MAD across bearing are the ships');
    one loud ship is found (tests).

    Noise only (the default array, ``ships = []``, 1800 s; the automatic band): 0.043 peaks a window at z >= 4
    (0.32 at 3, 0.0044 at 5); their excess z - threshold exponential (median and 90 % quantile within 7 % of the
    exponential's) with rate alpha = 1.92 per unit z at threshold 3 (95 % interval 1.77..2.08), 2.16 at 4
    (1.68..2.63); 32 x 1.25 m at 8 kHz (900 s): 0.038 a window at z >= 4, alpha 2.06 at 3 (1.82..2.30).

    Split array (P0) on the default scene's 150-300 Hz: detection 0.08 against CBF's 0.70 (its unsteered
    half-array sums hear only near broadside). The submarine (-20 dB per element) stays below any usable
    threshold in 1 s windows."""

    method: Literal["cbf", "split-array", "mvdr"] = setting("cbf", "beamformer: cbf = conventional frequency-domain "
                                                            "beamforming over the band; split-array = P0's cross-"
                                                            "correlation of the two half-array sums; mvdr = Capon "
                                                            "beams with diagonal loading (acoustics/mvdr.py)", unit="")
    band_hz: list[float] | None = setting(None, "processing band [low, high) (not set: auto_band_hz capped at fs / 2, "
                                                "grating lobes above c / (2 d) accepted)",
                                          unit="Hz", min_length=2, max_length=2)
    auto_band_hz: list[float] = setting(default_factory=lambda: [50.0, 1000.0],
                                        doc="the automatic processing band when band_hz is not set: the band where "
                                            "ships' broadband radiated noise stands above the sea noise, capped at "
                                            "fs / 2 (measured better than the octave below aliasing and than "
                                            "combining per-octave statistics: class doc)", unit="Hz",
                                        min_length=2, max_length=2)
    add_alias_free_octave: bool = setting(False, "with the automatic band: add the normalised level of the octave "
                                                 "below aliasing [f_a / 2, f_a] to the whole band's, and normalise "
                                                 "again (finds a weak ship among a loud one's grating lobes; its "
                                                 "wider beams bias crossing ships: class doc)", unit="")
    allow_grating_lobes: bool = setting(False, "accept a band_hz above the aliasing frequency c / (2 d) (grating "
                                               "lobes, smeared over a broad band) instead of refusing it", unit="")
    window_s: float = setting(1.0, "observation window of one line of the bearing-time record", unit="s", gt=0)
    beams: int = setting(181, "cone-angle grid: this many beams uniform in 0..180 deg (181 = 1 deg steps)",
                         unit="1", ge=3)
    peak_interpolation: Literal["pattern", "parabola"] = setting(
        "pattern", "sub-beam peak position: pattern = the array's own broadband beam pattern fitted to each peak with "
        "the other peaks' lobes taken out (:func:`resolve_peaks`; CBF over one band only, else parabola); parabola = a "
        "parabola through the three beams around the maximum (biased by a louder ship's lobes: the peak follows "
        "their slope)", unit="")
    hidden_peaks: bool = setting(True, "with the pattern interpolation: also report a ship hidden on a louder one's "
                                       "lobe, a maximum of z minus the peaks' fitted patterns at or above the "
                                       "threshold and more than a half-power half-width from every peak "
                                       "(:func:`add_hidden_peaks`; keeps a weak ship through a crossing)", unit="")
    threshold: float = setting(4.0, "detection threshold on the normalised statistic z = (P - median) / "
                                    "(1.4826 MAD) across bearing", unit="1")
    max_peaks: int = setting(8, "largest number of peaks kept per window (the highest z)", unit="1", ge=1)
    whiten: bool = setting(True, "divide each frequency bin by its mean element power before beamforming, so that "
                                 "every bin weighs the same (a loud tonal line does not dominate the band)", unit="")
    spread_floor: float = setting(1e-3, "normaliser: the spread is at least this fraction of the background "
                                        "(guards against a zero or constant recording)", unit="1", gt=0)
    censor_passes: int = setting(
        0, "normaliser: the median and MAD are measured again without the beams at or above the threshold, up to "
        "this many times (normalise_across_bearing), for loud ships near endfire whose wide lobes cover much of the "
        "grid and set the background. At 5, on 24 x 1.25 m at 6 kHz a crossing pair at -4 to -7 dB is held 8-740 s "
        "and 90-900 s (both ranges within 0.3 km) instead of 536-726 s, and on 40 x 0.9 m at 8 kHz a -7 dB tanker "
        "8-894 s instead of 178-330 s; but on the passive-chain study crossings kept fell 0.81 -> 0.75 (jumped 1 -> "
        "4) and one determined ML lay 333 sds off (a track that took another ship after a crossing): off by default; "
        "0: once, over every beam", unit="1", ge=0)
    fft_precision: Literal["single", "double"] = setting(
        "single", "precision of the channels' FFT and of the lags across elements (the products are double): single "
        "halves their time with errors ~5e-8 of a beam's power (~1e-5 in z), far below the noise the normaliser "
        "measures; double for reference checks", unit="")

    @property
    def cone_deg(self) -> np.ndarray:
        """The beams' cone angles (deg), uniform 0..180."""
        return np.linspace(0.0, 180.0, self.beams)


@dataclass(frozen=True)
class BearingTimeRecord:
    """The bearing-time record: window centres (T,), beam cone angles (B,), normalised level z (T, B) and
    the peaks (time, cone angle deg as ``bearing_deg``, amplitude = z at the peak); ``lofar``: the narrowband
    LOFAR gram per beam made in the same pass (:func:`bearing_time_record` with ``narrowband``), or None."""

    time_s: np.ndarray
    cone_deg: np.ndarray
    level: np.ndarray
    peaks: PeakRecord
    lofar: LofarGram | None = None

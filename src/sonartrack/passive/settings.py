"""Settings of the passive chain (``sonartrack passive``): the array, and one group per stage.

Each stage's settings are declared once, in its own module, and nested here as a TOML table:
``[front_end]`` (acoustics/beamforming.py), ``[tracker]`` (tracking/settings.py, with defaults for the
front end's normalised amplitudes instead of paper P0's correlation amplitudes), ``[tonal]``
(acoustics/tonal.py), ``[imm]`` and ``[sequential]`` (tma/settings.py).
"""

from __future__ import annotations

import math

import numpy as np

from sonartrack.acoustics.beamforming import BeamformerSettings
from sonartrack.acoustics.tonal import TonalSettings
from sonartrack.core.settings import Settings, setting
from sonartrack.tma.settings import ImmSettings, SequentialSettings
from sonartrack.tracking.settings import BearingTrackerSettings


def passive_tracker_settings() -> BearingTrackerSettings:
    """P0's JPDA_A tracker on the front end's statistic z (background spreads above the background level)
    instead of P0's correlation amplitudes (0..30000). DEVIATION from P0's values, measured on noise-only
    simulated recordings (front end defaults): see the field docs of BearingTrackerSettings for meanings."""
    return BearingTrackerSettings(
        q=0.001, gate_deg=6.0, p_detect=0.9, clutter_density_per_deg=1e-3, false_amplitude_rate=1.4,
        amplitude_threshold=4.0, init_amplitude=6.0, init_sigma_p_deg=0.5, init_amplitude_sd=5.0,
        confirm_m=8, confirm_n=10, delete_after=20)


class PassiveSettings(Settings):
    """The passive chain: recording + navigation -> bearing tracks -> target solutions."""

    spacing_m: float | None = setting(None, "element spacing d of the uniform line array (required)", unit="m", gt=0)
    elements: int | None = setting(None, "number of hydrophones; the WAV must have this many channels (not set: "
                                         "the WAV's channel count)", unit="1", ge=2)
    min_track_s: float = setting(120.0, "a confirmed bearing track shorter than this is reported but gets no TMA",
                                 unit="s", gt=0)
    min_side_log_lr: float = setting(math.log(100.0), "the array side is decided when the log likelihood ratio of "
                                     "the two mirror hypotheses exceeds this (ln 100: 100 to 1)", unit="1", gt=0)
    max_peak_offset_deg: float = setting(2.0, "a peak is a track's measurement when within this of the track's "
                                         "bearing at that time", unit="deg", gt=0)
    min_separation_deg: float | None = setting(None, "scans where two tracks' peaks are closer than this are left "
                                               "out of their TMA (not set: one broadside beamwidth 0.89 c / (f N d) "
                                               "at the band's centre frequency)", unit="deg", gt=0)
    sigma_freq_floor_hz: float = setting(0.02, "smallest frequency noise the TMA assumes", unit="Hz", gt=0)
    max_sigma_freq_hz: float = setting(0.4, "a tonal whose measured frequency noise exceeds this is not used by the "
                                       "TMA (its per-window values are mostly noise peaks near the line)", unit="Hz",
                                       gt=0)
    min_line_snr_db: float = setting(4.0, "a tonal weaker than this over its beam's background is not used by the "
                                     "TMA", unit="dB")
    front_end: BeamformerSettings = setting(default_factory=BeamformerSettings, doc="beamforming and peak picking")
    tracker: BearingTrackerSettings = setting(default_factory=passive_tracker_settings,
                                              doc="JPDA_A bearing tracker on the peaks")
    tonal: TonalSettings = setting(default_factory=TonalSettings, doc="tonal line measurement on each track's beam")
    imm: ImmSettings = setting(default_factory=ImmSettings, doc="IMM-MGEKF modes of the sequential TMA")
    sequential: SequentialSettings = setting(default_factory=SequentialSettings,
                                             doc="initialisation of the sequential TMA")

    def min_separation_for(self, fs_hz: float) -> float:
        """``min_separation_deg``, or one broadside beamwidth of the array at the band's centre (deg)."""
        if self.min_separation_deg is not None:
            return self.min_separation_deg
        lo, hi = self.front_end.band_for(self.spacing_m, fs_hz)
        wavelength_m = self.front_end.sound_speed_mps / (0.5 * (lo + hi))
        return float(np.rad2deg(0.89 * wavelength_m / ((self.elements or 2) * self.spacing_m)))

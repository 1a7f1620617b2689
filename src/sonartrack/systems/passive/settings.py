"""Settings of the passive system (``sonartrack passive``): one tree, each shared quantity declared once.

The root declares what several stages share: the array (``elements``, ``spacing_m``), the medium
(``sound_speed_mps``), the time base (``window_s``: one line of the bearing-time record, one tonal spectrum,
one tracker scan) and the detection statistic's threshold (``threshold`` on z: the front end's peaks and the
tracker's amplitude threshold tau), plus the chain's own choices. Each stage's group keeps only its own
fields (``core.settings.derived_settings``): ``[front_end]`` (acoustics/beamforming.py), ``[tracker]``
(tracking/settings.py, with the chain's defaults for the z statistic declared here, with docs for those
values), ``[tonal]`` (acoustics/tonal.py), ``[imm]`` and ``[sequential]`` (tma/settings.py), ``[narrowband]``
(acoustics/lofar.py, tracking/line_tracks.py, systems/passive/narrowband.py; on by default); the quiet-target
options, off by default: ``[mvdr]`` (acoustics/mvdr.py, with ``[front_end] method = "mvdr"``) and ``[btr_mftd]``
(detection/btr_mftd.py).

:meth:`PassiveSettings.stages` builds the stages' library settings from the tree, once per run, with the
array as one object (:class:`~sonartrack.acoustics.line_array.LineArray`) and its processing band resolved
and checked once (:class:`PassiveStages`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pydantic import model_validator

from sonartrack.acoustics.beamforming import BeamformerSettings
from sonartrack.acoustics.line_array import Band, LineArray
from sonartrack.acoustics.lofar import LofarSettings
from sonartrack.acoustics.mvdr import MvdrSettings
from sonartrack.acoustics.tonal import TonalSettings
from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, derived_settings, setting
from sonartrack.detection.btr_mftd import BtrMftdSettings
from sonartrack.tma.settings import ImmSettings, SequentialSettings, VerdictSettings
from sonartrack.tma.zig import DEFAULT_FALSE_ALARM_PER_HOUR
from sonartrack.tracking.line_tracks import LineTrackerSettings
from sonartrack.tracking.settings import BearingTrackerSettings

FrontEndSettings = derived_settings(
    BeamformerSettings, "FrontEndSettings", "The passive chain's beamforming and peak picking (acoustics/"
    "beamforming.py); window and threshold come from the root.", drop=("window_s", "threshold"))

PassiveTonalSettings = derived_settings(
    TonalSettings, "PassiveTonalSettings", "Tonal-line measurement on each track's beam (acoustics/tonal.py); "
    "its window is the root's, so the tonal times are the bearing-time record's.", drop=("window_s",))

PassiveSequentialSettings = derived_settings(
    SequentialSettings, "PassiveSequentialSettings", "Initialisation of the sequential TMA (tma/settings.py); the "
    "Doppler model's sound speed is the root's.", drop=("sound_speed_mps",))

PassiveLineTrackerSettings = derived_settings(
    LineTrackerSettings, "PassiveLineTrackerSettings", "Tracking of the narrowband lines in frequency and bearing "
    "(tracking/line_tracks.py), with the chain's process noise of the cone angle.",
    defaults={"q_bearing": (3e-3, "white-noise intensity of the cone-angle rate: the line must follow the ownship's "
                                  "turn, through which a target's cone angle changes by up to 0.5 deg/s (the "
                                  "library's 1e-5 loses the line there: a 360 s default scene with the turn at "
                                  "120 s gave the submarine no side; 3e-3 holds it 40..344 s, side port)")})


class LineMftdSettings(BtrMftdSettings):
    """Paper P1's MFTD per narrowband line (systems/passive/line_mftd.py): over each bin's bearing-time record
    (periods x beams) of the bins near a single-period line detection, the LOFAR statistic mapped to N(0, 1) through
    its F law. Off by default (``[narrowband] mftd``): on synthetic F cells it gains ~4 dB over the single period at
    equal false-alarm rate (study quiet-target, row cells-line-mftd-gain), and an hour of noise (16 x 2.5 m, 4 kHz)
    gave no line track and no target with it on; but it costs too much for what it adds on the default scene (1200 s,
    16 channels at 4 kHz: processor time 10.9 s against 7.9 s without, the same four targets, the submarine's line
    held to 1192 s instead of 1144 s)."""

    pfa: float = setting(1e-4, "false detections per beam, bin and period its threshold is calibrated for (the line "
                               "threshold's)", unit="1", gt=0, lt=0.1)
    max_rate_deg_s: float = setting(0.25, "largest cone-angle rate of a line (a 16 s period: 4 deg a period)",
                                    unit="deg/s", gt=0, le=30)
    tile_beams: int = setting(16, "beams a tile owns (one P1 test per tile and period: two lines on one bin 48 deg "
                                  "apart are both found)", unit="1", ge=1)
    band_bins: int = setting(1, "bins searched either side of each single-period line detection's bin", unit="1",
                             ge=0, le=16)
    min_detections: int = setting(3, "a bin is searched when at least this many single-period detections of the "
                                     "recording lie within band_bins of it, and more than noise alone puts there "
                                     "(systems/passive/line_mftd.py, BIN_ALPHA)", unit="1", ge=1)
    near_beams: int = setting(2, "an MFTD detection within this many beams and one bin of a single-period detection "
                                 "of its period is that detection", unit="1", ge=0, le=16)


class NarrowbandSettings(LofarSettings):
    """Narrowband (LOFAR) pass per beam (acoustics/lofar.py), its line tracks (tracking/line_tracks.py) and what the
    chain makes of them (systems/passive/narrowband.py): a track's tonal where its own beam shows none, and targets
    of their own for the lines no bearing track explains. On by default: it is how a quiet ship with a tonal is
    found at all (the default scene's submarine, 8 dB below the broadband threshold, is reported by its 200 Hz
    line), and it costs about a tenth of the chain's time (processor time of ``sonartrack passive``: the default
    scene for an hour, 16 channels at 4 kHz, 18.4 s against 16.4 s without, two runs each; 10 minutes of 32 channels
    at 8 kHz, 8.3 s against 7.6 s). An hour of noise alone gave one 32 s line track and no narrowband target."""

    enabled: bool = setting(True, "run the narrowband pass (lines, tonals, narrowband targets)", unit="")
    match_beamwidths: float = setting(0.5, "a line source follows a bearing track when their cone angles differ by "
                                           "at most this many broadside beamwidths at the line's frequency (RMS over "
                                           "the common periods; 0.5: 4.8 deg at 200 Hz, 10.7 deg at 90 Hz on 16 x "
                                           "2.5 m, where a low line's wide beam errs by several degrees)", unit="1",
                                      gt=0, le=5)
    same_line_hz: float = setting(1.0, "lines within this of each other are one line: an unexplained source on the "
                                       "frequency of a tracked ship's line is that line leaking into other beams, "
                                       "and fragments of one line are joined (one bin of a 1 s window)", unit="Hz",
                                  gt=0, le=100)
    min_target_snr_db: float = setting(0.0, "a narrowband target's bearings and frequencies are its line's "
                                            "detections at least this far over the background; the cone angles "
                                            "off the target's constant-velocity fit are left out as outliers "
                                            "instead (default scene, 1200 s, seeds 1-6: the submarine's detections "
                                            "at 1-3 dB err by a median 0.9 deg, as those at 3-4 dB, with 5 % more "
                                            "than 5 deg off; 3 dB kept a third of them, and the record then ended "
                                            "before the turn)", unit="dB", ge=-10, le=60)
    max_join_gap_s: float = setting(300.0, "largest gap between two fragments of one line joined into one target "
                                           "(a line breaks where the array turns: the cone angle moves by up to "
                                           "8 deg in a 16 s period and the line fades for 100-200 s)", unit="s",
                                    gt=0, le=3600)
    line_tracker: PassiveLineTrackerSettings = setting(default_factory=PassiveLineTrackerSettings,
                                                       doc="tracking of the lines in frequency and bearing")
    mftd: bool = setting(False, "run P1's MFTD over each line's bearing-time record (systems/passive/line_mftd.py) "
                                "and add its detections to the line detections", unit="")
    line_mftd: LineMftdSettings = setting(default_factory=LineMftdSettings,
                                          doc="the MFTD per narrowband line (with ``mftd = true``)")


class PassiveBtrMftdSettings(BtrMftdSettings):
    """Paper P1's MFTD on the bearing-time record (detection/btr_mftd.py); off by default. Its detections that no
    single-window peak lies near (half a gate) enter the tracker as peaks of z = the tracker's ``init_amplitude``
    (the MFTD decision stands in for the amplitude test). The chain's defaults: beams pooled by 3 (the beams are
    ~6-9 deg wide on the 1 deg grid), 4 pooled beams owned per tile (one detection per tile: loud neighbours
    would hide each other in wide tiles). Default scene, first 300 s: no detection more than 5 deg from a ship;
    the submarine (median z 0.4) stays undetected, as with the single window."""

    enabled: bool = setting(False, "run the MFTD on the bearing-time record and add its detections to the peaks",
                            unit="")
    pfa: float = setting(1e-3, "false detections per beam and window its threshold is calibrated for", unit="1",
                         gt=0, lt=0.1)
    pool_beams: int = setting(3, "the MFTD runs on the max over runs of this many adjacent beams", unit="1", ge=1,
                              le=16)
    tile_beams: int = setting(4, "pooled beams a tile owns (one P1 test per tile and window)", unit="1", ge=1)


#: the passive chain's tracker on the front end's statistic z (background spreads above the background level)
#: instead of paper P0's correlation amplitudes (0..30000): field -> (value, doc of that value). DEVIATION from
#: P0's values, chosen on simulated recordings (the front end's noise-only statistics: BeamformerSettings).
PASSIVE_TRACKER_DEFAULTS = {
    "q": (0.001, "white-noise intensity of the cone-angle rate: Q = q [[T^3/3, T^2/2], [T^2/2, T]] (the chain's "
                 "value; 0.01 and 0.05 gave the same targets on the default scene)"),
    "gate_deg": (6.0, "gate width V: a peak within V/2 = 3 deg of the predicted cone angle is validated"),
    "p_detect": (0.9, "probability that a target's peak is present in a window before the threshold on z"),
    "clutter_density_per_deg": (1e-3, "false-peak density above the threshold (noise-only recordings, automatic "
                                      "band: 0.043 peaks a window at z >= 4 over 0..180 deg, 2.4e-4 /deg; kept "
                                      "above it for the loud ships' sidelobes)"),
    "false_amplitude_rate": (2.0, "alpha of the exponential excess z - threshold of false peaks (noise-only "
                                  "recordings, automatic band: 1.92 per unit z at threshold 3, 95 % interval "
                                  "1.77..2.08; 2.16 at 4; 2.06 on 32 x 1.25 m at 8 kHz)"),
    "init_amplitude": (4.5, "a new track starts on an unassociated peak with z at least this: half a unit over the "
                            "detection threshold, so that a ship whose level hovers at z 4-6 gets a track (study "
                            "passive-chain at full size: ships held 0.86 -> 0.91 of their detectable time, pair-far "
                            "0.75 -> 0.84, false targets the same 3 in 10.7 h, none in noise; with 6 such ships went "
                            "without a track, or restarted late after a crossing, for 2.4 % of that time (0.2 % with "
                            "4.5 and 4 of 5); on its 12 hardest scenes 6 / 5 / 4.5 hold 0.83 / 0.89 / 0.90; noise "
                            "gives 0.016 peaks a window at z >= 4.5, each a start, none confirmed by M of N)"),
    "init_sigma_p_deg": (0.5, "cone-angle standard deviation sigma_p of a new track's peaks (the front end's peaks "
                              "of the default scene's loud ships err by 0.16..0.36 deg RMS)"),
    "init_amplitude_sd": (5.0, "standard deviation sigma_a of a new track's peak z"),
    "confirm_m": (8, "a new track is confirmed with gated peaks in M of its first N windows: M (study "
                     "passive-chain: no false target in 13.3 h). 4 of 5 confirms in 4 windows, not 8 (12 hardest "
                     "scenes: held 0.92, not 0.90, with the start at 4.5), but on the default ships over 300 s it "
                     "put the tanker's first windows into its record and its batch ML then passed as determined "
                     "11 km off: kept at 8 of 10 until the verdict catches that"),
    "confirm_n": (10, "... N windows (a track failing M-of-N is dropped)"),
    "delete_after": (20, "a track is dropped after this many consecutive windows with an empty gate"),
    "endfire_fold": (True, "a track runs on through endfire (the array's axis): its unfolded cone angle phi, "
                           "measured as its reflection into 0..180 deg; each pass through 0 or 180 deg is a change of "
                           "side (systems/passive/targets.py decides the sides per segment)"),
}

PassiveTrackerSettings = derived_settings(
    BearingTrackerSettings, "PassiveTrackerSettings", "P0's JPDA_A bearing tracker on the front end's peaks, with "
    "the chain's defaults for the statistic z; its amplitude threshold is the root's threshold.",
    drop=("amplitude_threshold",), defaults=PASSIVE_TRACKER_DEFAULTS)

#: keys the root declares now, as the groups used to hold them (a config in the old layout gets told where)
MOVED_TO_ROOT = {"front_end": {"window_s": "window_s", "sound_speed_mps": "sound_speed_mps", "threshold": "threshold"},
                 "tonal": {"window_s": "window_s", "sound_speed_mps": "sound_speed_mps"},
                 "tracker": {"amplitude_threshold": "threshold"},
                 "sequential": {"sound_speed_mps": "sound_speed_mps"}}


@dataclass(frozen=True, slots=True)
class PassiveStages:
    """The stages' settings built from one :class:`PassiveSettings` for one recording (:meth:`PassiveSettings.stages`).

    ``settings``: the tree as run (elements = the recording's channels; a 2-channel recording's front end);
    ``array`` and ``band``: the line array and its processing band (Hz), checked; ``fs_hz``: the sample rate;
    ``front_end``, ``tracker``, ``tonal``, ``imm``, ``sequential``: the library settings of each stage, with
    the root's window, threshold and sound speed; ``min_separation_deg``: the scans where two tracks lie closer
    are left out of their TMA."""

    settings: PassiveSettings
    array: LineArray
    band: Band
    fs_hz: float
    front_end: BeamformerSettings
    tracker: BearingTrackerSettings
    tonal: TonalSettings
    imm: ImmSettings
    sequential: SequentialSettings
    min_separation_deg: float


class PassiveSettings(Settings):
    """The passive chain: recording + navigation -> bearing tracks -> target solutions (module doc)."""

    elements: int | None = setting(None, "number of hydrophones; the WAV must have this many channels (not set: "
                                         "the WAV's channel count)", unit="1", ge=2, le=4096)
    spacing_m: float | None = setting(None, "element spacing d of the uniform line array (required)", unit="m", gt=0,
                                           le=1000)
    sound_speed_mps: float = setting(1500.0, "sound speed c at the array: the beams' steering delays (front end, "
                                             "tonal beams) and the sequential TMA's Doppler model", unit="m/s", gt=1300,
                                     lt=1700)
    window_s: float = setting(1.0, "time base of every stage: one line of the bearing-time record, one tracker scan "
                                   "and one tonal spectrum", unit="s", gt=0, le=600)
    threshold: float = setting(4.0, "detection threshold on the front end's normalised statistic z = (P - median) / "
                                    "(1.4826 MAD) across bearing; also the tracker's amplitude threshold tau",
                               unit="1", ge=0, le=100)
    min_track_s: float = setting(120.0, "a confirmed bearing track shorter than this is reported but gets no TMA",
                                 unit="s", gt=0, le=86_400)
    min_side_log_lr: float = setting(math.log(100.0), "the array side is decided when the log likelihood ratio of "
                                     "the two mirror hypotheses exceeds this (ln 100: 100 to 1)", unit="1", gt=0,
                                     le=1000)
    max_peak_offset_deg: float = setting(2.0, "a peak is a track's measurement when within this of the track's "
                                         "bearing at that time", unit="deg", gt=0, le=90)
    min_separation_deg: float | None = setting(None, "the array's resolution, one broadside beamwidth (not set: "
                                               "0.89 c / (f N d) at the band's centre frequency): scans where two "
                                               "tracks' peaks are closer than this are left out of their TMA, and "
                                               "two tracks whose direction cosines differ by less than it (in rad) "
                                               "share a beam (a beam's width is constant in cos(cone))",
                                               unit="deg", gt=0, le=180)
    ml_correlation_inflation: bool = setting(True, "inflate the batch ML covariance by (1 + rho) / (1 - rho) for "
                                                   "the lag-1 correlation rho of its residuals (consecutive windows "
                                                   "err alike)", unit="")
    sigma_freq_floor_hz: float = setting(0.02, "smallest frequency noise the TMA assumes", unit="Hz", gt=0, le=10)
    max_sigma_freq_hz: float = setting(0.4, "a tonal whose measured frequency noise exceeds this is not used by the "
                                       "TMA (its per-window values are mostly noise peaks near the line)", unit="Hz",
                                       gt=0, le=100)
    tma_min_tonal_snr_db: float = setting(4.0, "a tonal line weaker than this over its beam's background is not used "
                                               "by the sequential TMA (bearings only then); [tonal] min_line_snr_db "
                                               "decides whether a line is found at all", unit="dB",
                                          ge=-50, le=100)
    zig_false_alarm_per_hour: float = setting(DEFAULT_FALSE_ALARM_PER_HOUR,
                                              "stated rate of false zigs per hour of a constant-velocity "
                                                   "target for each target's zig test (tma/zig.py, on 30 s block "
                                                   "means of its bearings: systems/passive/target_legs.py); a "
                                                   "target with a zig gets leg-wise TMA rows and its constant-"
                                                   "velocity answers are not determined", unit="1/h", gt=0, le=10)
    front_end: FrontEndSettings = setting(default_factory=FrontEndSettings, doc="beamforming and peak picking")
    tracker: PassiveTrackerSettings = setting(default_factory=PassiveTrackerSettings,
                                              doc="JPDA_A bearing tracker on the peaks")
    tonal: PassiveTonalSettings = setting(default_factory=PassiveTonalSettings,
                                          doc="tonal line measurement on each track's beam")
    imm: ImmSettings = setting(default_factory=ImmSettings, doc="IMM-MGEKF modes of the sequential TMA")
    sequential: PassiveSequentialSettings = setting(default_factory=PassiveSequentialSettings,
                                                    doc="initialisation of the sequential TMA")
    mvdr: MvdrSettings = setting(default_factory=MvdrSettings, doc="MVDR beams, used when [front_end] method = "
                                 "'mvdr' (default scene, first 300 s: detection 0.99/0.86/0.01/1.00 of the four ships "
                                 "against CBF's 0.96/0.77/0.00/0.96, at 5x the cost; CBF stays the default, on "
                                 "which the tracker's z statistics were measured)")
    narrowband: NarrowbandSettings = setting(default_factory=NarrowbandSettings,
                                             doc="narrowband (LOFAR) pass and line tracks")
    btr_mftd: PassiveBtrMftdSettings = setting(default_factory=PassiveBtrMftdSettings,
                                               doc="track-before-detect (P1's MFTD) on the bearing-time record")
    verdict: VerdictSettings = setting(default_factory=VerdictSettings,
                                       doc="when a target's range is reported as NOT DETERMINED (tma/verdict.py)")

    @model_validator(mode="before")
    @classmethod
    def _old_layout(cls, data):
        """A key that moved to the root, given in its old group (or under its old name), gets told where it lives."""
        if not isinstance(data, dict):
            return data
        for group, keys in MOVED_TO_ROOT.items():
            table = data.get(group)
            stray = sorted(k for k in keys if isinstance(table, dict) and k in table)
            if stray:
                raise ValueError(f"{', '.join(stray)} under [{group}] now sit(s) at the top of the passive settings, "
                                 f"one value for every stage: move it out of [{group}] as "
                                 f"{', '.join(keys[k] for k in stray)}")
        if "min_line_snr_db" in data:
            raise ValueError("the top-level min_line_snr_db is now tma_min_tonal_snr_db (the tonal strength the TMA "
                             "needs); [tonal] min_line_snr_db is the line detection's")
        return data

    def stages(self, fs_hz: float, channels: int | None = None) -> PassiveStages:
        """The stages' settings for a recording, built once: root values handed down, the array and band checked.

        Parameters
        ----------
        fs_hz : float
            Sample rate of the recording (Hz).
        channels : int, optional
            The recording's channel count: it must match ``elements`` when that is set, and becomes the element
            count; 2 channels are two sensors (:meth:`two_sensor`). None: ``elements`` must be set.

        Returns
        -------
        PassiveStages
            The built stages. Raises :class:`~sonartrack.core.errors.InputError` with the fix when the spacing
            is missing, the recording does not match the array, or the band does not fit the array.
        """
        require(self.spacing_m is not None, "the element spacing is not set: give --spacing (metres)")
        s = self
        if channels is not None:
            if s.elements is not None:
                require(channels == s.elements, f"the recording has {channels} channels but --elements is "
                                                f"{s.elements}: give the recording of the whole array, or the right "
                                                "--elements")
            require(channels >= 2, f"the recording has {channels} channel(s): a line array needs at least two")
            s = (s.two_sensor(fs_hz) if channels == 2 else s).model_copy(update={"elements": channels})
        require(s.elements is not None, "the number of elements is not set: give --elements")
        return s._built(fs_hz)

    def _built(self, fs_hz: float) -> PassiveStages:
        from sonartrack.acoustics.beamforming import front_end_band

        array = LineArray(self.elements, self.spacing_m, self.sound_speed_mps)
        front_end = self.front_end.build(window_s=self.window_s, threshold=self.threshold)
        band = front_end_band(array, front_end, fs_hz)
        min_sep = self.min_separation_deg if self.min_separation_deg is not None else \
            array.beamwidth_deg(band.centre_hz)
        return PassiveStages(
            settings=self, array=array, band=band, fs_hz=float(fs_hz), front_end=front_end,
            tracker=self.tracker.build(amplitude_threshold=self.threshold),
            tonal=self.tonal.build(window_s=self.window_s), imm=self.imm,
            sequential=self.sequential.build(sound_speed_mps=self.sound_speed_mps), min_separation_deg=min_sep)

    def two_sensor(self, fs_hz: float) -> PassiveSettings:
        """The settings for a 2-channel recording: two sensors, as in paper P0, so their cross-correlation (the
        split-array method with one element per half) over a broad band, [fs / 80, fs / 4] (50-1000 Hz at 4 kHz)
        unless ``band_hz`` is given. A time delay of broadband noise is unambiguous over the physical lags, so the
        sensor spacing may exceed half a wavelength (P0's 20 m does) and grating lobes are accepted. ``fs_hz``: the
        recording's sample rate (Hz).

        Returns
        -------
        PassiveSettings
            A copy with the two-sensor front end.
        """
        fe = self.front_end
        band = fe.band_hz if fe.band_hz is not None else [fs_hz / 80.0, fs_hz / 4.0]
        front_end = fe.model_copy(update={"method": "split-array", "band_hz": band, "allow_grating_lobes": True})
        return self.model_copy(update={"front_end": front_end})

"""Settings of the active system (``sonartrack active``): one tree, each shared quantity declared once.

The root declares what several stages share: the array (``elements``, ``spacing_m``), the medium
(``sound_speed_mps``: beam steering, Doppler to range rate, travel time to bistatic range in the MFTD's prior
and in the contacts), the targets' largest bistatic range rate (``max_range_rate_mps``: the CW Doppler bank
and the MFTD's tiles), the time base (``ping_interval_s``: the MFTD's motion step; not set: the ping table's)
and the false-alarm rates per cell and ping: ``pfa`` sets the single-ping threshold (the CFAR's closed form),
``mftd_pfa`` the MFTD's (calibrated on noise; lower by default, so that the two give comparable false-track
rates: see its doc). The waveform is the ping table's (each ping's pulse is written there with the samples).
Each stage's group keeps only its own fields (``core.settings.derived_settings``): ``[front_end]``
(detection/cells.py: beams, CFAR), ``[mftd]`` (detection/ping_mftd.py), ``[contacts]``
(systems/active/contacts.py: P4's input errors), ``[tracker]`` (tracking/settings.py, P4's IMM-IPDA, with the
active chain's detection probability declared here), and the range-rate gate's width at the root.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, derived_settings, setting
from sonartrack.detection.cells import FrontEndSettings
from sonartrack.detection.cw_cells import CwNormaliserSettings
from sonartrack.detection.ping_mftd import PingMftdSettings
from sonartrack.systems.active.contacts import ContactSettings
from sonartrack.tracking.motion import TurnModes
from sonartrack.tracking.settings import PositionTrackerSettings

ActiveFrontEndSettings = derived_settings(
    FrontEndSettings, "ActiveFrontEndSettings", "The active front end of each ping (detection/cells.py: beams, "
    "matched filter, CFAR); the sound speed and the false-alarm rate are the root's.",
    drop=("sound_speed_mps", "pfa", "max_range_rate_mps"))

ActiveMftdSettings = derived_settings(
    PingMftdSettings, "ActiveMftdSettings", "MFTD across pings (detection/ping_mftd.py, paper P1); the ping interval, "
    "the sound speed, the false-alarm rate and the largest range rate are the root's.", drop=("max_range_rate_mps",))

#: the active chain's tracker: P4's IMM-IPDA (its clutter density too: measured on the default scene, seed 1, one
#: hour, 1e-6 confirms 3 false tracks from MFTD at mftd_pfa 1e-9 and 27 from single-ping detections at pfa 1e-5;
#: 5e-7: 28 and 70; 2e-6: 2 and 0 but holds the targets half as long). field -> (value, doc of that value)
ACTIVE_TRACKER_DEFAULTS = {
    "pd": (0.7, "probability that a target gives a contact on a ping (between P4's 0.8 and the front end's measured "
                "echo-level Pd of the default scene's targets, 0.5-0.7)"),
    "confirm_threshold": (0.99, "a track is confirmed when its existence exceeds this. Tuned on default scenes of "
                                "seeds the study does not use (reverberation-only 9001-9003, with targets 9101): "
                                "confirmed false tracks from MFTD in 3 h of reverberation 6 at 0.9, 2 at 0.97, 0 at "
                                "0.99 (single-ping: 79, 71, 2); the targets' held fraction falls by <= 0.02 and "
                                "their time to confirm grows by 30-60 s"),
    "false_tracks_per_h": (1.0, "stated false confirmed tracks per hour: the confirmation threshold from Ville's bound "
                                "on IPDA's existence odds and the tracks started so far (tracking/existence.py), in "
                                "place of confirm_threshold (benchmarks/bench_active_defaults.py, with the clutter map "
                                "and mftd_strong_pfa: 0 confirmed in 2 h of Rayleigh and 2 h of spiky K 0.5 "
                                "reverberation from the independent generator, a 15 dB target confirmed in 4, 4, 9 "
                                "pings against 8, 8, never at 0.99; the study's quick scene held as at 0.99; K 1 + "
                                "blast + 6 still points: 2 in 2 h with the map's lobe images (36 before); 0.5/h "
                                "confirmed as many false tracks there and one ping later)"),
    "confirm_statistic": ("likelihood_ratio", "the stated rate's threshold held against the likelihood-ratio odds "
                          "the rule bounds, not the existence whose p11 caps its odds below it (tracking/deleters.py "
                          "RateConfirmation; benchmarks/bench_acquisition.py: study trials 2, 14, 18 one ping sooner "
                          "on 5 of 10 targets, held 441 -> 448 of 760, 0 false on the twins of trials 14, 18, 10)"),
    "pd_cw": (0.4, "probability that a target gives a contact on a CW ping (contacts with a measured range rate): "
                   "measured 0.30-0.64 per detectable ping of the default scene's strong targets as CW (MFTD, seed 1), "
                   "as Swerling 1 at the single-ping threshold 16.3 gives, exp(-16.3 / (1 + EBR)) = 0.38 at the "
                   "targets' median 12 dB echo-to-background (benchmarks/bench_active_rows.py, CW seeds 1 and 2: "
                   "rows 6, 8 at 0.7 -> 5, 5 at 0.5 -> 4, 5 at 0.4)"),
    "transition_diagonal": (0.98, "mode transition matrix diagonal, the rest spread evenly over the other modes (P4's "
                                  "two CV modes and the turn modes, target_turn_rates_deg_s): 0.98, not P4's 0.99, "
                                  "lets a track enter a turn mode a ping sooner (tests/systems/active/"
                                  "test_turns_tracker.py: largest error in a 180 deg turn at 1 deg/s 497 -> 406 m, "
                                  "straight target's error unchanged)"),
}

ActiveTrackerSettings = derived_settings(
    PositionTrackerSettings, "ActiveTrackerSettings", "P4's IMM-IPDA on the mirror-pair contacts, with the active "
    "chain's detection probability.", defaults=ACTIVE_TRACKER_DEFAULTS)


class ActiveSettings(Settings):
    """The active chain: pings + navigation -> detections -> mirror contacts -> IMM-IPDA tracks (module doc)."""

    elements: int | None = setting(None, "hydrophones of the line array; every ping must have this many channels "
                                         "(not set: the pings' channel count)", unit="1", ge=2)
    spacing_m: float | None = setting(None, "element spacing d of the uniform line array (required)", unit="m", gt=0)
    sound_speed_mps: float = setting(1500.0, "sound speed c: beam steering, Doppler to range rate, travel time to "
                                             "bistatic range (MFTD prior, contacts)", unit="m/s", gt=1300, lt=1700)
    ping_interval_s: float | None = setting(None, "ping interval T: the MFTD's motion step (not set: the median "
                                                  "interval of the ping table)", unit="s", gt=0, le=600)
    pfa: float = setting(1e-5, "false detections per cell and ping of the single-ping CFAR threshold (closed form)",
                         unit="1", gt=0, lt=0.1)
    max_range_rate_mps: float = setting(15.0, "largest bistatic range rate of a target (rate of the total path Tx -> "
                                              "target -> Rx): the CW Doppler bank's span, the MFTD's tile margin and "
                                              "its range-rate span when the pulse measures no Doppler", unit="m/s",
                                        gt=0, le=200)
    mftd_pfa: float | None = setting(
        1e-9, "false detections per cell and ping of the MFTD ('off': pfa). Its false detections come in streaks "
              "(a strong reverberation echo lifts the K windows that hold it, each ending near it), which a tracker "
              "confirms more readily than single-ping false alarms: equal false-track rates need a lower rate here "
              "(the default scene: 3 false tracks an hour at 1e-9 against single-ping's 27 at 1e-5, the targets "
              "held longer)",
        unit="1", gt=0, lt=0.1)
    mftd_strong_pfa: float | None = setting(
        1e-6, "single-ping detections above the single-ping threshold of this per-cell false-alarm rate join the "
              "MFTD's (not within a beam and 3 delay cells of one): a target entering the window is then detected on "
              "its first ping, not when the MFTD's K-ping stack has filled with it (a 15 dB target: its 3rd ping). "
              "With it, the MFTD's SNR gain over single-ping detection at the same stated false-track rate is 1.6 dB "
              "[0.6, 2.3] against 1.2 [0.1, 2.1] without (benchmarks/bench_mftd_gain.py). 'off': the MFTD's "
              "detections alone", unit="1", gt=0, lt=0.1)
    detector: Literal["mftd", "single"] = setting(
        "mftd", "detections the tracker gets: mftd = paper P1 across pings, single = one ping's threshold", unit="")
    range_rate_gate_sigma: float | None = setting(
        3.0, "a contact in a confirmed track's position gate whose range rate is further than this many standard "
             "deviations from the track's predicted bistatic range rate is kept from the tracker ('off': no gate)",
        unit="1", gt=0)
    side_turn_deg: float | None = setting(
        20.0, "a confirmed track that has lived through this much change of the array heading has its side resolved: "
              "the mirror contact of each detection in its gate is then dropped, so no ghost track restarts on the "
              "other side after the turn ('off': both mirror contacts always go to the tracker)", unit="deg", gt=0,
        le=180)
    target_turn_rates_deg_s: list[Annotated[float, Field(gt=0, le=30)]] = setting(
        default_factory=lambda: [0.5, 1.0], unit="deg/s",
        doc="turn rates of the tracker's coordinated-turn modes (a clockwise and a counter-clockwise mode at each, "
            "beside P4's two constant-velocity modes; filters/coordinated_turn.py). A target turning at 1 deg/s "
            "turns 30 deg between pings 30 s apart, and P4's CV modes alone lag it 500-700 m and lose it "
            "(issue 34 item 5); empty: P4's CV modes only")
    target_turn_q: float = setting(1e-3, "white-noise acceleration intensity of each turn mode (covers a target "
                                         "turning between the modes' rates)", unit="m^2/s^3", ge=0)
    merge_probability: float | None = setting(
        0.99, "gate probability of the track-to-track test (tracking/duplicates.py: chi-square on the difference of "
              "two tracks' states [x, y, vx, vy]) by which a track following the same target as a confirmed track "
              "is deleted after each scan (the older confirmed one is kept). IPDA tracks share the contacts in their "
              "gates, so a track started on a stray contact beside a target coalesces with the target's track: "
              "without it the default scene (seed 9101, not a study seed) holds 3-4 confirmed tracks on each strong "
              "target at once ('off': no merging)", unit="1", gt=0, lt=1)
    rejoin_s: float | None = setting(
        600.0, "a track confirmed within this time of the loss of a confirmed track (its existence fell), whose state "
               "passes the track-to-track test (merge_probability) against that track's prediction, is listed as the "
               "same target's next segment (one row, systems/active/targets.py), as is a confirmed track merged into "
               "another as its duplicate ('off': no re-joining)", unit="s", gt=0)
    cw_peak_contacts: bool = setting(
        False, "CW pings: each MFTD detection measured by its ping's own echo peak where there is one, the others "
               "given the errors of a cell anywhere in the echo's response (travel time 2 tau / sqrt(12), cone the "
               "main lobe / sqrt(12)), one detection per echo (systems/active/cw_tracking.py cw_peaked, "
               "cw_unpeaked_errors, cw_merge_echoes). Measured (benchmarks/bench_active_rows.py, default scene as "
               "CW, seeds 1 and 2, contact_claims 'all'): confirmed tracks 21/21 -> 12/19, but held % of detectable "
               "pings 91/90 -> 85/88 (seed 1's approacher 95 -> 81) and rows not cleaner: off", unit="1")
    contact_claims: Literal["confirmed", "all", "lm"] | None = setting(
        "all", "contacts shared by rank (tracking/associators.py ClaimedPDA, a one-pass stand-in for JIPDA): a track "
              "is given a contact only as far as no track ranked above it claims it, so a young track beside a "
              "confirmed one gains no existence on that one's echoes; 'all': every track claims from those ranked "
              "below it (confirmed first, then by existence), 'confirmed': the confirmed from the tentative only, "
              "'lm': LMIPDA's symmetric odds form ('off': each track on its own, IPDA). Measured "
              "(benchmarks/bench_active_rows.py, default scene, cached contacts): confirmed tracks LFM 8/8 -> 8/6, "
              "CW 29/26 -> 21/21; LFM seed 2's row joining crossing-b and maneuvering gone; 'confirmed' and 'lm' "
              "left more CW rows (8-13 for 4 targets)",
        unit="1")
    merge_keep_apart: bool = setting(
        True, "two confirmed tracks once told apart by the track-to-track test (merge_probability) while both held "
              "their targets are two targets: never merged as duplicates when they later cross "
              "(tracking/duplicates.py keep_apart). Measured (benchmarks/bench_active_rows.py, default scene, cached "
              "contacts, contact_claims 'all'): CW seeds 1/2 rows holding two or more targets 1/1 -> 0/0 (seed 1's "
              "row held all four through merges at crossings), at 3 -> 7 and 4 -> 8 rows for 4 targets, held % "
              "91/90 -> 89/89; LFM 4 clean rows each either way; on bench_cw_held.py's scene b (seeds 3, 4) 2/1 "
              "-> 0/1 rows holding two or more, 5/6 -> 9/9 rows for 5 targets: extra rows for fewer joined targets "
              "(False: P4's merger)", unit="1")
    merge_reunite_scans: int = setting(
        8, "a told-apart pair (merge_keep_apart) merged after all after this many scans in a row passing the "
           "track-to-track test on the whole state AND on the velocity and sharing its nearest contact "
           "(tracking/duplicates.py reunite_scans; 0: never). Measured (benchmarks/bench_active_rows.py, CW seeds "
           "1/2/5 and bench_cw_held's scene b seeds 3/4): rows 7/5/6/9/8 -> 6/4/5/7/8, rows holding two targets "
           "0/0/0/0/2 -> 0/0/0/0/2 at 8; 3 and 5 scans joined two targets on seed 5 or scene b", unit="1", ge=0,
        le=100)
    endfire_alias: bool = setting(
        True, "a contact in the line array's grating-lobe alias of a contact a confirmed track holds (u = cos cone "
              "shifted by wavelength / spacing, within a main lobe; at half-wavelength spacing one endfire hears the "
              "other) and at its bistatic range within the delay's resolution goes to no unconfirmed track "
              "(contact_tracker.py EndfireAlias). Measured (benchmarks/bench_active_rows.py): CW seed 1's false row "
              "at the fore endfire, crossing-b's alias, gone (False: off)", unit="1")
    clutter_map_pings: int | None = setting(
        8, "clutter map (detection/clutter_map.py): a contact whose world position recurs in clutter_map_hits of "
           "the last this many pings, and whose recurrences fit a still point (clutter_map_still_probability), is "
           "stationary clutter and goes only to confirmed tracks whose gate holds it; a slow new track on a recurring "
           "contact is not confirmed until its speed or the map decides (tracking/deleters.py StillHold). On the "
           "independent generator's K 1 + blast + 6 still points of 35 dB (2 h) it cut the confirmed tracks on the "
           "points and their mirrors from 48 to 14, and with the points' mirror twins and lobe images withheld too "
           "(clutter_map.py same_range: weaker contacts at a recurring echo's bistatic range) and StillHold kept "
           "until a track moves, all false confirmed tracks there from 36 to 2; the study's quick scene (5 kn "
           "targets, 10 s pings) is held as without it ('off': no map)",
        unit="1", ge=1, le=100)
    clutter_map_hits: int = setting(3, "pings of the clutter map's memory that must hold a contact in the gate of a "
                                       "new one for it to be clutter (3: learned before IPDA confirms a track on a "
                                       "strong still point, ~4 pings; at 5 the independent generator's 6 points of 35 "
                                       "dB gave 7 confirmed tracks in 20 pings, at 3 one)", unit="1", ge=1, le=100)
    clutter_map_still_probability: float | None = setting(
        0.9, "the clutter map's stillness test (detection/clutter_map.py): a recurring contact is clutter only when "
             "the confidence ellipse, at this probability, of the velocity fitted through its recurrences lies "
             "within clutter_map_slow_mps, so a moving target's contacts are spared ('off': recurrence alone)",
        unit="1", gt=0, lt=1)
    clutter_map_slow_mps: float = setting(
        1.0, "speed below which the clutter map may take a recurring contact for a still point (a target slower "
             "than this, not yet confirmed, is taken for clutter once its fit shows it slower)", unit="m/s", gt=0)
    clutter_map_image_m: float | None = setting(
        15.0, "bistatic-range window of the clutter map's lobe images (detection/clutter_map.py same_range): a contact "
              "of the same ping weaker than a recurring one and within this of its bistatic range is withheld from "
              "unconfirmed tracks (a beam at one endfire hears the other's clutter; about 2 LFM delay cells; 'off': "
              "off)", unit="m", gt=0)
    bscan_bins: int = setting(400, "travel-time bins of the stored B-scan per ping (max over the cells of a bin and "
                                   "the Doppler cells)", unit="1", ge=10, le=100_000)
    front_end: ActiveFrontEndSettings = setting(default_factory=ActiveFrontEndSettings,
                                                doc="beams, matched filter and CFAR of each ping")
    cw: CwNormaliserSettings = setting(default_factory=CwNormaliserSettings,
                                       doc="a CW ping's normaliser across Doppler and delay, and its reverberation "
                                           "ridge notch (detection/cw_cells.py)")
    mftd: ActiveMftdSettings = setting(default_factory=ActiveMftdSettings, doc="MFTD across pings (paper P1)")
    contacts: ContactSettings = setting(default_factory=ContactSettings, doc="bistatic contact input errors (P4)")
    tracker: ActiveTrackerSettings = setting(default_factory=ActiveTrackerSettings,
                                             doc="IMM-IPDA position tracker (paper P4)")

    def front_end_settings(self) -> FrontEndSettings:
        """The front end's library settings with the root's sound speed and false-alarm rate.

        Returns
        -------
        FrontEndSettings
            The ``front_end`` group built with the root's ``sound_speed_mps`` (m/s), ``pfa`` and
            ``max_range_rate_mps`` (m/s).
        """
        return self.front_end.build(sound_speed_mps=self.sound_speed_mps, pfa=self.pfa,
                                    max_range_rate_mps=self.max_range_rate_mps)

    def mftd_settings(self) -> PingMftdSettings:
        """The MFTD's library settings with the root's largest range rate.

        Returns
        -------
        PingMftdSettings
            The ``mftd`` group built with the root's ``max_range_rate_mps`` (m/s).
        """
        return self.mftd.build(max_range_rate_mps=self.max_range_rate_mps)

    def tracker_settings(self) -> PositionTrackerSettings:
        """The tracker's library settings.

        Returns
        -------
        PositionTrackerSettings
            The ``tracker`` group built as it is.
        """
        return self.tracker.build()

    def turn_modes(self) -> TurnModes:
        """The tracker's coordinated-turn modes.

        Returns
        -------
        TurnModes
            ``target_turn_rates_deg_s`` (deg/s) with intensity ``target_turn_q`` (m^2/s^3).
        """
        return TurnModes(tuple(self.target_turn_rates_deg_s), self.target_turn_q)

    def checked(self, channels: int) -> ActiveSettings:
        """These settings for pings of ``channels`` channels (elements set to it; one-line errors).

        Parameters
        ----------
        channels : int
            The pings' channel count.

        Returns
        -------
        ActiveSettings
            A copy with ``elements`` = ``channels``.
        """
        require(self.spacing_m is not None, "the element spacing is not set: give --spacing (metres)")
        if self.elements is not None:
            require(channels == self.elements, f"the pings have {channels} channels but --elements is "
                                               f"{self.elements}: give the pings of the whole array, or the right "
                                               "--elements")
        require(channels >= 2, f"the pings have {channels} channel(s): a line array needs at least two")
        return self.model_copy(update={"elements": int(channels)})

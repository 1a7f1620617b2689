"""The tracker settings, each declared once: the position (IPDA / IMM-IPDA) and the bearing (JPDA / JPDA_A) tracker.

These two classes are the only declarations of tracker settings in the package. The studies nest them
in their configs (``tracker: ...``, a ``[tracker]`` table in TOML) and pass their paper values where
those differ from the defaults here; ``sonartrack track --config`` reads the same ``[tracker]`` table;
``sonartrack track --print-config`` prints them. Each default says in its doc where it comes from.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import model_validator

from sonartrack.core.settings import Settings, setting

#: clutter density of paper P0's peak model above the tracking threshold: lambda V = 2 false peaks per
#: 10 deg gate at threshold 0, times exp(-alpha tau) with alpha = 4e-4, tau = 5000 (the fraction above tau)
P0_CLUTTER_DENSITY_PER_DEG = 2.0 / 10.0 * float(np.exp(-2.0))


class PositionTrackerSettings(Settings):
    """IPDA / IMM-IPDA position tracker (paper P4: Park, Song, Lee 2017); defaults are that paper's tracker."""

    q: list[float] = setting(
        default_factory=lambda: [1e-4, 0.05], min_length=1, unit="m^2/s^3",
        doc="CV white-noise acceleration intensity, one per IMM mode (one value: single-model IPDA); "
            "default P4's two-mode IMM-IPDA: 1e-4 for straight running, 0.05 for a maneuvering target")
    transition_diagonal: float = setting(
        0.99, "mode transition matrix diagonal (the rest spread evenly); 0.99, not 0.95, keeps the small-q mode "
              "dominant on a straight target as P4's mode-probability plots show", unit="1", ge=0, le=1)
    pd: float = setting(0.8, "probability of detection of a target (P4)", unit="1", gt=0, le=1)
    pd_cw: float | None = setting(
        None, "probability of detection on the scans of a CW pulse (contacts carrying a measured range rate, the "
              "active chain's systems/active/contact_tracker.py), whose echoes are reverberation-limited where an "
              "LFM's are not (not set: pd)", unit="1", gt=0, le=1)
    gate_probability: float = setting(0.99, "chi-square(2) gate probability P_G (gamma = 9.21)", unit="1", gt=0, lt=1)
    clutter_density_per_m2: float = setting(1e-6, "clutter density the tracker assumes (P4: 40 points in 4e7 m^2)",
                                            unit="1/m^2", gt=0)
    p_survive: float = setting(0.98, "existence Markov chain p11: a track's target survives one scan", unit="1",
                               gt=0, le=1)
    p_birth: float = setting(0.0, "existence Markov chain p21: a non-existing track's target appears", unit="1",
                             ge=0, lt=1)
    initial_existence: float = setting(0.05, "existence probability of a new one-point track", unit="1", gt=0, lt=1)
    confirm_threshold: float = setting(0.9, "a track is confirmed when its existence exceeds this", unit="1",
                                       gt=0, le=1)
    false_tracks_per_h: float | None = setting(
        None, "stated false confirmed tracks per hour: the confirmation threshold is then set from it and the tracks "
              "started per scan so far by Ville's inequality on IPDA's existence odds (tracking/existence.py "
              "confirm_threshold_for_rate), in place of confirm_threshold (not set: confirm_threshold)",
        unit="1/h", gt=0)
    confirm_statistic: Literal["existence", "likelihood_ratio"] = setting(
        "existence", "what the stated false-track rate's threshold (false_tracks_per_h) is held against: the existence "
                     "probability (P4), or the likelihood-ratio odds the rule bounds, the track's initial odds times "
                     "its scans' Lambda, which p11 does not cap below the threshold (tracking/deleters.py "
                     "RateConfirmation); the existence still deletes", unit="")
    confirm_min_hits: int = setting(
        1, "fewest scans with a measurement in its gate (its initiating one counted) before a track may be confirmed, "
           "whatever its existence (tracking/deleters.py MinHits; 1: the existence alone, P4)", unit="1", ge=1, le=20)
    merge_confirmed_scans: int = setting(
        1, "consecutive scans on which two confirmed tracks must pass the track-to-track test before the younger is "
           "merged into the older as its duplicate (tracking/duplicates.py DuplicateMerger; a tentative duplicate is "
           "merged at once; 1: at once, P4)", unit="1", ge=1, le=20)
    merge_history_scans: int = setting(
        0, "a confirmed track deleted as another confirmed track's duplicate is recorded as the same target only when "
           "the pair also passed the track-to-track test on each of the last this many scans on which both were "
           "confirmed (tracking/duplicates.py DuplicateMerger history_scans; 0: on this scan only, P4)",
        unit="1", ge=0, le=100)
    terminate_threshold: float = setting(0.01, "a track is deleted when its existence falls below this", unit="1",
                                         ge=0, lt=1)
    listed_existence: float | None = setting(
        None, "a confirmed track whose existence falls below this is not listed (shown) while it stays below; the "
              "tracker's confirmation is unchanged (tracking/deleters.py listed_tracks; 0.5: listed while more likely "
              "a target than not); off: every confirmed track listed until deleted (P4)", unit="1", gt=0, lt=1)
    init_velocity_std_mps: float = setting(5.0, "standard deviation of the zero-mean velocity prior of a new track, "
                                                "per axis", unit="m/s", gt=0)
    max_tracks: int = setting(2000, "most live tracks; measurements beyond it start no track", unit="1", ge=1)

    amplitude_aided: bool = setting(
        False, "each contact's amplitude (its detector's statistic) weighs its association and existence update by "
               "the ratio of its target law to its clutter law above the threshold (Lerro & Bar-Shalom 1993 eq. 12; "
               "association/amplitude_ipda.py, tracking/amplitude_parts.py); off: positions (and range rates) only",
        unit="")
    amplitude_clutter_prior_mean: float = setting(
        10.0, "prior mean excess of a clutter contact's amplitude over the lowest seen (the statistic's unit: the "
              "default scene's LFM clutter contacts measured 12-15 over the MFTD's ~19)", unit="1", gt=0)
    amplitude_clutter_prior_n: float = setting(20.0, "weight of that prior in contacts", unit="1", gt=0)
    amplitude_clutter_scans: int = setting(30, "scans whose contacts' amplitudes make the clutter amplitude sample "
                                                "(the last ones)", unit="1", ge=1, le=10_000)
    amplitude_target_memory: float = setting(
        0.9, "factor on a track's own amplitude weights per scan (its echo level drifts with range and aspect)",
        unit="1", gt=0, le=1)
    amplitude_target_prior_ratio: float = setting(
        1.0, "a new track's prior mean amplitude excess as a multiple of the clutter's: 1, a track is as strong as "
             "clutter until its echoes say otherwise (benchmarks/bench_active_turns.py, default scene rows: at 2 with "
             "weight 2 young tracks beside strong targets confirmed sooner, LFM rows 4/4 -> 6/5, CW seed 2 4 -> 6; at "
             "1 with weight 5: 5/5 and CW 6/4 as without amplitude, acquisition the same)", unit="1", ge=1)
    amplitude_target_prior_n: float = setting(5.0, "weight of that prior (inverse-gamma alpha0 - 1) in contacts",
                                              unit="1", gt=0)
    amplitude_max_ratio: float = setting(
        5.0, "cap on a contact's amplitude likelihood ratio (benchmarks/bench_active_amplitude.py, the study's twins "
             "of trials 14, 15, 6, 1 h each: false confirmed 4/9/0 without amplitude, 2/9/0 at 5, 3/9/0 at 30, where a "
             "still point's strong echoes confirmed a track before the clutter map's verdict)", unit="1", gt=1)
    amplitude_start: bool = setting(
        False, "a new track's initial existence odds times its first contact's amplitude ratio under the prior target "
               "law (tracking/initiators.py AmplitudeOnePointInitiator)", unit="")

    @model_validator(mode="after")
    def _consistent(self):
        if any(q < 0 for q in self.q):
            raise ValueError("q must be non-negative (m^2/s^3)")
        if not self.terminate_threshold < self.initial_existence < self.confirm_threshold:
            raise ValueError("need terminate_threshold < initial_existence < confirm_threshold")
        if self.listed_existence is not None and not self.terminate_threshold < self.listed_existence:
            raise ValueError("need terminate_threshold < listed_existence (a track is unlisted before it is deleted)")
        if len(self.q) > 1 and self.transition_diagonal < 1.0 / len(self.q):
            raise ValueError("transition_diagonal must be in [1/modes, 1]")
        return self

    def transition_matrix(self) -> np.ndarray:
        """Mode transition matrix Pi: ``transition_diagonal`` on the diagonal, the rest of each row spread evenly.

        Returns
        -------
        ndarray, shape (r, r)
            Pi[i, j] = P(mode j at k | mode i at k-1); [[1]] for one mode.
        """
        r = len(self.q)
        if r == 1:
            return np.ones((1, 1))
        Pi = np.full((r, r), (1.0 - self.transition_diagonal) / (r - 1))
        np.fill_diagonal(Pi, self.transition_diagonal)
        return Pi

    def with_modes(self, q) -> PositionTrackerSettings:
        """The same settings with the modes' q replaced (validated).

        Parameters
        ----------
        q : sequence of float
            White-noise acceleration intensities, one per mode (m^2/s^3).

        Returns
        -------
        PositionTrackerSettings
            A new, validated instance.
        """
        return type(self).model_validate({**self.model_dump(), "q": [float(v) for v in q]})


class BearingTrackerSettings(Settings):
    """JPDA / JPDA_A bearing tracker (paper P0: Park, Ryu, Lee 1994); defaults are that paper's tracker.

    State [bearing (deg), bearing rate (deg/s)] of a cone angle; the scan period is taken from the scan
    times (the paper's T = 1 s for 1 s scans)."""

    q: float = setting(
        0.01, "white-noise intensity of the bearing rate: Q = q [[T^3/3, T^2/2], [T^2/2, T]]. DEVIATION: P0's "
              "'q = 0.1 deg' is read as a standard deviation, so q = 0.1^2 (as the variance, 0.1, weak tracks are "
              "lost in clutter)", unit="deg^2/s^3", gt=0)
    gate_deg: float = setting(10.0, "gate width V: a peak within V/2 of the predicted bearing is validated (P0)",
                              unit="deg", gt=0)
    p_detect: float = setting(1.0, "probability that a track's true peak is present before the amplitude threshold "
                                   "(P0's model: always)", unit="1", gt=0, le=1)
    clutter_density_per_deg: float = setting(P0_CLUTTER_DENSITY_PER_DEG,
                                             "false-peak density above the threshold: P0's lambda V = 2 per 10 deg "
                                             "times exp(-alpha tau)", unit="1/deg", gt=0)
    false_amplitude_rate: float = setting(4e-4, "alpha of the exponential false-peak amplitudes (P0)",
                                          unit="1/amplitude", gt=0)
    amplitude_threshold: float = setting(5_000.0, "amplitude threshold tau applied to the peaks before tracking (P0)",
                                         unit="amplitude", ge=0)
    init_amplitude: float = setting(7_000.0, "a new track starts on an unassociated peak at least this strong",
                                    unit="amplitude", ge=0)
    init_sigma_p_deg: float = setting(1.5, "peak position standard deviation sigma_p of a new track (between P0's "
                                           "strong 1.3 and weak 1.8 deg)", unit="deg", gt=0)
    init_amplitude_sd: float = setting(3_000.0, "peak amplitude standard deviation sigma_a of a new track (between "
                                                "P0's 2500 and 3500)", unit="amplitude", gt=0)
    confirm_m: int = setting(3, "a new track is confirmed with gated peaks in M of its first N scans: M",
                             unit="1", ge=1)
    confirm_n: int = setting(4, "... N (a track failing M-of-N is dropped)", unit="1", ge=1)
    delete_after: int = setting(5, "a track is dropped after this many consecutive scans with an empty gate",
                                unit="1", ge=1)
    endfire_fold: bool = setting(False, "the state is the unfolded cone angle phi, measured as its reflection into "
                                        "0..180 deg, so a track runs on through endfire (the array's axis) instead "
                                        "of ending there (P0: off)", unit="")
    resolution_deg: float = setting(0.0, "two confirmed tracks whose predicted cone angles lie closer than this share "
                                         "one peak and are associated and updated as one merged track, so they do "
                                         "not coalesce (tracking/resolution.py; about a beamwidth); 0: off (P0)",
                                    unit="deg", ge=0, le=90)

    @model_validator(mode="after")
    def _consistent(self):
        if self.confirm_m > self.confirm_n:
            raise ValueError("need confirm_m <= confirm_n")
        return self

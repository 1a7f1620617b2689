"""Amplitude-aided JPDA (JPDA_A, paper P0: Park, Ryu & Lee 1994, appendix A and eq. 9) for Stone Soup.

Detections carry their peak amplitude a_j in ``detection.metadata["amplitude"]``; only peaks above the
threshold tau reach the tracker. A false peak's amplitude is exponential with rate alpha, a target's is
N(z_hat_t, sigma_a^2) around the track strength z_hat_t (kept in the track's metadata, stonesoup/tracks.py).
:class:`AmplitudeHypothesiser` multiplies each PDA hit weight by the amplitude likelihood ratio and uses
the thresholded detection probability in the miss weight (association/amplitude.py):

    w_tj = P_D0 N(z_j; z_hat, S) / lambda * r_tj
    log r_tj = log N(a_j; z_hat_t, sigma_a^2) - log(alpha exp(-alpha (a_j - tau)))
    w_t0 = 1 - P_D0 Phi((z_hat_t - tau) / sigma_a) P_G

(P_D0 stays in the hit weight: P_D Phi(...) times the truncated amplitude density N / Phi is P_D0 N).
:class:`JPDAWithAmplitude` is the exact JPDA (stonesoup/jpda.py) on these weights, and after each scan
stages the new strength (eq. 9)  z_hat(k) = 0.7 z_hat(k-1) + 0.3 max_j a_j  over the track's validated
detections (a track with none keeps its strength).
"""

from __future__ import annotations

import numpy as np
from stonesoup.base import Property
from stonesoup.hypothesiser.probability import PDAHypothesiser
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.numeric import Probability

from sonartrack.association.amplitude import (
    STRENGTH_INITIAL,
    amplitude_log_ratio,
    detection_probability_above,
    update_strength,
)
from sonartrack.core.errors import InputError
from sonartrack.stonesoup.hypotheses import weighted_hypotheses
from sonartrack.stonesoup.jpda import JPDA, associate_exact
from sonartrack.stonesoup.tracks import STRENGTH, stage

#: detection metadata key of the peak amplitude
AMPLITUDE = "amplitude"


def amplitude_of(detection) -> float:
    """The detection's peak amplitude (metadata["amplitude"]).

    Parameters
    ----------
    detection : Detection
        A detection with ``metadata["amplitude"]``; raises :class:`InputError` without one.

    Returns
    -------
    float
        The amplitude (units of the peaks, e.g. 0..30000 for the cross-correlation peaks).
    """
    try:
        return float(detection.metadata[AMPLITUDE])
    except (KeyError, TypeError):
        raise InputError("JPDA_A needs each detection's amplitude in detection.metadata['amplitude'] "
                         "(e.g. from sonartrack.stonesoup.convert.detections_from_peaks)") from None


class AmplitudeHypothesiser(PDAHypothesiser):
    """PDA hypothesiser with the amplitude likelihood ratio of JPDA_A (module doc). Weights stay unnormalised."""

    amplitude_threshold: float = Property(doc="tau, the amplitude threshold the peaks passed (amplitude units)")
    false_amplitude_rate: float = Property(doc="alpha, rate of the exponential false-peak amplitudes (1/amplitude)")
    amplitude_spread: float = Property(doc="sigma_a, standard deviation of a target's peak amplitude")
    initial_strength: float = Property(default=STRENGTH_INITIAL, doc="z_hat of a track without one (eq. 9: 15000)")
    normalise: bool = Property(default=False, doc="Must be False: the weights' scale carries the amplitude ratio")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if self.normalise:
            raise InputError("AmplitudeHypothesiser needs normalise=False")

    def strength_of(self, track) -> float:
        """The track's strength z_hat (metadata), or ``initial_strength``.

        Parameters
        ----------
        track : Track
            The track.

        Returns
        -------
        float
            z_hat (amplitude units).
        """
        return float(track.metadata.get(STRENGTH, self.initial_strength))

    def hypothesise(self, track, detections, timestamp, **kwargs):
        """PDA hypotheses with w_t0 and w_tj of the module doc (arguments as
        :meth:`sonartrack.stonesoup.ipda.IPDAHypothesiser.hypothesise`): an unnormalised MultipleHypothesis, hits
        weighted by the amplitude likelihood ratio r_tj, the miss by 1 - P_D0 Phi((z_hat - tau) / sigma_a) P_G."""
        multi = super().hypothesise(track, detections, timestamp, **kwargs)
        strength = self.strength_of(track)
        pd_eff = float(detection_probability_above(float(self.prob_detect), strength, self.amplitude_spread,
                                                   self.amplitude_threshold))
        hits = [h for h in multi if h]
        log_r = amplitude_log_ratio([amplitude_of(h.measurement) for h in hits], [strength],
                                    [self.amplitude_spread], self.false_amplitude_rate, self.amplitude_threshold)[0]
        for h, lr in zip(hits, log_r, strict=True):
            h.probability = Probability(h.probability.log_value + float(lr), log_value=True)
        for h in multi:
            if not h:
                h.probability = Probability(1.0 - pd_eff * float(self.prob_gate))
        return MultipleHypothesis(multi.single_hypotheses, normalise=False)


class JPDAWithAmplitude(JPDA):
    """JPDA_A: exact JPDA on the amplitude-aided weights, with the eq. 9 strength update (module doc)."""

    hypothesiser: AmplitudeHypothesiser = Property(doc="Amplitude-aided PDA hypothesiser")

    def associate(self, tracks, detections, timestamp, **kwargs):
        """Mapping track -> MultipleHypothesis holding the exact JPDA marginal weights of its hypotheses (arguments
        as :meth:`sonartrack.stonesoup.jpda.JPDA.associate`); stages each track's new strength z_hat."""
        hypotheses, table, log_beta = associate_exact(self, tracks, detections, timestamp, **kwargs)
        out = {}
        for t, track in enumerate(table.tracks):
            out[track] = weighted_hypotheses(hypotheses[track], table.columns[t], log_beta[t].tolist(), timestamp)
            gated = [amplitude_of(h.measurement) for h in hypotheses[track] if h]
            a_max = max(gated) if gated else np.nan
            stage(track, **{STRENGTH: float(update_strength(self.hypothesiser.strength_of(track), a_max))})
        return out

"""sonartrack's estimators as Stone Soup components (optional extra: ``pip install sonartrack[stonesoup]``).

Each component subclasses Stone Soup's own base class and takes and returns Stone Soup types, so it drops
into a Stone Soup tracker in place of Stone Soup's:

* :class:`JPDA` -- exact JPDA marginals by our compiled forward-backward pass; a drop-in for Stone Soup's
  ``JPDA`` / ``JPDAwithEHM2`` (same hypothesiser, same hypotheses, same weights) -- stonesoup/jpda.py;
* :class:`IPDAHypothesiser`, :class:`IPDA`, :class:`JIPDA` -- association with track existence
  (Musicki et al. 1994; Musicki & Evans 2004), :class:`ExistenceInitiator`, :class:`ExistenceDeleter`
  and :class:`ExistenceTrack` for existence-based track management -- stonesoup/ipda.py, existence.py;
* :class:`AmplitudeHypothesiser`, :class:`JPDAWithAmplitude` -- JPDA_A of paper P0 (detections carry
  ``metadata["amplitude"]``) -- stonesoup/amplitude.py;
* :class:`IMMPredictor`, :class:`IMMUpdater` (mode probabilities on an :class:`IMMState`) and paper P4's
  IMM-IPDA: :class:`IMMIPDAHypothesiser`, :class:`IMMIPDAUpdater`, :class:`IMMIPDATracker`,
  :func:`imm_ipda_tracker` -- stonesoup/imm.py, imm_ipda.py;
* :class:`MGEKFUpdater` (modified-gain EKF, paper P2) and the bearing + frequency measurement model
  :class:`BearingFrequency` with :class:`RelativeConstantVelocity` -- stonesoup/mgekf.py, models.py;
* :class:`RangeParameterisedInitiator` -- a bearings-only initiator: Peach's range-parameterised EKF bank held
  until the range is known, then one Gaussian (Stone Soup has none) -- stonesoup/bearings_initiator.py,
  range_mixture.py;
* converters between our arrays and files and Stone Soup's types -- stonesoup/convert.py;
* Stone Soup's OSPA and GOSPA metric generators over our tables of time, id and position
  (:mod:`sonartrack.stonesoup.metrics`, imported on its own; our own are metrics/ospa.py).

The components' defaults are the declarations of sonartrack's tracker (tracking/settings.py), read by
stonesoup/defaults.py, and the IMM-IPDA weights and mixture are association/pda.py's.

The rest of sonartrack never imports this subpackage (nor Stone Soup).
"""

try:
    import stonesoup  # noqa: F401
except ImportError as exc:  # pragma: no cover - exercised only without the extra
    raise ImportError("sonartrack.stonesoup needs Stone Soup: pip install sonartrack[stonesoup]") from exc

from sonartrack.stonesoup.amplitude import AMPLITUDE, AmplitudeHypothesiser, JPDAWithAmplitude
from sonartrack.stonesoup.bearings_initiator import RANGE_MIXTURE, RangeParameterisedInitiator
from sonartrack.stonesoup.existence import ExistenceDeleter, ExistenceInitiator, confirmed_tracks
from sonartrack.stonesoup.imm import IMMPredictor, IMMState, IMMStatePrediction, IMMStateUpdate, IMMUpdater
from sonartrack.stonesoup.imm_ipda import (
    IMMIPDAHypotheses,
    IMMIPDAHypothesiser,
    IMMIPDATracker,
    IMMIPDAUpdater,
    imm_ipda_tracker,
)
from sonartrack.stonesoup.ipda import IPDA, JIPDA, ExistenceMultipleHypothesis, IPDAHypothesiser
from sonartrack.stonesoup.jpda import JPDA
from sonartrack.stonesoup.mgekf import MGEKFUpdater
from sonartrack.stonesoup.models import BearingFrequency, RelativeConstantVelocity, observer_control_model
from sonartrack.stonesoup.tracks import CONFIRMED, EXISTENCE, STRENGTH, ExistenceTrack, existence_of

__all__ = [
    "AMPLITUDE", "CONFIRMED", "EXISTENCE", "IPDA", "JIPDA", "JPDA", "STRENGTH", "AmplitudeHypothesiser",
    "ExistenceDeleter", "ExistenceInitiator", "ExistenceMultipleHypothesis", "ExistenceTrack", "IPDAHypothesiser",
    "JPDAWithAmplitude", "confirmed_tracks", "existence_of",
    "IMMIPDAHypotheses", "IMMIPDAHypothesiser", "IMMIPDATracker", "IMMIPDAUpdater", "IMMPredictor", "IMMState",
    "IMMStatePrediction", "IMMStateUpdate", "IMMUpdater", "imm_ipda_tracker",
    "RANGE_MIXTURE", "RangeParameterisedInitiator",
    "MGEKFUpdater", "BearingFrequency", "RelativeConstantVelocity", "observer_control_model",
]

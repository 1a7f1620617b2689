"""Existence-based track management for Stone Soup (IPDA / JIPDA; Musicki, Evans & Stankovic 1994, sec. V).

IPDA starts a tentative track on every detection that no track explains, with an initial existence
probability P0, and lets the data decide: the track is confirmed once P(E) exceeds a confirmation
threshold and deleted once it falls below a termination threshold (the thresholds trade confirmed
true tracks against false tracks; paper P4 uses the same rule, tracking/deleters.py). P0 and the two
thresholds default to the declarations of sonartrack's tracker (tracking/settings.py, stonesoup/defaults.py).

* :class:`ExistenceInitiator` wraps any Stone Soup initiator and gives its tracks P(E) = P0
  (they become :class:`~sonartrack.stonesoup.tracks.ExistenceTrack`).
* :class:`ExistenceDeleter` deletes below ``deletion_threshold`` and marks ``metadata["confirmed"]``
  once P(E) > ``confirmation_threshold`` (sticky: the metadata is carried to later states).
"""

from __future__ import annotations

from stonesoup.base import Property
from stonesoup.deleter.base import Deleter
from stonesoup.initiator.base import Initiator
from stonesoup.types.numeric import Probability

from sonartrack.stonesoup.defaults import tracker_default
from sonartrack.stonesoup.tracks import CONFIRMED, EXISTENCE, ExistenceTrack, existence_of


class ExistenceInitiator(Initiator):
    """Tracks of ``initiator`` with existence probability ``initial_existence`` (module doc)."""

    initiator: Initiator = Property(doc="Initiator that makes the tracks' states (e.g. SimpleMeasurementInitiator)")
    initial_existence: Probability = Property(default=Probability(tracker_default("initial_existence")),
                                              doc="P0, the new tracks' existence probability")

    def initiate(self, detections, timestamp, **kwargs):
        """The wrapped initiator's tracks, as ExistenceTracks with P(E) = P0.

        Parameters
        ----------
        detections : set of Detection
            Detections no track took.
        timestamp : datetime.datetime
            Time of the scan.
        **kwargs
            Passed to the wrapped initiator.

        Returns
        -------
        set of ExistenceTrack
            The new tracks, existence ``initial_existence`` in their metadata.
        """
        return {ExistenceTrack(list(track.states), id=track.id,
                               init_metadata={**track.init_metadata, EXISTENCE: float(self.initial_existence)})
                for track in self.initiator.initiate(detections, timestamp, **kwargs)}


class ExistenceDeleter(Deleter):
    """Delete tracks whose existence probability is below ``deletion_threshold``; confirm above the other."""

    deletion_threshold: Probability = Property(default=Probability(tracker_default("terminate_threshold")),
                                               doc="delete when P(E) < this")
    confirmation_threshold: Probability = Property(default=Probability(tracker_default("confirm_threshold")),
                                                   doc="mark metadata['confirmed'] = True once P(E) > this (None: "
                                                       "never)")

    def check_for_deletion(self, track, **kwargs):
        """True when P(E) < deletion_threshold; marks the track confirmed when P(E) > confirmation_threshold.

        Parameters
        ----------
        track : Track
            A track with an existence probability.
        **kwargs
            Not used (Stone Soup's signature).

        Returns
        -------
        bool
            Whether to delete the track.
        """
        p = existence_of(track)
        if self.confirmation_threshold is not None and p > float(self.confirmation_threshold):
            track.metadata[CONFIRMED] = True
        return p < float(self.deletion_threshold)


def confirmed_tracks(tracks) -> set:
    """The tracks that an :class:`ExistenceDeleter` has confirmed.

    Parameters
    ----------
    tracks : iterable of Track
        Tracks.

    Returns
    -------
    set of Track
        Those with metadata :data:`CONFIRMED` true.
    """
    return {track for track in tracks if track.metadata.get(CONFIRMED, False)}

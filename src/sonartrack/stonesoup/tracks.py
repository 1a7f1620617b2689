"""Per-track quantities of our associators on Stone Soup tracks: existence probability, amplitude strength.

They live in the track's metadata (``track.metadata[EXISTENCE]``, ``track.metadata[STRENGTH]``), which
Stone Soup copies from state to state, so ``track.metadatas[k]`` holds the value after scan k.

An associator computes the new value before the tracker appends the new state. :func:`stage` hands it to
the track: an :class:`ExistenceTrack` keeps it aside and writes it into the metadata of the next state
appended (whatever the tracker appends: an update or, as ``MultiTargetMixtureTracker`` does when no
detection is likely, a bare prediction), so every state keeps its own value and calling ``associate``
twice on the same scan gives the same answer. A plain ``Track`` gets the value written into its current
metadata at once (the latest value is right; the previous state's entry is overwritten).
"""

from __future__ import annotations

from stonesoup.types.track import Track

from sonartrack.core.errors import InputError

#: metadata key of the IPDA / JIPDA existence probability P(E)
EXISTENCE = "existence_probability"
#: metadata key of the JPDA_A track strength z_hat (paper P0, eq. 9)
STRENGTH = "amplitude_strength"
#: metadata key set to True once a track's existence has passed the confirmation threshold
CONFIRMED = "confirmed"


class ExistenceTrack(Track):
    """A Stone Soup ``Track`` whose metadata receives the values our associators stage (module doc).

    Create it as any track, with the initial existence in its metadata, e.g.
    ``ExistenceTrack([prior], init_metadata={EXISTENCE: 0.5})``."""

    def _update_metadata_from_state(self, state):
        super()._update_metadata_from_state(state)
        staged = self.__dict__.pop("_staged", None)
        if staged:
            self.metadata.update(staged)


def stage(track, **values) -> None:
    """Give ``track`` the values (metadata key -> value) computed for the state about to be appended.

    Parameters
    ----------
    track : Track
        An :class:`ExistenceTrack` (the values land in its metadata when the next state is appended) or any
        track (its metadata is updated now).
    **values
        Metadata key -> value.
    """
    if isinstance(track, ExistenceTrack):
        track.__dict__.setdefault("_staged", {}).update(values)
    else:
        track.metadata.update(values)


def existence_of(track, default=None) -> float:
    """The track's existence probability P(E) after its last state (``default`` when it has none).

    Hypothesisers may be handed a bare state instead of a track (Stone Soup's CompositeHypothesiser does):
    it has no metadata, so ``default`` applies.

    Parameters
    ----------
    track : Track or State
        The track.
    default : float, optional
        Value without one; None: raise :class:`InputError`.

    Returns
    -------
    float
        P(E).
    """
    value = (getattr(track, "metadata", None) or {}).get(EXISTENCE, default)
    if value is None:
        raise InputError(f"track {getattr(track, 'id', track)!r} has no existence probability: create it with "
                         f"init_metadata={{'{EXISTENCE}': p}} (e.g. with ExistenceInitiator)")
    return float(value)

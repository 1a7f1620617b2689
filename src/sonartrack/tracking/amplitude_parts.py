"""Amplitude-aided IPDA for a built position tracker: its measurement and initiator parts swapped for the amplitude
ones (tracking/measurements.py :class:`AmplitudeRangeRateMeasurements`, tracking/initiators.py
:class:`AmplitudeOnePointInitiator`), sharing one :class:`~sonartrack.association.amplitude_ipda.AmplitudeModel`."""

from __future__ import annotations

from dataclasses import fields

from sonartrack.association.amplitude_ipda import AmplitudeModel
from sonartrack.tracking.initiators import AmplitudeOnePointInitiator
from sonartrack.tracking.measurements import AmplitudeRangeRateMeasurements, RangeRatePositionMeasurements
from sonartrack.tracking.settings import PositionTrackerSettings


def amplitude_model_of(settings: PositionTrackerSettings) -> AmplitudeModel:
    """A fresh :class:`AmplitudeModel` from the settings' ``amplitude_*`` fields."""
    s = settings
    return AmplitudeModel(s.amplitude_clutter_prior_mean, s.amplitude_clutter_prior_n, s.amplitude_clutter_scans,
                          s.amplitude_target_prior_ratio, s.amplitude_target_prior_n, s.amplitude_max_ratio)


def with_amplitude(tracker, settings: PositionTrackerSettings):
    """``tracker`` (tracking/configurations.py ``position_tracker``) made amplitude-aided when the settings'
    ``amplitude_aided`` is set (else returned as it is): its position (or range-rate position) measurement part
    becomes :class:`AmplitudeRangeRateMeasurements` with the same fields (a position part: no range rate, factor 1),
    its one-point initiator :class:`AmplitudeOnePointInitiator`; each scan must then give amplitudes
    (``tracker.step(t, z, R, amplitude=...)``).

    Returns
    -------
    MultiTargetTracker
        The same tracker object.
    """
    if not settings.amplitude_aided:
        return tracker
    model = amplitude_model_of(settings)
    m = tracker.measurements
    kept = {f.name: getattr(m, f.name) for f in fields(m) if f.name not in ("model", "target_memory")} \
        if isinstance(m, RangeRatePositionMeasurements) else {"pd": m.pd, "gate_probability": m.gate_probability,
                                                               "clutter_density_per_m2": m.clutter_density_per_m2}
    tracker.measurements = AmplitudeRangeRateMeasurements(**kept, model=model,
                                                          target_memory=settings.amplitude_target_memory)
    i = tracker.initiator
    tracker.initiator = AmplitudeOnePointInitiator(i.velocity_std, i.initial_existence, i.max_tracks, model=model,
                                                   amplitude_start=settings.amplitude_start)
    return tracker

"""Multi-target trackers composed of parts, and the paper trackers as configurations of them.

* settings.py -- the tracker settings, declared once: :class:`PositionTrackerSettings` (IPDA / IMM-IPDA,
  paper P4) and :class:`BearingTrackerSettings` (JPDA / JPDA_A, paper P0);
* multi_target.py -- :class:`MultiTargetTracker`, built from the parts in motion.py, measurements.py,
  associators.py, existence.py, initiators.py and deleters.py; tracks.py holds the stacked track arrays;
* configurations.py -- ``position_tracker(settings)`` and ``bearing_tracker(settings, ...)``;
* run.py -- ``track_contacts`` and ``track_peaks``: a tracker over a whole record, as typed records of arrays.

Nothing is imported here, so ``import sonartrack`` stays fast.
"""

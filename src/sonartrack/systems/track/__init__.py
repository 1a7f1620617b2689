"""The track system: a user's contacts or bearing peaks in, tracks out (``sonartrack track``).

* settings.py -- :class:`ContactsTrackSettings` (IPDA / IMM-IPDA tracker, paper P4, and the contacts' input
  errors) and :class:`PeaksTrackSettings` (JPDA / JPDA_A tracker, paper P0);
* run.py -- :func:`run_contacts` and :func:`run_peaks`: typed records in, typed tracks out;
* files.py -- reads the contacts / peaks files, writes ``tracks.csv`` / ``bearing_tracks.csv``.

Nothing is imported here: ``from sonartrack.systems.track.run import run_contacts``.
"""

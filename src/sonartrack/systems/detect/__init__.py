"""The detect system: a user's range-Doppler frames in, a decision and the best track out (``sonartrack detect``).

* settings.py -- the one settings tree, :class:`~sonartrack.detection.detect.DetectSettings` (normalisation,
  ``[plane]``, ``[detector]``, ``[decision]``; the sound speed once, in ``[plane]``);
* run.py -- :func:`run_detect`: normalise, MFTD (paper P1), decide; :func:`verdict` the one-line decision;
* files.py -- reads the frames file (.npy / .npz), writes ``detection.csv``.

Nothing is imported here: ``from sonartrack.systems.detect.run import run_detect``.
"""

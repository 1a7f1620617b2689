"""Multi-frame track-before-detect (MFTD, Im & Kim 1996, paper P1) on a range-Doppler plane.

One idea per module:

* ``detect``: :func:`detect_frames` (frames -> decision and best track) and its settings
  :class:`DetectSettings` (``sonartrack detect`` runs exactly this);
* ``mftd``: the detector, :class:`MftdDetector` (a plane + :class:`MftdSettings`), and the compiled
  pruned detector ``pruned_detect_fast``; its module doc states the equations;
* ``prior``: the Kalman-predictor track prior (eqs. 16-19, 21);
* ``mftd_reference``: the NumPy references (track weights, exhaustive optimum, pruned detector);
* ``mftd_kernel``: the numba kernel, in named steps;
* ``pruned``: the result record and what the pruned detectors share;
* ``frames``, ``normalise``, ``threshold``: input checks, median normalisation, threshold calibration.

The submodules are imported on use (``from sonartrack.detection.detect import detect_frames``).
"""

"""The detect system's run function: a K x Nr x Nd stack of square-law cells in, a decision out.

:func:`run_detect` is :func:`sonartrack.detection.detect.detect_frames`:

    frames -> normalised to the noise model's median (unless normalisation = "none")
           -> the pruned MFTD statistic S and best tracks on the plane (paper P1, Im & Kim 1996)
           -> S > threshold, the threshold given or calibrated for a Pfa on seeded noise

and :func:`verdict` says the decision in one line.
"""

from __future__ import annotations

import numpy as np

from sonartrack.detection.detect import DetectSettings, FrameDetection, detect_frames


def run_detect(frames: np.ndarray, settings: DetectSettings | None = None) -> FrameDetection:
    """Decide whether a target is present in a stack of range-Doppler frames.

    Parameters
    ----------
    frames : numpy.ndarray, shape (K, Nr, Nd)
        Square-law cell values (powers, >= 0) of K frames of Nr range by Nd Doppler cells.
    settings : DetectSettings, optional
        The system's settings (default: the paper's, with a threshold calibrated for Pfa 0.01).

    Returns
    -------
    FrameDetection
        The decision, the statistic and the threshold (dimensionless log-likelihood ratios), the normalised
        frames, the plane's grid and the best tracks.
    """
    return detect_frames(frames, settings)


def verdict(det: FrameDetection) -> str:
    """The decision in one line: statistic against threshold, the plane, where the best track runs.

    Parameters
    ----------
    det : FrameDetection
        What :func:`run_detect` returned.

    Returns
    -------
    str
        The line, with the best track's first and last cell centres (range m, range rate m/s).
    """
    K, nr, nd = det.frames.shape
    c = det.best_track_centres()
    return (f"{'TARGET PRESENT' if det.present else 'no target'}: statistic {det.statistic:.3f} vs threshold "
            f"{det.threshold:.3f} ({det.threshold_source}); {K} frames of {nr} x {nd} cells; best track from range "
            f"{c[0, 0]:.0f} m, {c[0, 1]:+.2f} m/s to {c[-1, 0]:.0f} m, {c[-1, 1]:+.2f} m/s")

"""Multi-frame detection on a user's frames: normalise, detect (MFTD, paper P1), decide.

:func:`detect_frames` is what ``sonartrack detect`` runs, callable from Python with an array:

    frames (K x Nr x Nd square-law cells)
      -> normalised to the noise model's median (``normalise.py``, unless normalisation = "none")
      -> the pruned MFTD statistic S and best tracks on the plane of ``settings.plane`` (``mftd.py``)
      -> S > threshold, the threshold given or calibrated for a Pfa on seeded noise (``threshold.py``)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from sonartrack.core.settings import Settings, setting
from sonartrack.detection.frames import validate_frames
from sonartrack.detection.mftd import MftdDetector, MftdSettings
from sonartrack.detection.normalise import normalise_frames
from sonartrack.detection.pruned import MftdResult
from sonartrack.detection.threshold import ThresholdSettings, decision_threshold
from sonartrack.models.range_doppler import CwPlaneSettings, RangeDopplerGrid


class DetectSettings(Settings):
    """Settings of multi-frame detection on a user's frames; defaults are the paper's (P1, sec. V)
    and the mftd study's."""

    normalisation: Literal["median", "none"] = setting(
        "median", "scale the cells so their median is a noise cell's, 2 ln 2 ('none': use them as given)", unit="1")
    plane: CwPlaneSettings = setting(default_factory=CwPlaneSettings, doc="cell geometry of the frames")
    detector: MftdSettings = setting(default_factory=MftdSettings, doc="the MFTD detector")
    decision: ThresholdSettings = setting(default_factory=ThresholdSettings, doc="the decision threshold")


@dataclass(frozen=True, slots=True)
class FrameDetection:
    """The decision on one stack of frames: S > threshold, with the best track and what was seen.

    ``frames`` are the cell values the detector saw (normalised); ``mftd`` the detector's result
    (statistic and best tracks, ``tracks[0]`` the best); ``threshold_source`` says where the
    threshold came from ("given", or the Pfa and the number of calibration trials).
    """

    present: bool
    statistic: float
    threshold: float
    threshold_source: str
    frames: np.ndarray
    grid: RangeDopplerGrid
    mftd: MftdResult

    @property
    def best_track(self) -> np.ndarray:
        """(K, 2) [range index, Doppler index] of the best track, frame by frame."""
        return self.mftd.tracks[0]

    def best_track_centres(self) -> np.ndarray:
        """Cell centres of the best track, frame by frame.

        Returns
        -------
        ndarray, shape (K, 2)
            [range (m), range-rate (m/s)].
        """
        best = self.best_track
        return self.grid.centres()[best[:, 0] * self.grid.n_doppler + best[:, 1]]

    def best_track_table(self) -> dict[str, np.ndarray]:
        """The best track as columns, a row per frame (frames numbered from 1): cells, their centres and values.

        Returns
        -------
        dict of str to ndarray, each shape (K,)
            ``frame``, ``range_index``, ``doppler_index``, ``range_m`` (m), ``range_rate_mps`` (m/s) and
            ``cell_value`` (the normalised square-law value the detector saw).
        """
        best, centres = self.best_track, self.best_track_centres()
        K = len(best)
        return {"frame": np.arange(1, K + 1), "range_index": best[:, 0], "doppler_index": best[:, 1],
                "range_m": centres[:, 0], "range_rate_mps": centres[:, 1],
                "cell_value": self.frames[np.arange(K), best[:, 0], best[:, 1]]}


def detect_frames(frames, settings: DetectSettings | None = None) -> FrameDetection:
    """Decide whether a target is present in a stack of square-law cell values (MFTD, paper P1; module docstring).

    The plane is ``settings.plane`` with the frames' Nr x Nd cells; the threshold is settled first
    (a calibration that cannot work fails before the detection runs).

    Parameters
    ----------
    frames : array_like, shape (K, Nr, Nd)
        Square-law cell values (powers, >= 0), frame by frame, range index then Doppler index.
    settings : DetectSettings, optional
        Normalisation, plane geometry, detector and decision; None for the defaults (paper P1, sec. V).

    Returns
    -------
    FrameDetection
        The decision S > threshold, the statistic, the threshold and its source, the normalised frames,
        the plane and the detector's result (best tracks).

    Raises
    ------
    InputError
        If the frames are malformed (see :func:`detection.frames.validate_frames`) or the threshold
        cannot be calibrated.
    """
    settings = DetectSettings() if settings is None else settings
    y = normalise_frames(validate_frames(frames), settings.normalisation)
    grid = settings.plane.grid(y.shape[1], y.shape[2])
    detector = MftdDetector(grid, settings.detector)
    threshold, source = decision_threshold(detector, y.shape, settings.decision)
    res = detector.detect(y, checked=True)
    return FrameDetection(bool(res.statistic > threshold), float(res.statistic), threshold, source, y, grid, res)

"""The detect system's settings: one tree, the detection library's own (detection/detect.py).

``sonartrack detect --print-config`` prints it: ``normalisation`` at the root, ``[plane]`` the cell geometry
(pulse, carrier, the sound speed: declared once, here), ``[detector]`` the MFTD detector (paper P1) and
``[decision]`` the threshold (given, or calibrated for a false-alarm probability). The system overrides no
library default, so the tree is the library's class itself.
"""

from __future__ import annotations

from sonartrack.detection.detect import DetectSettings
from sonartrack.detection.mftd import MftdSettings
from sonartrack.detection.threshold import ThresholdSettings

__all__ = ["DetectSettings", "MftdSettings", "ThresholdSettings"]

"""Frame normalisation: put a user's cell values on the noise model's scale (paper P1, eq. 8).

The detector's design SNR and its log-likelihood weights assume noise-only cells exponential with
mean 2 (eq. 8), whose median is 2 ln 2. A receiver's gain is arbitrary, so by default the frames are
scaled so that their median is 2 ln 2: the median is robust to a target occupying a few cells, and
after it the design SNR means what it says whatever the gain.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.errors import require
from sonartrack.models.swerling import NOISE_MEAN

#: the ways frames can be normalised: by their median, or left as given
NORMALISATIONS = ("median", "none")
#: median of a noise-only square-law cell, exponential with mean 2 (eq. 8): 2 ln 2
NOISE_MEDIAN = NOISE_MEAN * np.log(2.0)


def normalise_to_noise_median(frames) -> np.ndarray:
    """Scale frames so that their median is a noise cell's: ``y * (2 ln 2 / median(y))`` (paper P1, eq. 8).

    Parameters
    ----------
    frames : array_like
        Square-law cell values (any gain).

    Returns
    -------
    ndarray
        Scaled values, on the noise model's scale (noise mean 2).

    Raises
    ------
    InputError
        If the median is 0.
    """
    y = np.asarray(frames, dtype=float)
    med = float(np.median(y))
    require(med > 0, "the median cell value is 0: cannot normalise by it; set normalisation = 'none' and give "
                     "frames on the noise model's scale (noise mean 2)")
    return y * (NOISE_MEAN * np.log(2.0) / med)


def normalise_frames(frames, how: str = "median") -> np.ndarray:
    """Frames normalised ``how``: "median" (:func:`normalise_to_noise_median`) or "none" (as given).

    Parameters
    ----------
    frames : array_like
        Square-law cell values.
    how : {"median", "none"}, default "median"
        Normalisation.

    Returns
    -------
    ndarray of float
        The normalised frames.

    Raises
    ------
    InputError
        If ``how`` is unknown (or as :func:`normalise_to_noise_median`).
    """
    require(how in NORMALISATIONS, f"normalisation must be one of {NORMALISATIONS}, got '{how}'")
    return normalise_to_noise_median(frames) if how == "median" else np.asarray(frames, dtype=float)

"""The decision threshold of a detector: given, or calibrated for a false-alarm probability.

Calibration runs the same detector on ``trials`` noise-only stacks of the frames' shape (cells
exponential with mean 2, eq. 8 of paper P1; stack i drawn from ``trial_rng(seed, i)``, so the
threshold is reproducible) and takes the empirical threshold with at most Pfa * trials of the
noise-only statistics above it (``metrics.roc.thresholds``). It needs Pfa * trials >= 5 exceedances
to mean anything.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.random import trial_rng
from sonartrack.core.settings import Settings, setting
from sonartrack.metrics.roc import thresholds
from sonartrack.models.swerling import sample_cells

#: noise-only exceedances a calibrated threshold needs at least
MIN_CALIBRATION_EXCEEDANCES = 5


class ThresholdSettings(Settings):
    """How the detector decides: a given threshold, or one calibrated for ``pfa`` on seeded noise."""

    threshold: float | None = setting(
        None, "decision threshold on the log statistic S (not set: calibrated for pfa)", unit="1", ge=-1e6,
        le=1e12)
    pfa: float = setting(1e-2, "false-alarm probability of the calibrated threshold", unit="1", gt=0, lt=1)
    calibration_trials: int = setting(2000, "noise-only stacks simulated to calibrate the threshold", unit="1",
                                      ge=10, le=10_000_000)
    seed: int = setting(0, "seed of the calibration's noise-only stacks", unit="1")


def noise_only_statistics(detector, shape, trials: int, seed: int) -> np.ndarray:
    """The detector's statistic on ``trials`` noise-only stacks (cells exponential, mean 2; paper P1, eq. 8).

    Parameters
    ----------
    detector : MftdDetector
        Anything with ``detect(frames, checked=True).statistic``.
    shape : tuple of int
        (K, Nr, Nd) of each stack.
    trials : int
        Number of stacks.
    seed : int
        Master seed; stack i draws from ``trial_rng(seed, i)``.

    Returns
    -------
    ndarray, shape (trials,)
        Statistics.
    """
    return np.array([detector.detect(sample_cells(trial_rng(seed, i), shape), checked=True).statistic
                     for i in range(trials)])


def calibrate_threshold(detector, shape, pfa: float, trials: int, seed: int) -> float:
    """Threshold t with ``P(S > t | noise only) = pfa`` from ``trials`` seeded noise stacks of ``shape``.

    Parameters
    ----------
    detector : MftdDetector
        The detector.
    shape : tuple of int
        (K, Nr, Nd).
    pfa : float
        False-alarm probability.
    trials : int
        Noise-only stacks simulated.
    seed : int
        Master seed.

    Returns
    -------
    float
        Threshold on the statistic S.

    Raises
    ------
    InputError
        If ``pfa * trials`` < 5 (too few exceedances to mean anything).
    """
    require(pfa * trials >= MIN_CALIBRATION_EXCEEDANCES,
            f"pfa {pfa:g} needs at least {int(np.ceil(MIN_CALIBRATION_EXCEEDANCES / pfa))} calibration trials "
            f"(have {trials}): raise calibration_trials or give a threshold")
    return float(thresholds(noise_only_statistics(detector, shape, trials, seed), pfa)[0])


def decision_threshold(detector, shape, settings: ThresholdSettings) -> tuple[float, str]:
    """The decision threshold and its source: the given one, or :func:`calibrate_threshold` for ``settings.pfa``.

    Parameters
    ----------
    detector : MftdDetector
        The detector.
    shape : tuple of int
        (K, Nr, Nd) of the frames.
    settings : ThresholdSettings
        Given threshold, or Pfa, trials and seed for the calibration.

    Returns
    -------
    threshold : float
        Threshold on S.
    source : str
        "given", or the Pfa and the number of calibration trials.
    """
    if settings.threshold is not None:
        return float(settings.threshold), "given"
    t = calibrate_threshold(detector, shape, settings.pfa, settings.calibration_trials, settings.seed)
    return t, f"Pfa {settings.pfa:g} from {settings.calibration_trials} noise-only trials"

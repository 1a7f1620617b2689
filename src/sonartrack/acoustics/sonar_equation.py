"""The passive sonar equation and what follows from it: detection ranges and convergence zones.

    SNR = SL - TL + DI - NL      (dB; Urick, Principles of Underwater Sound, ch. 2; paper P3, eq. 30)

Paper P3's values: SL = 140 dB, NL = 73 dB, DI = 12.5 dB (so SNR = 79.5 - TL).
"""

from __future__ import annotations

import numpy as np

#: paper P3's source level, noise level and directivity index (dB)
SL_DB, NL_DB, DI_DB = 140.0, 73.0, 12.5


def passive_snr_db(sl_db, tl_db, di_db=DI_DB, nl_db=NL_DB):
    """Passive sonar equation ``SNR = SL - TL + DI - NL`` (Urick, ch. 2; paper P3, eq. 30).

    Parameters
    ----------
    sl_db : float or array_like
        Source level (dB re 1 uPa at 1 m).
    tl_db : float or array_like
        Transmission loss (dB).
    di_db : float, default 12.5
        Directivity index (dB; paper P3).
    nl_db : float, default 73.0
        Noise level (dB; paper P3).

    Returns
    -------
    ndarray
        SNR (dB), broadcast over the inputs.
    """
    return np.asarray(sl_db, dtype=float) - np.asarray(tl_db, dtype=float) + di_db - nl_db


def detection_ranges(ranges_m, snr_db, threshold_db: float = 0.0) -> list[tuple[float, float]]:
    """Intervals of range where the SNR exceeds the threshold, in order.

    Parameters
    ----------
    ranges_m : array_like, shape (n,)
        Ranges (m), increasing.
    snr_db : array_like, shape (n,)
        SNR at those ranges (dB).
    threshold_db : float, default 0.0
        Detection threshold (dB).

    Returns
    -------
    list of tuple of float
        (first, last) range of each run of samples above the threshold (m).
    """
    r = np.asarray(ranges_m, dtype=float)
    ok = np.asarray(snr_db, dtype=float) > threshold_db
    if not ok.any():
        return []
    edges = np.diff(np.concatenate([[0], ok.astype(int), [0]]))
    starts, ends = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0] - 1
    return [(float(r[a]), float(r[b])) for a, b in zip(starts, ends, strict=True)]


def convergence_zones(ranges_m, snr_db, threshold_db: float = 0.0,
                      min_gap_m: float = 2_000.0) -> list[tuple[float, float]]:
    """Detection intervals that begin at least ``min_gap_m`` beyond the end of the previous one (the shadow zone).

    The first interval (the direct path) is never a convergence zone.

    Parameters
    ----------
    ranges_m : array_like, shape (n,)
        Ranges (m), increasing.
    snr_db : array_like, shape (n,)
        SNR (dB).
    threshold_db : float, default 0.0
        Detection threshold (dB).
    min_gap_m : float, default 2000.0
        Shortest shadow before a convergence zone (m).

    Returns
    -------
    list of tuple of float
        (first, last) range of each convergence zone (m).
    """
    zones = detection_ranges(ranges_m, snr_db, threshold_db)
    if not zones:
        return []
    out, last_end = [], zones[0][1]
    for a, b in zones[1:]:
        if a - last_end >= min_gap_m:
            out.append((a, b))
        last_end = b
    return out

"""The passive sonar equation and what follows from it: detection ranges and convergence zones.

    SNR = SL - TL + DI - NL      (dB; Urick, Principles of Underwater Sound, ch. 2; paper P3, eq. 30)

Paper P3's values: SL = 140 dB, NL = 73 dB, DI = 12.5 dB (so SNR = 79.5 - TL).
"""

from __future__ import annotations

import numpy as np

#: paper P3's source level, noise level and directivity index (dB)
SL_DB, NL_DB, DI_DB = 140.0, 73.0, 12.5


def passive_snr_db(sl_db, tl_db, di_db=DI_DB, nl_db=NL_DB):
    """SNR = SL - TL + DI - NL (dB), broadcast over arrays."""
    return np.asarray(sl_db, dtype=float) - np.asarray(tl_db, dtype=float) + di_db - nl_db


def detection_ranges(ranges_m, snr_db, threshold_db: float = 0.0) -> list[tuple[float, float]]:
    """Intervals [start, end] (m) of range where SNR exceeds the threshold, in order."""
    r = np.asarray(ranges_m, dtype=float)
    ok = np.asarray(snr_db, dtype=float) > threshold_db
    if not ok.any():
        return []
    edges = np.diff(np.concatenate([[0], ok.astype(int), [0]]))
    starts, ends = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0] - 1
    return [(float(r[a]), float(r[b])) for a, b in zip(starts, ends, strict=True)]


def convergence_zones(ranges_m, snr_db, threshold_db: float = 0.0,
                      min_gap_m: float = 2_000.0) -> list[tuple[float, float]]:
    """Detection intervals that begin after a shadow of at least ``min_gap_m`` beyond the direct path."""
    zones = detection_ranges(ranges_m, snr_db, threshold_db)
    if not zones:
        return []
    out, last_end = [], zones[0][1]
    for a, b in zones[1:]:
        if a - last_end >= min_gap_m:
            out.append((a, b))
        last_end = b
    return out

"""The tma system's files: the bearings and ownship files (and em-map's environment) in, the solution out.

The readers and their checks are io/tma_files.py's (bearings ``time_s, bearing_deg[, frequency_hz, snr_db]``,
ownship ``time_s, x_m, y_m``) and io/environment.py's; ``tma_solution.csv`` holds the columns of
tma/solution_table.py and the bearing noise (:data:`NOISE_COLUMNS`), ``tma_legs.csv`` one row per leg of the
target (tma/leg_solution.py :meth:`~sonartrack.tma.leg_solution.LegSolution.table`), both written atomically. The
tactical picture is report/figures/tma.py's.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from sonartrack.tma.records import BearingRecord, OwnshipTrack
from sonartrack.tma.settings import TmaSettings

if TYPE_CHECKING:
    from sonartrack.acoustics.environment import Environment

CSV_NAME = "tma_solution.csv"
#: the bearing noise, the same on every row: the sd the solution states (given, or estimated from the record) and
#: the residual sd of the record's constant-velocity fit with its 95 % interval (tma/motion_verdict.py; empty when
#: not measured). A stated sd outside that interval is one the record contradicts (unless the fit is rejected:
#: then the residual sd holds the misfit, not the noise)
NOISE_COLUMNS = ("sigma_bearing_deg", "residual_sd_deg", "residual_sd_lo_deg", "residual_sd_hi_deg")
PNG_NAME = "tactical_picture.png"
LEGS_NAME = "tma_legs.csv"


@dataclass(frozen=True, slots=True)
class TmaInputs:
    """What the tma system reads: the bearings record, the ownship track and em-map's environment (or None)."""

    record: BearingRecord
    ownship: OwnshipTrack
    environment: Environment | None = None


def read_tma_inputs(bearings, ownship, settings: TmaSettings) -> TmaInputs:
    """Read and check the bearings and ownship files and, for em-map, the environment of ``settings.batch.env``.

    Parameters
    ----------
    bearings : path-like
        Bearings file (CSV/Parquet): time_s (s), bearing_deg (deg true)[, frequency_hz (Hz), snr_db (dB)].
    ownship : path-like
        Ownship navigation file (CSV/Parquet): time_s (s), x_m, y_m (m).
    settings : TmaSettings
        ``inputs.check_radians`` and, for em-map, ``batch.env``.

    Returns
    -------
    TmaInputs
        The record, the ownship track and the environment (None for sequential methods or without ``env``).
    """
    from sonartrack.io.tma_files import read_bearings, read_ownship
    from sonartrack.systems.tma.run import tma_environment

    record = read_bearings(bearings, check_radians=settings.inputs.check_radians)
    return TmaInputs(record, read_ownship(ownship), tma_environment(settings))


def write_tma_solution(result, out) -> Path:
    """Write the target solution of ``result`` (a TmaResult, what :func:`~sonartrack.systems.tma.run.run_tma`
    returned) as ``tma_solution.csv`` in the output folder ``out``, atomically: the solution table's columns, then
    :data:`NOISE_COLUMNS`; returns the file's path."""
    import numpy as np
    import pandas as pd

    from sonartrack.io.atomic import write_csv
    from sonartrack.tma.solution_table import solution_columns

    frame = pd.DataFrame(solution_columns(result.solution, result.ownship))
    sd = result.bearing_sd
    measured = np.rad2deg([sd.sd_rad, sd.lo_rad, sd.hi_rad]) if sd is not None else [np.nan] * 3
    for name, value in zip(NOISE_COLUMNS, [result.settings.sigma_bearing_deg, *measured], strict=True):
        frame[name] = value
    path = Path(out) / CSV_NAME
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_csv(frame, path, float_format="%.10g")


def write_tma_legs(result, out) -> Path | None:
    """Write a solved record's legs as ``tma_legs.csv`` in ``out``, atomically (one row per leg: span and the zig
    interval that starts it, course and speed with sds, the state at the leg's end with position sds, range and its
    sd, determined and reason, current).

    Parameters
    ----------
    result : TmaResult
        What :func:`~sonartrack.systems.tma.run.run_tma` returned with ``legs=True``.
    out : path-like
        Output folder.

    Returns
    -------
    Path or None
        The file written (None when no legs were fitted: nothing is written).
    """
    import pandas as pd

    from sonartrack.io.atomic import write_csv

    if result.legs is None or not result.legs.legs:
        return None
    path = Path(out) / LEGS_NAME
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_csv(pd.DataFrame(result.legs.table()), path, float_format="%.10g")

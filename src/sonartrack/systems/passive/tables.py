"""The chain's results as tables (what ``sonartrack passive`` writes) and one summary line per target.

targets.csv: one row per target, per TMA method (``ml``: batch ML, paper P3; ``imm-mgekf``: sequential,
paper P2), per time of its record; columns: the target and track ids, the method, the side decision
(side at that time -- it changes where the target crosses the array's axis --, side_log_lr = ln L_starboard -
ln L_port, side_resolved_s), joined_track_ids (the other tracks joined into this target as its fragments, space
separated; empty when none), the solution columns of
tma/solution_table.py (position, velocity, true bearing, range, course, speed and their standard
deviations, range_determined and undetermined_reason -- tma/verdict.py, for the ML and the IMM-MGEKF rows alike;
where the range is not determined, every column but the bearing is left empty, as no number is known there), and
the track's measured tonal frequency (NaN where none).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from sonartrack.tma.solution_table import solution_columns
from sonartrack.tma.verdict import not_determined_text

if TYPE_CHECKING:
    from sonartrack.acoustics.beamforming import BearingTimeRecord
    from sonartrack.systems.passive.chain import PassiveResult
    from sonartrack.systems.passive.targets import Target

TARGET_ID_COLUMNS = ["target_id", "track_id", "method", "side", "side_log_lr", "side_resolved_s",
                     "joined_track_ids"]


def peaks_table(record: BearingTimeRecord):
    """peaks.csv.

    Parameters
    ----------
    record : BearingTimeRecord
        The front end's record.

    Returns
    -------
    pandas.DataFrame
        One row per peak: time_s, cone_deg (the peak's cone angle, deg), amplitude (z).
    """
    import pandas as pd

    p = record.peaks
    return pd.DataFrame({"time_s": p.time_s, "cone_deg": p.bearing_deg, "amplitude": p.amplitude})


#: the columns that mean nothing where the range is not determined: left empty there (a bearing still means something)
RANGE_DEPENDENT_COLUMNS = ("x_m", "y_m", "vx_mps", "vy_mps", "course_deg", "speed_kn", "range_m", "x_std_m",
                           "y_std_m", "vx_std_mps", "vy_std_mps", "course_std_deg", "speed_std_kn", "range_std_m")


def blank_undetermined(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The solution columns with NaN (an empty CSV cell) in the range-dependent columns of undetermined rows.

    Parameters
    ----------
    cols : dict of str to ndarray
        Solution columns (tma/solution_table.py), with ``range_determined``.

    Returns
    -------
    dict of str to ndarray
        The same columns; where ``range_determined`` is False, :data:`RANGE_DEPENDENT_COLUMNS` are NaN.
    """
    det = np.asarray(cols["range_determined"], bool)
    return {k: (np.where(det, v, np.nan) if k in RANGE_DEPENDENT_COLUMNS else v) for k, v in cols.items()}


def _target_rows(target: Target, result_tma):
    import pandas as pd

    sol = result_tma.solution
    cols = blank_undetermined(solution_columns(sol, result_tma.ownship))
    n = len(cols["time_s"])
    tonal = target.tonal
    freq = (np.interp(cols["time_s"], tonal.time_s, tonal.frequency_hz, left=np.nan, right=np.nan)
            if tonal is not None else np.full(n, np.nan))
    head = {"target_id": np.full(n, target.target_id), "track_id": np.full(n, target.track.track_id),
            "method": np.full(n, result_tma.settings.method), "side": target.side.side_at(cols["time_s"]),
            "side_log_lr": np.full(n, target.side.log_likelihood_ratio),
            "side_resolved_s": np.full(n, target.side_resolved_s),
            "joined_track_ids": np.full(n, " ".join(str(i) for i in target.track.joined_track_ids))}
    return pd.DataFrame({**head, **cols, "frequency_hz": freq})


def targets_table(result: PassiveResult):
    """targets.csv (module docstring).

    Parameters
    ----------
    result : PassiveResult
        The chain's result.

    Returns
    -------
    pandas.DataFrame
        The rows of every target's ML and IMM-MGEKF solutions; an empty table with the columns when there is no
        target.
    """
    import pandas as pd

    parts = [_target_rows(tg, r) for tg in result.targets for r in (tg.ml, tg.sequential)]
    if parts:
        return pd.concat(parts, ignore_index=True)
    return pd.DataFrame(columns=TARGET_ID_COLUMNS + ["time_s", "bearing_deg", "range_m", "frequency_hz"])


def target_line(target: Target) -> str:
    """One line about a target.

    Parameters
    ----------
    target : Target
        A target of the chain.

    Returns
    -------
    str
        Side, then the ML solution at the last time (or "range NOT DETERMINED (reason)"), tonal, IMM-MGEKF range
        (or "NOT DETERMINED (reason)": no number for an undetermined range).
    """
    c = {k: v[-1] for k, v in solution_columns(target.ml.solution, target.ml.ownship).items()}
    s = target.side
    crossed = "" if not s.crossings_s else (f", crossed the array's axis at "
                                            f"{', '.join(f'{c:.0f}' for c in s.crossings_s)} s: now {s.final_side}")
    side = (f"{s.side} (ln LR {s.log_likelihood_ratio:+.0f}, from {target.side_resolved_s:.0f} s{crossed})"
            if s.side != "unresolved" else f"side unresolved (ln LR {s.log_likelihood_ratio:+.1f})")
    line = (f"target {target.target_id} (track {target.track.track_id}, {target.track.time_s[0]:.0f}.."
            f"{target.track.time_s[-1]:.0f} s): {side}; at {c['time_s']:.0f} s bearing {c['bearing_deg']:.1f} ± "
            f"{c['bearing_std_deg']:.1f} deg, ")
    if c["range_determined"]:
        line += (f"range {c['range_m'] / 1e3:.2f} ± {c['range_std_m'] / 1e3:.2f} km, course {c['course_deg']:.0f} ± "
                 f"{c['course_std_deg']:.0f} deg, speed {c['speed_kn']:.1f} ± {c['speed_std_kn']:.1f} kn (ML)")
    else:
        line += f"{not_determined_text(c['undetermined_reason'])} by this record (ML)"
    if target.tonal is not None:
        line += f"; tonal {target.tonal.line_hz:.2f} Hz"
    q = {k: v[-1] for k, v in solution_columns(target.sequential.solution, target.sequential.ownship).items()}
    if q["range_determined"]:
        return line + f"; IMM-MGEKF range {q['range_m'] / 1e3:.2f} ± {q['range_std_m'] / 1e3:.2f} km"
    return line + f"; IMM-MGEKF {not_determined_text(q['undetermined_reason'])}"


def summary_lines(result: PassiveResult) -> list[str]:
    """What the command line prints.

    Parameters
    ----------
    result : PassiveResult
        The chain's result.

    Returns
    -------
    list of str
        One line per target (:func:`target_line`), or one line saying that nothing was found.
    """
    if not result.targets:
        extra = f" ({len(result.short_tracks)} confirmed track(s) shorter than min_track_s)" if result.short_tracks \
            else ""
        return [f"passive: no target in {result.duration_s:.0f} s of recording ({len(result.record.peaks.time_s)} "
                f"peaks, no confirmed bearing track long enough for TMA){extra}"]
    return [target_line(t) for t in result.targets]

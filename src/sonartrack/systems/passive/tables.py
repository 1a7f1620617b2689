"""The chain's results as tables (what ``sonartrack passive`` writes) and one summary line per target.

targets.csv: one row per target, per TMA method (``ml``: batch ML, paper P3; ``imm-mgekf``: sequential,
paper P2; ``legs``: the leg-wise ML of a target with a zig, systems/passive/target_legs.py, after every target's ML
and IMM-MGEKF rows), per time of its record; columns: the target and track ids, the method, ``leg`` (the 0-based leg
of the target's legs that the row's time falls in: 0 on every row of a target without a zig), the side decision
(side at that time -- it changes where the target crosses the array's axis --, side_log_lr = ln L_starboard -
ln L_port, side_resolved_s), joined_track_ids (the other tracks joined into this target as its fragments, space
separated; empty when none), the solution columns of
tma/solution_table.py (position, velocity, true bearing, range, course, speed and their standard
deviations, range_determined and undetermined_reason -- tma/verdict.py, for the ML and the IMM-MGEKF rows alike;
where the range is not determined, every column but the bearing is left empty, as no number is known there), and
the track's measured tonal frequency (NaN where none).

Glossary of the parameters: ``result``, the chain's result (:class:`~sonartrack.systems.passive.chain.PassiveResult`);
``record``, the front end's bearing-time record (:class:`~sonartrack.acoustics.beamforming.BearingTimeRecord`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from sonartrack.tma.solution_table import solution_columns
from sonartrack.tma.verdict import bearing_text, not_determined_text

if TYPE_CHECKING:
    from sonartrack.acoustics.beamforming import BearingTimeRecord
    from sonartrack.systems.passive.chain import PassiveResult
    from sonartrack.systems.passive.targets import Target

TARGET_ID_COLUMNS = ["target_id", "track_id", "method", "leg", "side", "side_log_lr", "side_resolved_s",
                     "joined_track_ids"]


def peaks_columns(record: BearingTimeRecord) -> dict[str, np.ndarray]:
    """peaks.csv's columns.

    Returns
    -------
    dict of str to ndarray
        One row per peak: time_s, cone_deg (the peak's cone angle, deg), amplitude (z).
    """
    p = record.peaks
    return {"time_s": np.asarray(p.time_s), "cone_deg": np.asarray(p.bearing_deg), "amplitude": np.asarray(p.amplitude)}


def peaks_table(record: BearingTimeRecord):
    """peaks.csv as a table.

    Returns
    -------
    pandas.DataFrame
        :func:`peaks_columns`.
    """
    import pandas as pd

    return pd.DataFrame(peaks_columns(record))


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


def _target_rows(target: Target, result_tma, method: str | None = None) -> dict[str, np.ndarray]:
    sol = result_tma.solution
    cols = blank_undetermined(solution_columns(sol, result_tma.ownship))
    n = len(cols["time_s"])
    tonal = target.tonal
    freq = (np.interp(cols["time_s"], tonal.time_s, tonal.frequency_hz, left=np.nan, right=np.nan)
            if tonal is not None else np.full(n, np.nan))
    head = {"target_id": np.full(n, target.target_id), "track_id": np.full(n, target.track.track_id),
            "method": np.full(n, method or result_tma.settings.method),
            "leg": target.legs.leg_of(cols["time_s"]) if target.legs is not None else np.zeros(n, int),
            "side": target.side.side_at(cols["time_s"]),
            "side_log_lr": np.full(n, target.side.log_likelihood_ratio),
            "side_resolved_s": np.full(n, target.side_resolved_s),
            "joined_track_ids": np.full(n, " ".join(str(i) for i in target.track.joined_track_ids))}
    return {**head, **cols, "frequency_hz": freq}


def stack_column(parts: list[np.ndarray]) -> np.ndarray:
    """One column of stacked row blocks, of the type a table's concatenation gives it.

    Parameters
    ----------
    parts : list of ndarray
        The blocks' values of the column, in row order.

    Returns
    -------
    ndarray
        Their concatenation: numbers promoted among themselves, booleans kept, anything else (text, or text and
        numbers mixed) as objects -- the types pandas' ``concat`` gives, so that the CSV text is the same.
    """
    kinds = {np.asarray(p).dtype.kind for p in parts}
    if kinds <= set("iuf") or kinds == {"b"}:
        return np.concatenate(parts)
    return np.concatenate([np.asarray(p, dtype=object) for p in parts])


#: targets.csv's columns when there is no target
EMPTY_TARGET_COLUMNS = TARGET_ID_COLUMNS + ["time_s", "bearing_deg", "range_m", "frequency_hz"]


def targets_columns(result: PassiveResult) -> dict[str, np.ndarray]:
    """targets.csv's columns (module docstring).

    Returns
    -------
    dict of str to ndarray
        The rows of every target's ML and IMM-MGEKF solutions, stacked; empty columns
        (:data:`EMPTY_TARGET_COLUMNS`) when there is no target.
    """
    parts = [_target_rows(tg, r) for tg in result.targets for r in (tg.ml, tg.sequential)]
    parts += [_target_rows(tg, tg.legs.result, "legs") for tg in result.targets
              if tg.legs is not None and tg.legs.result is not None]
    if not parts:
        return {c: np.array([], dtype=object) for c in EMPTY_TARGET_COLUMNS}
    return {c: stack_column([p[c] for p in parts]) for c in parts[0]}


def targets_table(result: PassiveResult):
    """targets.csv as a table (module docstring).

    Returns
    -------
    pandas.DataFrame
        :func:`targets_columns`: the rows of every target's ML and IMM-MGEKF solutions; an empty table with the
        columns when there is no target.
    """
    import pandas as pd

    return pd.DataFrame(targets_columns(result))


def _cells(values, float_format: str | None) -> np.ndarray:
    """A column's CSV cells as pandas' ``to_csv`` writes them (``index=False``, ``na_rep=""``): floats as numpy's
    shortest round-trip text (``astype(str)``) or ``float_format % value``, NaN empty; integers and booleans as
    ``astype(str)``; other objects as they are (the csv writer turns them into text), None and NaN empty."""
    v = np.asarray(values)
    if v.dtype.kind == "f":
        text = v.astype(str) if float_format is None else np.array([float_format % x for x in v], dtype=object)
        return np.where(np.isnan(v), "", text).astype(object)
    if v.dtype.kind in "iub":
        return v.astype(str).astype(object)
    out = v.astype(object)
    empty = np.array([x is None or (isinstance(x, float) and x != x) for x in out], dtype=bool)
    out[empty] = ""
    return out


def csv_text(columns: dict[str, np.ndarray], float_format: str | None = None) -> str:
    """A table of equal-length columns as CSV text, byte for byte what pandas' ``DataFrame(columns).to_csv(
    index=False, float_format=...)`` writes (header line, then one line per row; the csv module's minimal
    quoting; ``\\n`` line ends), without importing pandas.

    Parameters
    ----------
    columns : dict of str to array_like
        Column name -> values (n,), in column order.
    float_format : str, optional
        A %-format for float columns (e.g. ``"%.2f"``); None: the shortest text that reads back to the same float.

    Returns
    -------
    str
        The file's text.
    """
    import csv
    import io

    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(list(columns))
    writer.writerows(zip(*(_cells(v, float_format) for v in columns.values()), strict=True))
    return buf.getvalue()


def write_columns_csv(columns: dict[str, np.ndarray], path, float_format: str | None = None) -> Path:
    """Write :func:`csv_text` of ``columns`` atomically to ``path``.

    Parameters
    ----------
    columns : dict of str to array_like
        The table's columns.
    path : str or path-like
        The CSV file.
    float_format : str, optional
        A %-format for the float columns.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    from sonartrack.io.atomic import write_text

    return write_text(path, csv_text(columns, float_format))


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
            f"{target.track.time_s[-1]:.0f} s): {side}; at {c['time_s']:.0f} s "
            f"{bearing_text(c['bearing_deg'], c['bearing_std_deg'])}, ")
    if c["range_determined"]:
        line += (f"range {c['range_m'] / 1e3:.2f} ± {c['range_std_m'] / 1e3:.2f} km, course {c['course_deg']:.0f} ± "
                 f"{c['course_std_deg']:.0f} deg, speed {c['speed_kn']:.1f} ± {c['speed_std_kn']:.1f} kn (ML)")
    else:
        line += f"{not_determined_text(c['undetermined_reason'])} by this record (ML)"
    if target.legs is not None and target.legs.note():
        line += f"; {target.legs.note()}"
    if target.tonal is not None:
        line += f"; tonal {target.tonal.line_hz:.2f} Hz"
    q = {k: v[-1] for k, v in solution_columns(target.sequential.solution, target.sequential.ownship).items()}
    if q["range_determined"]:
        return line + f"; IMM-MGEKF range {q['range_m'] / 1e3:.2f} ± {q['range_std_m'] / 1e3:.2f} km"
    return line + f"; IMM-MGEKF {not_determined_text(q['undetermined_reason'])}"


def summary_lines(result: PassiveResult) -> list[str]:
    """What the command line prints.

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

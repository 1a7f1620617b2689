"""The chain's results as tables (what ``sonartrack passive`` writes) and one summary line per target.

targets.csv: one row per target, per TMA method (``ml``: batch ML, paper P3; ``imm-mgekf``: sequential,
paper P2), per time of its record; columns: the target and track ids, the method, the side decision
(side, side_log_lr = ln L_starboard - ln L_port, side_resolved_s), the solution columns of
tma/solution_table.py (position, velocity, true bearing, range, course, speed and their standard
deviations, range_determined), and the track's measured tonal frequency (NaN where none).
"""

from __future__ import annotations

import numpy as np

from sonartrack.tma.solution_table import solution_columns

TARGET_ID_COLUMNS = ["target_id", "track_id", "method", "side", "side_log_lr", "side_resolved_s"]


def peaks_table(record):
    import pandas as pd

    p = record.peaks
    return pd.DataFrame({"time_s": p.time_s, "cone_deg": p.bearing_deg, "amplitude": p.amplitude})


def _target_rows(target, result_tma):
    import pandas as pd

    sol = result_tma.solution
    cols = solution_columns(sol, result_tma.ownship)
    n = len(cols["time_s"])
    tonal = target.tonal
    freq = (np.interp(cols["time_s"], tonal.time_s, tonal.frequency_hz, left=np.nan, right=np.nan)
            if tonal is not None else np.full(n, np.nan))
    head = {"target_id": np.full(n, target.target_id), "track_id": np.full(n, target.track.track_id),
            "method": np.full(n, result_tma.settings.method), "side": np.full(n, target.side.side),
            "side_log_lr": np.full(n, target.side.log_likelihood_ratio),
            "side_resolved_s": np.full(n, target.side_resolved_s)}
    return pd.DataFrame({**head, **cols, "frequency_hz": freq})


def targets_table(result):
    """targets.csv (module docstring); an empty table with the columns when there is no target."""
    import pandas as pd

    parts = [_target_rows(tg, r) for tg in result.targets for r in (tg.ml, tg.sequential)]
    if parts:
        return pd.concat(parts, ignore_index=True)
    return pd.DataFrame(columns=TARGET_ID_COLUMNS + ["time_s", "bearing_deg", "range_m", "frequency_hz"])


def target_line(target) -> str:
    """One line: side, then the ML solution at the last time (or NOT DETERMINED), tonal, IMM-MGEKF range."""
    c = {k: v[-1] for k, v in solution_columns(target.ml.solution, target.ml.ownship).items()}
    s = target.side
    side = (f"{s.side} (ln LR {s.log_likelihood_ratio:+.0f}, from {target.side_resolved_s:.0f} s)"
            if s.side != "unresolved" else f"side unresolved (ln LR {s.log_likelihood_ratio:+.1f})")
    line = (f"target {target.target_id} (track {target.track.track_id}, {target.track.time_s[0]:.0f}.."
            f"{target.track.time_s[-1]:.0f} s): {side}; at {c['time_s']:.0f} s bearing {c['bearing_deg']:.1f} ± "
            f"{c['bearing_std_deg']:.1f} deg, ")
    if c["range_determined"]:
        line += (f"range {c['range_m'] / 1e3:.2f} ± {c['range_std_m'] / 1e3:.2f} km, course {c['course_deg']:.0f} ± "
                 f"{c['course_std_deg']:.0f} deg, speed {c['speed_kn']:.1f} ± {c['speed_std_kn']:.1f} kn (ML)")
    else:
        line += "range NOT DETERMINED by this record (ML)"
    if target.tonal is not None:
        line += f"; tonal {target.tonal.line_hz:.2f} Hz"
    q = {k: v[-1] for k, v in solution_columns(target.sequential.solution, target.sequential.ownship).items()}
    return line + f"; IMM-MGEKF range {q['range_m'] / 1e3:.2f} ± {q['range_std_m'] / 1e3:.2f} km"


def summary_lines(result) -> list[str]:
    """One line per target, or one line saying that nothing was found."""
    if not result.targets:
        extra = f" ({len(result.short_tracks)} confirmed track(s) shorter than min_track_s)" if result.short_tracks \
            else ""
        return [f"passive: no target in {result.duration_s:.0f} s of recording ({len(result.record.peaks.time_s)} "
                f"peaks, no confirmed bearing track long enough for TMA){extra}"]
    return [target_line(t) for t in result.targets]

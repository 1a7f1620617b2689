"""The passive chain's HTML page (``sonartrack passive`` writes DIR/index.html): the summary lines, the
bearing-time, tactical and LOFAR pictures, one row per target (broadband or narrowband), and the settings used.
Self-contained (figures embedded), written atomically."""

from __future__ import annotations

import html
from pathlib import Path

from sonartrack.core.settings import to_commented_toml
from sonartrack.report.html import _CSS, _img
from sonartrack.tma.solution_table import solution_columns

_HEAD = ("<tr><th>target</th><th>origin</th><th>track / line source</th><th>span (s)</th><th>side</th><th>ln LR</th>"
         "<th>bearing (deg)</th><th>range (km)</th><th>course (deg)</th><th>speed (kn)</th><th>tonal (Hz)</th></tr>")


def _row(tg, narrowband: set[int]) -> str:
    c = {k: v[-1] for k, v in solution_columns(tg.ml.solution, tg.ml.ownship).items()}
    det = bool(c["range_determined"])
    cells = [tg.target_id, "narrowband" if tg.target_id in narrowband else "broadband", tg.track.track_id,
             f"{tg.track.time_s[0]:.0f}..{tg.track.time_s[-1]:.0f}", tg.side.side,
             f"{tg.side.log_likelihood_ratio:+.1f}", f"{c['bearing_deg']:.1f} ± {c['bearing_std_deg']:.1f}",
             f"{c['range_m'] / 1e3:.2f} ± {c['range_std_m'] / 1e3:.2f}" if det else "not determined",
             f"{c['course_deg']:.0f} ± {c['course_std_deg']:.0f}" if det else "-",
             f"{c['speed_kn']:.1f} ± {c['speed_std_kn']:.1f}" if det else "-",
             f"{tg.tonal.line_hz:.2f}" if tg.tonal is not None else "-"]
    return "<tr>" + "".join(f"<td>{html.escape(str(x))}</td>" for x in cells) + "</tr>"


def passive_page(result, lines: list[str], figures: list[Path], inputs: dict[str, str]) -> str:
    """The page's HTML text."""
    narrowband = set(getattr(result, "narrowband_target_ids", None) or ())
    rows = "".join(_row(tg, narrowband) for tg in result.targets)
    table = f"<table>{_HEAD}{rows}</table>" if rows else "<p>No target: no confirmed track long enough for TMA.</p>"
    src = "".join(f"<li>{html.escape(k)}: {html.escape(v)}</li>" for k, v in inputs.items())
    summary = "".join(f"<li>{html.escape(line)}</li>" for line in lines)
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>sonartrack passive</title><style>{_CSS}"
            f"</style></head><body><h1>Passive chain</h1><ul>{src}</ul><h2>Targets</h2><ul>{summary}</ul>{table}"
            "<p class='muted'>Range, course and speed: batch ML (paper P3) on the chosen side's true bearings, 95 % "
            "ellipses; side: ln of the likelihood ratio of the two mirror hypotheses (positive: starboard). A "
            "narrowband target was found by its tonal line alone (LOFAR per beam, lines.csv): its bearings are the "
            "line's, one per integration period.</p>"
            + "".join(_img(p) for p in figures)
            + f"<h2>Settings</h2><pre>{html.escape(to_commented_toml(result.settings))}</pre></body></html>")


def write_passive_page(path, result, lines, figures, inputs) -> Path:
    from sonartrack.io.atomic import write_text

    return write_text(path, passive_page(result, lines, figures, inputs))

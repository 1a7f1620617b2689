"""The passive chain's HTML page (``sonartrack passive`` writes DIR/index.html): a summary line (hours processed,
targets by side, ranges determined), the summary lines per target, the bearing-time, tactical and LOFAR pictures,
one row per target (broadband or narrowband), the settings that differ from the defaults and the whole settings
used. Self-contained (figures embedded), written atomically. The settings as run are also in the page as JSON
(``<script type="application/json" id="sonartrack-settings">``: :func:`read_page_settings`), so that the survey
page can state each recording's settings from its page.
"""

from __future__ import annotations

import html
import json
import re
from pathlib import Path

from sonartrack.core.settings import to_commented_toml
from sonartrack.report.html import _CSS, _img
from sonartrack.report.settings_table import settings_table_html
from sonartrack.tma.solution_table import solution_columns

_HEAD = ("<tr><th>target</th><th>origin</th><th>track / line source</th><th>span (s)</th><th>side</th><th>ln LR</th>"
         "<th>bearing (deg)</th><th>range (km)</th><th>course (deg)</th><th>speed (kn)</th><th>tonal (Hz)</th></tr>")


#: the id of the page's JSON block of the settings as run
SETTINGS_ID = "sonartrack-settings"
_SETTINGS_BLOCK = re.compile(rf'<script type="application/json" id="{SETTINGS_ID}">(.*?)</script>', re.DOTALL)
_SIDES = ("starboard", "port", "unresolved")


def _last(tg) -> dict:
    """The target's ML solution at its last time: the solution table's columns (tma/solution_table.py)."""
    return {k: v[-1] for k, v in solution_columns(tg.ml.solution, tg.ml.ownship).items()}


def summary_line(duration_s: float, sides: list[str], determined: list[bool], narrowband: int) -> str:
    """The page's first line: hours processed, targets by side, ranges determined.

    Parameters
    ----------
    duration_s : float
        The recording processed (s).
    sides : list of str
        Each target's side at its last time (starboard, port, unresolved).
    determined : list of bool
        Whether each target's range is determined at its last time (batch ML; tma/verdict.py).
    narrowband : int
        How many of the targets were found by their tonal lines alone.

    Returns
    -------
    str
        E.g. ``0.08 h processed; 3 targets (1 narrowband): 2 starboard, 1 port; 2 ranges determined``.
    """
    n = len(sides)
    by_side = ", ".join(f"{sides.count(s)} {s}" for s in _SIDES if sides.count(s))
    nb = f" ({narrowband} narrowband)" if narrowband else ""
    what = f"{n} target{'s' if n != 1 else ''}{nb}" + (f": {by_side}" if n else "")
    return f"{duration_s / 3600.0:.2f} h processed; {what}; {sum(determined)} of {n} ranges determined"


def result_summary_line(result) -> str:
    """:func:`summary_line` of a chain's result (sides and ranges at each target's last time)."""
    sides = [str(tg.side.side_at(tg.track.time_s[-1])) for tg in result.targets]
    determined = [bool(_last(tg)["range_determined"]) for tg in result.targets]
    narrowband = len(set(getattr(result, "narrowband_target_ids", None) or ()))
    return summary_line(float(result.duration_s), sides, determined, narrowband)


def settings_block(settings) -> str:
    """The settings as run, as the page's JSON block (module doc)."""
    payload = json.dumps(settings.model_dump(mode="json"), separators=(",", ":")).replace("</", "<\\/")
    return f'<script type="application/json" id="{SETTINGS_ID}">{payload}</script>'


def read_page_settings(path) -> dict | None:
    """The settings as run from a passive page's JSON block (module doc).

    Parameters
    ----------
    path : path
        A page written by :func:`write_passive_page`.

    Returns
    -------
    dict or None
        The settings' values (``model_dump`` JSON); None when the page is missing, unreadable or has no block.
    """
    try:
        m = _SETTINGS_BLOCK.search(Path(path).read_text(encoding="utf-8"))
        return json.loads(m.group(1)) if m else None
    except (OSError, ValueError):
        return None


def _row(tg, narrowband: set[int]) -> str:
    c = _last(tg)
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
            f"</style></head><body><h1>Passive chain</h1><p class='summary'><b>"
            f"{html.escape(result_summary_line(result))}</b></p><ul>{src}</ul><h2>Targets</h2><ul>{summary}</ul>{table}"
            "<p class='muted'>Range, course and speed: batch ML (paper P3) on the chosen side's true bearings, 95 % "
            "ellipses; side: ln of the likelihood ratio of the two mirror hypotheses (positive: starboard). A "
            "narrowband target was found by its tonal line alone (LOFAR per beam, lines.csv): its bearings are the "
            "line's, one per integration period.</p>"
            + "".join(_img(p) for p in figures)
            + f"<h2>Settings that differ from the defaults</h2>{settings_table_html(result.settings)}"
            + f"<details><summary>all settings</summary><pre>{html.escape(to_commented_toml(result.settings))}</pre>"
            + f"</details>{settings_block(result.settings)}</body></html>")


def write_passive_page(path, result, lines, figures, inputs) -> Path:
    from sonartrack.io.atomic import write_text

    return write_text(path, passive_page(result, lines, figures, inputs))

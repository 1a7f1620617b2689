"""The survey page (``sonartrack survey`` writes it): ``OUT/index.html``, opening with a summary line (recordings,
targets, hours processed), then a table of the recordings (status, start, hours, gaps, targets, the reason of a
failure, a link to the recording's own page), a map of every recording's ownship track and the targets it found
with filters by recording and by time, and a table of those targets (report/survey_map_section.py), the chart of
the targets over time (``OUT/survey_targets.png``, report/figures/survey_timeline.py) and the settings that differ
from the defaults in any recording (each read from its own page, report/passive_page.py). The page needs no
network: it works from ``file://``.
"""

from __future__ import annotations

import html
import math
from datetime import UTC, datetime
from pathlib import Path
from urllib.parse import quote

from sonartrack.io.atomic import write_text
from sonartrack.systems.survey.files import read_status, recording_dir, survey_targets

_CSS = """body{font-family:system-ui,sans-serif;margin:2em;color:#222;line-height:1.4}
table{border-collapse:collapse;margin:.5em 0 1em}td,th{border:1px solid #ccc;padding:3px 8px;text-align:left}
th{background:#eef}tr.failed{background:#fee}p.summary{font-size:1.1em}h2{border-bottom:1px solid #ccc;
margin-top:1.8em}img{max-width:100%}"""


def _level(value) -> str:
    """The median broadband level (dB re 1 uPa) as a cell; empty when none was measured."""
    try:
        return f"{float(value):.1f}" if value is not None and value == value else ""
    except (TypeError, ValueError):
        return ""


def _row_html(out: Path, r: dict) -> str:
    page = recording_dir(out, r["name"]) / "index.html"
    name = html.escape(r["name"])
    # a name may hold characters that mean something in an address (# ? %): the link quotes them
    link = f'<a href="recordings/{html.escape(quote(r["name"]))}/index.html">{name}</a>' if page.is_file() else name
    cells = [link, html.escape(str(r["status"])), html.escape(str(r["start_utc"] or "")), f"{r['duration_h']:.3f}",
             f"{r['recorded_h']:.3f}", str(r["gaps"]), _level(r.get("level_db_re_1upa")), str(r["targets"]),
             html.escape(str(r["reason"] or ""))]
    cls = ' class="failed"' if r["status"] == "failed" else ""
    return f"<tr{cls}>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>"


def summary_line(rows: list[dict]) -> str:
    """The page's first line: recordings (ok, failed, not run), targets, hours processed and the UTC span.

    Parameters
    ----------
    rows : list of dict
        systems/survey/files.py ``survey_rows``.

    Returns
    -------
    str
        E.g. ``3 recordings (2 ok, 1 failed); 5 targets; 0.08 h processed (recorded) over 2024-05-17 13:45 to
        14:02 UTC``.
    """
    ok = [r for r in rows if r["status"] == "ok"]
    counts = [f"{len(ok)} ok"] + [f"{n} {s}" for s in ("failed", "not run")
                                  if (n := sum(r["status"] == s for r in rows))]
    n_targets = sum(int(r["targets"] or 0) for r in ok)
    hours = sum(float(r["recorded_h"] or 0.0) for r in ok)
    line = (f"{len(rows)} recording{'s' if len(rows) != 1 else ''} ({', '.join(counts)}); {n_targets} "
            f"target{'s' if n_targets != 1 else ''}; {hours:.2f} h processed (recorded)")
    starts = [(r["start_utc"], r["duration_h"]) for r in ok if r["start_utc"]]
    if starts:
        first = min(datetime.fromisoformat(s).timestamp() for s, _ in starts)
        last = max(datetime.fromisoformat(s).timestamp() + 3600.0 * float(h) for s, h in starts)
        # whole minutes that hold the span: the start rounded down, the end rounded up
        first, last = (datetime.fromtimestamp(60.0 * f(v / 60.0), UTC) for f, v in ((math.floor, first),
                                                                                  (math.ceil, last)))
        line += f" over {first:%Y-%m-%d %H:%M} to {last:%Y-%m-%d %H:%M} UTC"
    return line


def _positions(out: Path, rows: list[dict]) -> list:
    from sonartrack.report.survey_positions import recording_positions

    found = []
    for r in rows:
        status = read_status(out, r["name"]) if r["status"] == "ok" else None
        p = recording_positions(recording_dir(out, r["name"]), status) if status else None
        if p is not None:
            found.append(p)
    return found


def _settings_section(out: Path, rows: list[dict]) -> str:
    """The settings that differ from the defaults in any recording, each read from the recording's page."""
    from sonartrack.report.passive_page import read_page_settings
    from sonartrack.report.settings_table import merged_settings_table_html
    from sonartrack.systems.passive.settings import PassiveSettings

    runs, missing = {}, []
    for r in rows:
        if r["status"] != "ok":
            continue
        values = read_page_settings(recording_dir(out, r["name"]) / "index.html")
        try:
            runs[r["name"]] = PassiveSettings.model_validate(values) if values is not None else None
        except ValueError:  # a page of another version of sonartrack: not compared, said so
            runs[r["name"]] = None
        if runs[r["name"]] is None:
            missing.append(r["name"])
            del runs[r["name"]]
    note = (f"<p class='muted'>Settings not found in the page of: {html.escape(', '.join(missing))}.</p>"
            if missing else "")
    return (merged_settings_table_html(runs) if runs else "<p>No recording's settings to show.</p>") + note


def survey_page(out, rows: list[dict]) -> str:
    """The page's HTML text (module doc); writes the timeline chart ``OUT/survey_targets.png`` beside it.

    Parameters
    ----------
    out : path
        The survey's output folder.
    rows : list of dict
        systems/survey/files.py ``survey_rows``.

    Returns
    -------
    str
        The HTML page.
    """
    from sonartrack.report.figures.survey_timeline import write_targets_timeline
    from sonartrack.report.survey_map_section import map_section

    out = Path(out)
    names = [r["name"] for r in rows if r["status"] == "ok"]
    chart = write_targets_timeline(survey_targets(out, rows), names, {r["name"]: r["start_utc"] for r in rows},
                                   out / "survey_targets.png")
    head = ["recording", "status", "start (UTC)", "span (h)", "recorded (h)", "gaps", "level (dB re 1 uPa)",
            "targets", "reason"]
    body = "\n".join(_row_html(out, r) for r in rows)
    img = f'<p><img src="{chart.name}" alt="targets over time"></p>' if chart else "<p>No target.</p>"
    return f"""<!doctype html>
<html><head><meta charset="utf-8"><title>sonartrack survey</title><style>{_CSS}</style></head>
<body><h1>Survey</h1><p class="summary" id="summary"><b>{html.escape(summary_line(rows))}</b></p>
<h2>Recordings</h2>
<table id="recordings-table"><tr>{''.join(f'<th>{h}</th>' for h in head)}</tr>
{body}
</table>
<h2>Map</h2>
{map_section(_positions(out, rows))}
<h2>Targets over time</h2>
{img}
<h2>Settings that differ from the defaults</h2>
{_settings_section(out, rows)}
<p>Tables: <a href="survey.csv">survey.csv</a>, <a href="survey_targets.csv">survey_targets.csv</a>.</p>
</body></html>
"""


def write_survey_page(out, rows: list[dict]) -> Path:
    """Write ``OUT/index.html`` and its chart (module doc; ``out`` and ``rows`` as :func:`survey_page`'s); returns
    the page's path."""
    return write_text(Path(out) / "index.html", survey_page(out, rows))

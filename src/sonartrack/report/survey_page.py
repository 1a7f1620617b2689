"""The survey page (``sonartrack survey`` writes it): ``OUT/index.html`` with a table of the recordings (status,
start, hours, gaps, targets, the reason of a failure, a link to the recording's own page) and a chart of the
targets over time
(``OUT/survey_targets.png``: one row per recording, a bar per target from its first to its last time, in UTC
when the recording's start is known, else in hours from its start)."""

from __future__ import annotations

import html
from datetime import datetime, timedelta
from pathlib import Path
from urllib.parse import quote

from sonartrack.io.atomic import save_figure, write_text
from sonartrack.systems.survey.files import recording_dir, survey_targets


def _chart(out: Path, rows: list[dict]) -> Path | None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    targets = survey_targets(out, rows)
    if targets.empty:
        return None
    names = [r["name"] for r in rows if r["status"] == "ok"]
    starts = {r["name"]: r["start_utc"] for r in rows}
    utc = all(starts[n] for n in targets["recording"])
    fig, ax = plt.subplots(figsize=(9, 1.2 + 0.45 * len(names)))
    counts = targets.groupby("recording").size()
    for j, (_, t) in enumerate(targets.iterrows()):
        k = j - int(targets.index[targets["recording"] == t["recording"]][0])  # the target's place in its row
        y = names.index(t["recording"]) + 0.6 * ((k + 0.5) / counts[t["recording"]] - 0.5)
        if utc:
            s0 = datetime.fromisoformat(starts[t["recording"]])
            x0, x1 = s0 + timedelta(seconds=float(t["first_s"])), s0 + timedelta(seconds=float(t["last_s"]))
        else:
            x0, x1 = float(t["first_s"]) / 3600.0, float(t["last_s"]) / 3600.0
        ax.plot([x0, x1], [y, y], lw=4, solid_capstyle="butt", alpha=0.8)
        ax.annotate(f"{t['target_id']}", (x1, y), xytext=(3, 0), textcoords="offset points", va="center", fontsize=7)
    ax.set_yticks(range(len(names)), names)
    ax.set_ylim(-0.7, len(names) - 0.3)
    ax.set_xlabel("time (UTC)" if utc else "hours from the recording's start")
    ax.set_title("targets over time (a bar per target, labelled by its id: first to last ML solution)")
    fig.autofmt_xdate() if utc else None
    fig.tight_layout()
    return save_figure(fig, out / "survey_targets.png", dpi=110)


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


def write_survey_page(out, rows: list[dict]) -> Path:
    """Write ``OUT/index.html`` and its chart (module doc); returns the page."""
    out = Path(out)
    chart = _chart(out, rows)
    failed = sum(r["status"] == "failed" for r in rows)
    head = ["recording", "status", "start (UTC)", "span (h)", "recorded (h)", "gaps", "level (dB re 1 uPa)",
            "targets", "reason"]
    body = "\n".join(_row_html(out, r) for r in rows)
    img = f'<p><img src="{chart.name}" alt="targets over time"></p>' if chart else "<p>No target.</p>"
    text = f"""<!doctype html>
<html><head><meta charset="utf-8"><title>sonartrack survey</title>
<style>body{{font-family:sans-serif;margin:2em}} table{{border-collapse:collapse}}
td,th{{border:1px solid #ccc;padding:3px 8px;text-align:left}} tr.failed{{background:#fee}}</style></head>
<body><h1>Survey: {len(rows)} recordings, {failed} failed</h1>
<table><tr>{''.join(f'<th>{h}</th>' for h in head)}</tr>
{body}
</table>
{img}
<p>Tables: <a href="survey.csv">survey.csv</a>, <a href="survey_targets.csv">survey_targets.csv</a>.</p>
</body></html>
"""
    return write_text(out / "index.html", text)

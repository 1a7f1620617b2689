"""The HTML report: one self-contained page, a section per study.

Each section shows the paper, the scenario picture, the claims table (paper vs ours, holds or
not), the other figures and the resolved configuration. Figures are embedded as base64 PNG so the
page can be mailed or archived on its own. The page is written atomically (``io/atomic.py``).
"""

from __future__ import annotations

import base64
import html
import json
from datetime import UTC, datetime
from pathlib import Path

from sonartrack import __version__
from sonartrack.io.atomic import write_text

_CSS = """
body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;color:#222;line-height:1.4}
h1{border-bottom:2px solid #246}h2{margin-top:2.5em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;margin:1em 0;font-size:.92em}
td,th{border:1px solid #ccc;padding:4px 8px;vertical-align:top}
th{background:#eef}.ok{background:#e6f6e6}.no{background:#fbe4e4}
img{max-width:100%;margin:.5em 0;border:1px solid #eee}
pre{background:#f6f6f6;padding:.8em;overflow-x:auto;font-size:.85em}.muted{color:#777}
"""
_CLAIMS_HEADER = "<tr><th>claim</th><th>statement</th><th>paper</th><th>ours</th><th>tolerance</th><th></th></tr>"


def _img(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode()
    return f'<img alt="{html.escape(path.stem)}" src="data:image/png;base64,{data}">'


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return html.escape(str(v))


def _claim_row(c: dict) -> str:
    cells = [html.escape(str(c["id"])), html.escape(str(c["text"])), _fmt(c.get("paper", "")), _fmt(c.get("ours", "")),
             html.escape(str(c.get("tolerance", ""))), "holds" if c.get("holds") else "does not hold"]
    return f'<tr class="{"ok" if c.get("holds") else "no"}">' + "".join(f"<td>{x}</td>" for x in cells) + "</tr>"


def _section(folder: Path) -> str:
    doc = json.loads((folder / "summary.json").read_text())
    claims = doc.get("claims", [])
    held = sum(1 for c in claims if c.get("holds"))
    title = f'{html.escape(doc["title"])} <span class="muted">({doc["study"]})</span>'
    verdict = (f"claims holding: <b>{held}/{len(claims)}</b>" if claims
               else "no claims of its own: it explains another study's claim (see its figures)")
    parts = [f'<h2 id="{doc["study"]}">{title}</h2>',
             f'<p>{html.escape(doc["paper"])} — {doc["runs"]} Monte Carlo runs; {verdict}</p>']
    figs = doc.get("figures", [])
    if "scenario" in figs and (folder / "scenario.png").exists():
        parts.append(_img(folder / "scenario.png"))
    if claims:
        parts.append(f"<table>{_CLAIMS_HEADER}{''.join(_claim_row(c) for c in claims)}</table>")
    parts += [_img(folder / f"{name}.png") for name in figs
              if name != "scenario" and (folder / f"{name}.png").exists()]
    if (folder / "config.toml").exists():
        parts.append("<details><summary>configuration</summary><pre>"
                     f"{html.escape((folder / 'config.toml').read_text())}</pre></details>")
    return "\n".join(parts)


def write_report(out: Path) -> Path:
    """Write ``out/report.html`` from every ``out/<study>/summary.json``; return its path."""
    from sonartrack import studies

    out = Path(out)
    folders = [out / s for s in studies.STUDIES if (out / s / "summary.json").exists()]
    toc = "".join(f'<li><a href="#{f.name}">{f.name}</a></li>' for f in folders)
    body = "\n".join(_section(f) for f in folders) or "<p>No study has been run yet.</p>"
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    page = (f"<!doctype html><html><head><meta charset='utf-8'><title>sonartrack report</title>"
            f"<style>{_CSS}</style></head><body><h1>sonartrack — reproduced studies</h1>"
            f"<p class='muted'>sonartrack {__version__}, {stamp}</p><ul>{toc}</ul>{body}</body></html>")
    return write_text(out / "report.html", page)

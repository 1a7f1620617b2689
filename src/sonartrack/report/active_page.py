"""The active chain's HTML page (``sonartrack active`` writes DIR/index.html): the summary lines, the B-scan and
tactical pictures, one row per confirmed track, the detection and contact counts, and the settings used.
Self-contained (figures embedded), written atomically."""

from __future__ import annotations

import base64
import html
from pathlib import Path

import numpy as np

from sonartrack.core.settings import to_commented_toml
from sonartrack.report.html import _CSS

_HEAD = ("<tr><th>track</th><th>confirmed (s)</th><th>pings</th><th>x (km)</th><th>y (km)</th><th>speed (kn)</th>"
         "<th>course (deg)</th><th>existence</th><th>mode probabilities</th><th>side (ln LR, from s)</th></tr>")


def _side_cell(result, tid: int) -> str:
    """The track's side decision (systems/active/sides.py): side, ln LR and the time it held from."""
    d = result.tracks.sides
    k = None if d is None else d.of(tid)
    if k is None or d.decision[k] == "undecided":
        return "undecided" + ("" if k is None else f" ({d.log_lr[k]:+.1f})")
    ghost = " — this track is its mirror" if d.decision[k] == "mirror" else ""
    return f"{d.side[k]}{ghost} ({d.log_lr[k]:+.1f}, {d.resolved_s[k]:.0f})"


def _rows(result) -> str:
    t = result.tracks.tracks
    out = []
    for tid in dict.fromkeys(t.track_id[t.confirmed].tolist()):
        rows = np.nonzero(t.track_id == tid)[0]
        conf = rows[t.confirmed[rows]]
        k = rows[-1]
        x = t.x[k]
        cells = [tid, f"{t.time_s[conf[0]]:.0f}..{t.time_s[conf[-1]]:.0f}", len(conf),
                 f"{x[0] / 1e3:.2f} ± {t.sd_x_m[k] / 1e3:.2f}", f"{x[1] / 1e3:.2f} ± {t.sd_y_m[k] / 1e3:.2f}",
                 f"{np.hypot(x[2], x[3]) / 0.514444:.1f}", f"{np.rad2deg(np.arctan2(x[2], x[3])) % 360:.0f}",
                 f"{t.existence[k]:.2f}", " / ".join(f"{m:.2f}" for m in t.mode_prob[k]), _side_cell(result, tid)]
        out.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in cells) + "</tr>")
    return "".join(out)


def _embed(name: str, png: bytes) -> str:
    return f'<img alt="{html.escape(name)}" src="data:image/png;base64,{base64.b64encode(png).decode()}">'


def active_page(result, lines: list[str], figures: dict[str, bytes], inputs: dict[str, str]) -> str:
    """The page's HTML text.

    Parameters
    ----------
    result : ActiveResult
        The chain's result.
    lines : list of str
        The summary lines (one per confirmed track).
    figures : dict
        Name -> PNG bytes, embedded in that order.
    inputs : dict
        Input name -> path, listed at the top.

    Returns
    -------
    str
        The HTML page.
    """
    rows = _rows(result)
    table = f"<table>{_HEAD}{rows}</table>" if rows else "<p>No confirmed track.</p>"
    src = "".join(f"<li>{html.escape(k)}: {html.escape(v)}</li>" for k, v in inputs.items())
    summary = "".join(f"<li>{html.escape(line)}</li>" for line in lines)
    counts = (f"{len(result.ping_time_s)} pings; detections: {len(result.single)} single-ping, {len(result.mftd)} "
              f"MFTD; {len(result.contacts)} mirror-pair contacts ({int((~result.gated_out).sum())} kept from the "
              f"tracker by the range-rate gate); the tracker took the {result.settings.detector} detections.")
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>sonartrack active</title><style>{_CSS}"
            f"</style></head><body><h1>Active chain</h1><ul>{src}</ul><p>{html.escape(counts)}</p><h2>Confirmed "
            f"tracks</h2><ul>{summary}</ul>{table}<p class='muted'>Positions: IMM-IPDA (paper P4) on the bistatic "
            "contacts of each detection, both mirror sides, 95 % ellipses; the mirror side's track dies after the "
            "ownship turns.</p>" + "".join(_embed(n, png) for n, png in figures.items())
            + f"<h2>Settings</h2><pre>{html.escape(to_commented_toml(result.settings))}</pre></body></html>")


def write_active_page(path, result, lines, figures, inputs) -> Path:
    """:func:`active_page` written atomically at ``path``."""
    from sonartrack.io.atomic import write_text

    return write_text(path, active_page(result, lines, figures, inputs))

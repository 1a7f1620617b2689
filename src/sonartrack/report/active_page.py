"""The active chain's HTML page (``sonartrack active`` writes DIR/index.html): a summary line, the decided targets
and the undecided mirror pairs in two tables, the B-scan and tactical pictures, the detection and contact counts,
and the settings that differ from the defaults (then all of them). Self-contained (figures embedded), written
atomically.

Targets, not tracks (systems/active/targets.py): a target tracked on both sides of the array before its side is
decided is ONE target with two hypotheses, listed once in the undecided table with both positions and drawn as
two dashed twins; a decided target is listed once with its side, its rejected mirror named as dropped."""

from __future__ import annotations

import base64
import html
from pathlib import Path

import numpy as np

from sonartrack.core.settings import to_commented_toml
from sonartrack.report.html import _CSS
from sonartrack.report.settings_table import settings_table_html

_PAGE_CSS = _CSS + ".summary{font-size:1.1em;background:#eef;padding:.6em;border:1px solid #ccd}" \
                   "tr.pair td{border-top:2px solid #88a}"
_DECIDED_HEAD = ("<tr><th>target</th><th>side</th><th>decided at (s)</th><th>ln LR</th><th>track</th>"
                 "<th>confirmed (s)</th><th>x (km)</th><th>y (km)</th><th>speed (kn)</th><th>course (deg)</th>"
                 "<th>existence</th><th>mode probabilities</th><th>mirror track</th></tr>")
_PAIR_HEAD = ("<tr><th>target</th><th>hypothesis</th><th>track</th><th>x (km)</th><th>y (km)</th>"
              "<th>confirmed (s)</th><th>ln LR</th></tr>")


def _cells(values, cls: str = "") -> str:
    row = "".join(f"<td>{html.escape(str(c))}</td>" for c in values)
    return f'<tr class="{cls}">{row}</tr>' if cls else f"<tr>{row}</tr>"


def _track_cells(t, tid: int) -> list:
    """[confirmed span, x ± sd, y ± sd, speed, course, existence, modes] of a track at its last row."""
    rows = np.nonzero(t.track_id == tid)[0]
    conf = rows[t.confirmed[rows]]
    k = rows[-1]
    x = t.x[k]
    return [f"{t.time_s[conf[0]]:.0f}..{t.time_s[conf[-1]]:.0f}", f"{x[0] / 1e3:.2f} ± {t.sd_x_m[k] / 1e3:.2f}",
            f"{x[1] / 1e3:.2f} ± {t.sd_y_m[k] / 1e3:.2f}", f"{np.hypot(x[2], x[3]) / 0.514444:.1f}",
            f"{np.rad2deg(np.arctan2(x[2], x[3])) % 360:.0f}", f"{t.existence[k]:.2f}",
            " / ".join(f"{m:.2f}" for m in t.mode_prob[k])]


def _decided_rows(result, m) -> str:
    t, out = result.tracks.tracks, []
    for k in np.nonzero(m.decision == "decided")[0]:
        own, mirror = int(m.track_id[k]), int(m.mirror_track_id[k])
        track = _track_cells(t, own) if own >= 0 else ["only its mirror was tracked"] + [""] * 6
        out.append(_cells([m.target[k], m.side[k], f"{m.resolved_s[k]:.0f}", f"{m.log_lr[k]:+.1f}",
                           own if own >= 0 else "", *track, f"{mirror} (dropped)" if mirror >= 0 else ""]))
    return "".join(out)


def _pair_rows(result, m) -> str:
    """Two rows per undecided target, one per hypothesis (a lone track's other hypothesis is its reflection)."""
    t, out = result.tracks.tracks, []
    for k in np.nonzero(m.decision == "undecided")[0]:
        own, mirror = int(m.track_id[k]), int(m.mirror_track_id[k])
        other = "port" if m.track_side[k] == "starboard" else "starboard"
        span = _track_cells(t, own)[0]
        out.append(_cells([m.target[k], m.track_side[k], own, f"{m.xy[k, 0] / 1e3:.2f}", f"{m.xy[k, 1] / 1e3:.2f}",
                           span, f"{m.log_lr[k]:+.1f}"], "pair"))
        out.append(_cells(["", other, mirror if mirror >= 0 else "not tracked (its reflection)",
                           f"{m.mirror_xy[k, 0] / 1e3:.2f}", f"{m.mirror_xy[k, 1] / 1e3:.2f}",
                           _track_cells(t, mirror)[0] if mirror >= 0 else "", ""], "twin"))
    return "".join(out)


def summary_line(result, m, scores: dict | None = None) -> str:
    """The page's first line: targets decided / undecided, held fraction and false targets (when the truth is
    known), run time and its ratio to real time.

    Parameters
    ----------
    result : ActiveResult
        The chain's result.
    m : MirrorTargets
        Its targets (systems/active/targets.py).
    scores : dict, optional
        :func:`~sonartrack.systems.active.targets.truth_scores` (None: no truth).

    Returns
    -------
    str
        One line of text.
    """
    decided = int((m.decision == "decided").sum())
    pairs = int(((m.decision == "undecided") & (m.mirror_track_id >= 0)).sum())
    line = (f"{len(m)} targets: {decided} with the side decided, {len(m) - decided} undecided ({pairs} tracked on "
            f"both sides, shown as mirror pairs)")
    if scores is not None:
        held = ", ".join(f"{n} {100 * v:.0f} %" for n, v in scores["held"].items())
        line += (f"; truth: held {100 * scores['held_all']:.0f} % of target-pings ({held}), "
                 f"{scores['false_targets']} false targets")
    run_s = float(sum(result.stage_seconds.values()))
    if run_s > 0:
        line += f"; {len(result.ping_time_s)} pings in {run_s:.1f} s ({result.duration_s / run_s:.0f}x real time)"
    return line


def _embed(name: str, png: bytes) -> str:
    return f'<img alt="{html.escape(name)}" src="data:image/png;base64,{base64.b64encode(png).decode()}">'


def active_page(result, lines: list[str], figures: dict[str, bytes], inputs: dict[str, str], *, truth=None) -> str:
    """The page's HTML text.

    Parameters
    ----------
    result : ActiveResult
        The chain's result.
    lines : list of str
        The summary lines (systems/active/files.py: a count line, then one per target).
    figures : dict
        Name -> PNG bytes, embedded in that order.
    inputs : dict
        Input name -> path, listed at the top.
    truth : pandas.DataFrame, optional
        A simulated scene's truth (time_s, target, x_m, y_m): held fraction and false targets in the summary line.

    Returns
    -------
    str
        The HTML page.
    """
    from sonartrack.systems.active.targets import mirror_targets, truth_scores

    m = mirror_targets(result.tracks, result.geometry)
    scores = None if truth is None else truth_scores(result.tracks, m, truth, result.geometry)
    decided, pairs = _decided_rows(result, m), _pair_rows(result, m)
    src = "".join(f"<li>{html.escape(k)}: {html.escape(v)}</li>" for k, v in inputs.items())
    counts = (f"{len(result.ping_time_s)} pings; detections: {len(result.single)} single-ping, {len(result.mftd)} "
              f"MFTD; {len(result.contacts)} mirror-pair contacts ({int((~result.gated_out).sum())} kept from the "
              f"tracker by the range-rate gate); the tracker took the {result.settings.detector} detections.")
    body = [f'<h1>Active chain</h1><p class="summary" id="summary">{html.escape(summary_line(result, m, scores))}</p>',
            f"<ul>{src}</ul><p>{html.escape(counts)}</p>",
            "<h2>Decided targets</h2>" + (f'<table class="decided">{_DECIDED_HEAD}{decided}</table>' if decided
                                          else "<p>No target's side was decided.</p>"),
            "<h2>Undecided mirror pairs</h2><p class='muted'>One target, two hypotheses: a line array cannot tell "
            "port from starboard until it turns; each row pair is one target, its position on either side.</p>"
            + (f'<table class="pairs">{_PAIR_HEAD}{pairs}</table>' if pairs else "<p>None.</p>"),
            "<h2>Summary lines</h2><ul>" + "".join(f"<li>{html.escape(line)}</li>" for line in lines) + "</ul>",
            "<p class='muted'>Positions: IMM-IPDA (paper P4) on the bistatic contacts of each detection, both mirror "
            "sides; solid: a decided target with 95 % ellipses; dashed twins: a target's two hypotheses before its "
            "side is decided, joined by a dotted line.</p>",
            "".join(_embed(n, png) for n, png in figures.items()),
            "<h2>Settings that differ from the defaults</h2>" + settings_table_html(result.settings),
            f"<details><summary>All settings</summary><pre>{html.escape(to_commented_toml(result.settings))}</pre>"
            "</details>"]
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>sonartrack active</title><style>{_PAGE_CSS}"
            f"</style></head><body>{''.join(body)}</body></html>")


def write_active_page(path, result, lines, figures, inputs, *, truth=None) -> Path:
    """:func:`active_page` written atomically at ``path``."""
    from sonartrack.io.atomic import write_text

    return write_text(path, active_page(result, lines, figures, inputs, truth=truth))

"""The survey page's map section: the map (report/figures/survey_map.py) inline, a table of the targets, and the
filters over both -- a checkbox per recording and a time window (two sliders) -- run by a small inline script.

Everything is in the page (no file, no address fetched): it works from ``file://`` and offline. The time axis is
UTC when any recording's start is known (a recording whose start is not stays outside the time filter, and is
said so), else hours from each recording's start. Without the script (a reader that runs none) everything shows.
The filters can start from the page's address: ``index.html#recordings=leg1,leg2&from=S&to=S`` (S: seconds on
the time axis from its origin, the earliest start).
"""

from __future__ import annotations

import html
import json
from datetime import datetime, timedelta

import numpy as np

from sonartrack.report.figures.survey_map import recording_color, survey_map_svg

_SCRIPT = """(function(){
var data=JSON.parse(document.getElementById('survey-map-data').textContent);
var boxes=Array.prototype.slice.call(document.querySelectorAll('#rec-filter input.rec'));
var from=document.getElementById('t-from'),to=document.getElementById('t-to');
var rows=Array.prototype.slice.call(document.querySelectorAll('#targets-table tbody tr'));
var nodes=data.elements.map(function(e){return [e,document.getElementById(e.id)];});
function label(s){if(data.mode==='utc'){return new Date((data.origin_epoch_s+Number(s))*1000).toISOString()
.slice(0,19).replace('T',' ')+' UTC';}return (Number(s)/3600).toFixed(2)+' h from each start';}
function shown(on,rec,t0,t1,lo,hi){return on[rec]&&(t0===null||(t1>=lo&&t0<=hi));}
function num(v){return v===''?null:Number(v);}
function apply(){var lo=Number(from.value),hi=Number(to.value);if(lo>hi){var x=lo;lo=hi;hi=x;}
var on={};boxes.forEach(function(b){on[b.getAttribute('data-rec')]=b.checked;});
nodes.forEach(function(p){if(p[1]){p[1].style.display=shown(on,p[0].rec,p[0].t0,p[0].t1,lo,hi)?'':'none';}});
var n=0;rows.forEach(function(r){var v=shown(on,r.getAttribute('data-rec'),num(r.getAttribute('data-t0')),
num(r.getAttribute('data-t1')),lo,hi);r.style.display=v?'':'none';n+=v?1:0;});
document.getElementById('t-from-label').textContent=label(lo);
document.getElementById('t-to-label').textContent=label(hi);
document.getElementById('filter-count').textContent=n+' of '+rows.length+' targets shown';}
var q={};location.hash.slice(1).split('&').forEach(function(p){var kv=p.split('=');
if(kv[0]){q[decodeURIComponent(kv[0])]=decodeURIComponent(kv[1]||'');}});
if(q.recordings!==undefined){var keep=q.recordings.split(',');
boxes.forEach(function(b){b.checked=keep.indexOf(b.getAttribute('data-name'))>=0;});}
if(q.from!==undefined){from.value=q.from;}if(q.to!==undefined){to.value=q.to;}
boxes.concat([from,to]).forEach(function(el){el.addEventListener('input',apply);});
function all(v){return function(){boxes.forEach(function(b){b.checked=v;});apply();};}
document.getElementById('rec-all').addEventListener('click',all(true));
document.getElementById('rec-none').addEventListener('click',all(false));
document.getElementById('t-reset').addEventListener('click',function(){from.value=from.min;to.value=to.max;
apply();});
apply();})();"""

_CSS = """.map svg{max-width:100%;height:auto}
#map-filter fieldset{display:inline-block;vertical-align:top;margin:0 1em 1em 0}
#rec-filter label{display:inline-block;margin-right:1em}.swatch{display:inline-block;width:.9em;height:.9em;
margin:0 .3em;vertical-align:middle;border:1px solid #444}#time-filter input[type=range]{width:22em}
#time-filter output{display:inline-block;min-width:13em;font-family:monospace}.muted{color:#777}"""


def time_axis(recordings) -> tuple[str, datetime | None, list, float]:
    """The survey's time axis (module doc): mode ("utc" or "relative"), its origin (the earliest start), each
    recording's offset on it (s; None: off it), and its span (s)."""
    starts = [r.start_utc for r in recordings]
    known = [s for s in starts if s is not None]
    end = [float(r.time_s[-1]) if r.time_s.size else 0.0 for r in recordings]
    for r, k in zip(recordings, range(len(recordings)), strict=True):
        for tg in r.targets:
            end[k] = max(end[k], float(np.max(tg.time_s)) if tg.time_s.size else 0.0)
    if not known:
        return "relative", None, [0.0] * len(recordings), max(end, default=0.0)
    origin = min(known)
    offsets = [None if s is None else (s - origin).total_seconds() for s in starts]
    span = max((o + e for o, e in zip(offsets, end, strict=True) if o is not None), default=0.0)
    return "utc", origin, offsets, span


def _when(r, t_s: float) -> str:
    if r.start_utc is None:
        return f"{t_s:.0f} s"
    return (r.start_utc + timedelta(seconds=float(t_s))).strftime("%Y-%m-%d %H:%M:%S")


def _position(r, tg) -> str:
    i = np.flatnonzero(tg.determined)
    if not i.size:
        return "range not determined"
    e, n = tg.east[i[-1]], tg.north[i[-1]]
    return f"{n:.5f}, {e:.5f}" if r.frame == "latlon" else f"{e:.2f}, {n:.2f} km (local)"


def _target_rows(recordings, offsets) -> str:
    out = []
    for k, (r, off) in enumerate(zip(recordings, offsets, strict=True)):
        for tg in r.targets:
            t0, t1 = (("", "") if off is None or not tg.time_s.size
                      else (f"{off + tg.time_s[0]:.1f}", f"{off + tg.time_s[-1]:.1f}"))
            cells = [r.name, str(tg.target_id), tg.side, _when(r, tg.time_s[0]), _when(r, tg.time_s[-1]),
                     f"{tg.last_bearing_deg:.1f}", _position(r, tg)]
            out.append(f'<tr data-rec="{k}" data-t0="{t0}" data-t1="{t1}">'
                       + "".join(f"<td>{html.escape(c)}</td>" for c in cells) + "</tr>")
    return "".join(out)


def _controls(recordings, mode: str, span_s: float, offsets) -> str:
    boxes = "".join(f'<label><input type="checkbox" class="rec" data-rec="{k}" '
                    f'data-name="{html.escape(r.name, quote=True)}" checked><span class="swatch" '
                    f'style="background:{recording_color(k)}"></span>{html.escape(r.name)}'
                    f'{" (no UTC start: not filtered by time)" if mode == "utc" and offsets[k] is None else ""}'
                    "</label>" for k, r in enumerate(recordings))
    top = f"{max(span_s, 1.0):.1f}"
    return (f'<div id="map-filter"><fieldset id="rec-filter"><legend>recordings</legend>{boxes}'
            '<button type="button" id="rec-all">all</button> <button type="button" id="rec-none">none</button>'
            f'</fieldset><fieldset id="time-filter"><legend>time window</legend>'
            f'from <input type="range" id="t-from" min="0" max="{top}" step="any" value="0"> '
            '<output id="t-from-label"></output><br>'
            f'to&nbsp;&nbsp;&nbsp; <input type="range" id="t-to" min="0" max="{top}" step="any" value="{top}"> '
            '<output id="t-to-label"></output> <button type="button" id="t-reset">whole survey</button>'
            '</fieldset><p id="filter-count" class="muted"></p></div>')


def map_section(recordings) -> str:
    """The map section's HTML (module doc): filters, the inline SVG map, notes, the targets table, the script.

    Parameters
    ----------
    recordings : list of RecordingPositions
        report/survey_positions.py, one per recording that ran.

    Returns
    -------
    str
        HTML (a paragraph saying so when nothing can be drawn).
    """
    if not recordings:
        return "<p>No recording ran: nothing to draw.</p>"
    mode, origin, offsets, span = time_axis(recordings)
    drawn = survey_map_svg(recordings, offsets, span)
    notes = "".join(f"<li>{html.escape(r.note)}</li>" for r in recordings if r.note)
    data = {"mode": mode, "origin_epoch_s": origin.timestamp() if origin else None,
            "elements": drawn[1] if drawn else []}
    svg = f'<div class="map">{drawn[0]}</div>' if drawn else "<p>No position to draw.</p>"
    head = ("<tr><th>recording</th><th>target</th><th>side</th><th>first ML solution</th><th>last</th>"
            "<th>last bearing (deg)</th><th>last position (lat, lon deg)</th></tr>")
    table = f'<table id="targets-table"><thead>{head}</thead><tbody>{_target_rows(recordings, offsets)}</tbody></table>'
    caption = ("<p class='muted'>Ownship: thick line, a triangle at its start; targets: dashed line of their "
               "recording's colour (batch ML, paper P3, where the range is determined) ending in a circle labelled "
               "with the target's id. A target whose range is not determined has no position: a dotted line marks its "
               "last bearing from the ownship at its last time (its length means nothing).</p>")
    payload = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    return (f"<style>{_CSS}</style>{_controls(recordings, mode, span, offsets)}{svg}{caption}"
            f"{f'<ul>{notes}</ul>' if notes else ''}<h2>Targets</h2>{table}"
            f'<script type="application/json" id="survey-map-data">{payload}</script><script>{_SCRIPT}</script>')

"""The survey's map: every recording's ownship track and its targets' ML positions, drawn as an SVG whose pieces
the page's filters show and hide (by recording and by time).

Each track is cut into pieces of a common duration (:data:`PIECES` over the survey's time span) so that a time
window shows the part of each track inside it; every piece, target mark and label is one SVG group with an id
(``sv-N``) listed with its recording and its time span. Recordings whose navigation gives latitude and longitude
share one panel (equal distances east and north: the aspect is 1 / cos(latitude)); recordings in a local frame of
their own (a navigation table in metres) are drawn on a second panel in km. The ownship is the recording's colour,
thick, a triangle at its start labelled with the recording's name; each target is a thin line of the same colour
ending in a circle labelled with its id; a target whose range is never determined is a dotted line along its last
bearing from the ownship at its last time, labelled "id (bearing)".
"""

from __future__ import annotations

import io
import math
import re

import numpy as np

#: pieces of each track over the survey's whole time span (the time filter's resolution)
PIECES = 60
#: the most points drawn of one line (ownship or target track; a longer one is thinned evenly)
MAX_POINTS = 1500
#: the shortest line of bearing drawn for a target without a position (km)
MIN_STROBE_KM = 2.0
#: the recordings' colours, in turn (matplotlib's tab10)
COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22",
          "#17becf")
_TITLES = {"latlon": "latitude / longitude (WGS84)", "local": "local frames of navigation tables (km)"}
_LABELS = {"latlon": ("longitude (deg)", "latitude (deg)"), "local": ("x east (km)", "y north (km)")}


def recording_color(k: int) -> str:
    """The colour of the k-th recording (cycling through :data:`COLORS`)."""
    return COLORS[k % len(COLORS)]


def _runs(t: np.ndarray, ok: np.ndarray, piece_s: float) -> list[tuple[int, int]]:
    """Index ranges [a, b] (inclusive) of consecutive ``ok`` samples cut where ``t // piece_s`` changes; each piece
    ends on the next piece's first sample, so that the drawn pieces join (a lone sample makes no piece)."""
    good = np.flatnonzero(ok)
    idx = np.floor(t / piece_s)
    out = []
    for run in np.split(good, np.flatnonzero(np.diff(good) != 1) + 1) if good.size else []:
        cuts = np.flatnonzero(np.diff(idx[run]) != 0) + 1
        out += [(int(run[a]), int(run[b])) for a, b in zip(np.r_[0, cuts], np.r_[cuts, run.size - 1], strict=True)
                if b > a]
    return out


class _Elements:
    """The SVG groups drawn so far and their kind (ownship, start, name, target, target-end, target-label,
    bearing, bearing-label), recording, first and last time, for the page's filter."""

    def __init__(self):
        self.items: list[dict] = []

    def add(self, artist, kind: str, rec: int, t0, t1) -> None:
        gid = f"sv-{len(self.items)}"
        artist.set_gid(gid)
        self.items.append({"id": gid, "kind": kind, "rec": rec, "t0": None if t0 is None else round(float(t0), 1),
                           "t1": None if t1 is None else round(float(t1), 1)})


def _strobe_end(rec, tg, length_km: float) -> tuple[float, float, float, float]:
    """From the ownship at the target's last time, ``length_km`` along its last true bearing: (east0, north0, east1,
    north1) in the recording's frame (on a sphere of 6371 km in lat/lon: a drawing aid, not a position)."""
    t = float(tg.time_s[-1])
    e0, n0 = float(np.interp(t, rec.time_s, rec.east)), float(np.interp(t, rec.time_s, rec.north))
    b = math.radians(tg.last_bearing_deg)
    de, dn = length_km * math.sin(b), length_km * math.cos(b)
    if rec.frame == "latlon":
        km_per_deg = math.pi * 6371.0 / 180.0
        de, dn = de / (km_per_deg * max(math.cos(math.radians(n0)), 0.05)), dn / km_per_deg
    return e0, n0, e0 + de, n0 + dn


def _strobe_km(rec) -> float:
    """A bearing line's length: a third of the extent of the recording's ownship and target positions (km), at
    least :data:`MIN_STROBE_KM`."""
    east = np.concatenate([rec.east] + [tg.east[tg.determined] for tg in rec.targets])
    north = np.concatenate([rec.north] + [tg.north[tg.determined] for tg in rec.targets])
    extent = max(float(np.ptp(east)), float(np.ptp(north))) if east.size else 0.0
    if rec.frame == "latlon":
        extent *= math.pi * 6371.0 / 180.0 * max(math.cos(math.radians(float(np.mean(north)))), 0.05)
    return max(extent / 3.0, MIN_STROBE_KM)


def _draw_bearing_only(ax, els: _Elements, k: int, rec, tg, when) -> None:
    """A target whose range is never determined: a dotted line of bearing from the ownship at its last time."""
    e0, n0, e1, n1 = _strobe_end(rec, tg, _strobe_km(rec))
    span = (when(tg.time_s[0]), when(tg.time_s[-1]))
    (line,) = ax.plot([e0, e1], [n0, n1], color=recording_color(k), lw=1.0, ls=":")
    els.add(line, "bearing", k, *span)
    text = ax.annotate(f"{tg.target_id} (bearing)", (e1, n1), xytext=(2, 2), textcoords="offset points", fontsize=7,
                       color=recording_color(k))
    els.add(text, "bearing-label", k, *span)


def _draw_pieces(ax, els: _Elements, tag: tuple, t_s, east, north, ok, timing: tuple, style: dict) -> None:
    """A line (``tag``: kind, recording, time map) in its time pieces (``timing``: the recording's offset and the
    piece length, s), thinned to at most :data:`MAX_POINTS` drawn points (the pieces' ends kept, so they join)."""
    kind, k, when = tag
    step = max(1, math.ceil(int(np.count_nonzero(ok)) / MAX_POINTS))
    for a, b in _runs(t_s + timing[0], ok, timing[1]):
        i = np.unique(np.r_[np.arange(a, b, step), b])
        (line,) = ax.plot(east[i], north[i], **style)
        els.add(line, kind, k, when(t_s[a]), when(t_s[b]))


def _draw_recording(ax, els: _Elements, k: int, rec, offset_s, piece_s: float) -> None:
    color = recording_color(k)
    shift = 0.0 if offset_s is None else offset_s
    when = (lambda t: None) if offset_s is None else (lambda t: t + shift)
    own = {"color": color, "lw": 2.4, "solid_capstyle": "round"}
    _draw_pieces(ax, els, ("ownship", k, when), rec.time_s, rec.east, rec.north, np.ones(rec.time_s.size, bool),
                 (shift, piece_s), own)
    if rec.time_s.size:
        span = (when(rec.time_s[0]), when(rec.time_s[-1]))
        (start,) = ax.plot(rec.east[:1], rec.north[:1], marker="^", ms=8, color=color, mec="k", mew=0.6, ls="none")
        els.add(start, "start", k, *span)
        label = ax.annotate(rec.name, (rec.east[0], rec.north[0]), xytext=(5, 5), textcoords="offset points",
                            fontsize=8, color=color, fontweight="bold")
        els.add(label, "name", k, *span)
    for tg in rec.targets:
        ok = tg.determined
        if not ok.any():
            _draw_bearing_only(ax, els, k, rec, tg, when)
            continue
        _draw_pieces(ax, els, ("target", k, when), tg.time_s, tg.east, tg.north, ok, (shift, piece_s),
                     {"color": color, "lw": 1.0, "ls": "--"})
        i = np.flatnonzero(ok)
        span = (when(tg.time_s[i[0]]), when(tg.time_s[i[-1]]))
        (end,) = ax.plot(tg.east[i[-1]:i[-1] + 1], tg.north[i[-1]:i[-1] + 1], marker="o", ms=6, color=color,
                         mec="k", mew=0.6, ls="none")
        els.add(end, "target-end", k, *span)
        text = ax.annotate(f"{tg.target_id}", (tg.east[i[-1]], tg.north[i[-1]]), xytext=(4, -9),
                           textcoords="offset points", fontsize=7, color=color)
        els.add(text, "target-label", k, *span)


def _frame_axes(ax, frame: str, recs) -> None:
    ax.set_title(_TITLES[frame], fontsize=10)
    ax.set_xlabel(_LABELS[frame][0])
    ax.set_ylabel(_LABELS[frame][1])
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.ticklabel_format(useOffset=False, style="plain")
    if frame == "latlon":
        lat = np.concatenate([r.north for r in recs if r.north.size])
        mid = 0.5 * (float(np.nanmin(lat)) + float(np.nanmax(lat))) if lat.size else 0.0
        ax.set_aspect(1.0 / max(math.cos(math.radians(mid)), 0.05), adjustable="datalim")
    else:
        ax.set_aspect("equal", adjustable="datalim")


def survey_map_svg(recordings: list, offsets_s: list, span_s: float) -> tuple[str, list[dict]] | None:
    """The map (module doc) as SVG text and the list of its filterable groups.

    Parameters
    ----------
    recordings : list of RecordingPositions
        report/survey_positions.py; the k-th is drawn in :func:`recording_color` (k).
    offsets_s : list of float or None
        Each recording's start on the survey's time axis (s); None: not on it (its pieces carry no times).
    span_s : float
        The survey's time span on that axis (s): the pieces are ``span_s / PIECES`` long.

    Returns
    -------
    (str, list of dict) or None
        ``<svg ...>`` text (no XML prolog: for inlining in HTML) and one ``{id, kind, rec, t0, t1}`` per group (t0, t1
        in s on the time axis, None when not on it); None when no recording has a point to draw.
    """
    from matplotlib import rc_context
    from matplotlib.backends.backend_svg import FigureCanvasSVG
    from matplotlib.figure import Figure

    frames = [f for f in ("latlon", "local") if any(r.frame == f and r.time_s.size for r in recordings)]
    if not frames:
        return None
    piece_s = max(span_s / PIECES, 1.0)
    els = _Elements()
    with rc_context({"svg.fonttype": "none", "svg.hashsalt": "sonartrack-survey-map"}):
        fig = Figure(figsize=(6.2 * len(frames) + 0.6, 6.2))
        FigureCanvasSVG(fig)
        axes = fig.subplots(1, len(frames), squeeze=False)[0]
        for ax, frame in zip(axes, frames, strict=True):
            recs = [(k, r) for k, r in enumerate(recordings) if r.frame == frame and r.time_s.size]
            for k, r in recs:
                _draw_recording(ax, els, k, r, offsets_s[k], piece_s)
            _frame_axes(ax, frame, [r for _, r in recs])
        fig.tight_layout()
        buf = io.StringIO()
        fig.savefig(buf, format="svg", metadata={"Date": None})
    text = buf.getvalue()
    # inline: no XML prolog, no RDF metadata block (the page says what the picture is)
    return re.sub(r"\s*<metadata>.*?</metadata>", "", text[text.index("<svg"):], flags=re.DOTALL), els.items

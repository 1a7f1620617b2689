"""Pictures of the passive chain (``sonartrack passive``): the bearing-time record with the tracks on it,
the tactical picture (ownship, array, every target with its 95 % ellipses, rejected mirrors faint) and the LOFAR
gram on each tracked line source's beam (frequency against time, as an operator's LOFAR display)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.report.figures.tma import ellipses

#: the pictures' resolution (dots per inch)
DPI = 110
#: zlib level of the PNG files (1: fastest; lossless at any level)
PNG_COMPRESS_LEVEL = 1
#: white margin kept around the drawing when the picture is cropped to it (inches)
PAD_IN = 0.1


def _figure(size_in: tuple[float, float]):
    """A figure of ``size_in`` inches at :data:`DPI` on its own Agg canvas: no pyplot, so no figure manager to open
    and close and nothing kept after the picture is saved."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size_in, dpi=DPI)
    FigureCanvasAgg(fig)
    return fig


def _save_png(fig, path: Path) -> Path:
    """Draw ``fig`` once and write it as a PNG cropped to its drawing plus :data:`PAD_IN` of white (what a tight
    bounding box gives, which matplotlib gets by drawing the figure twice), atomically.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure of :func:`_figure` (an Agg canvas), on a white background.
    path : path
        The PNG file.

    Returns
    -------
    Path
        ``path``.
    """
    from PIL import Image

    from sonartrack.io.atomic import atomic_path

    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())
    ink = np.any(rgba[..., :3] != 255, axis=2)
    rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    if rows.size:
        pad = int(round(PAD_IN * fig.dpi))
        rgba = rgba[max(rows[0] - pad, 0): rows[-1] + pad + 1, max(cols[0] - pad, 0): cols[-1] + pad + 1]
    with atomic_path(path) as tmp:
        Image.fromarray(np.ascontiguousarray(rgba), "RGBA").save(tmp, format="png", compress_level=PNG_COMPRESS_LEVEL)
    return Path(path)


def bearing_time_picture(result):
    """The bearing-time record with the tracks on it.

    Parameters
    ----------
    result : PassiveResult
        The passive chain's result (systems/passive/chain.py).

    Returns
    -------
    matplotlib.figure.Figure
        Normalised beam level over cone angle (x) and time (y, downwards), the targets' tracks on top (a narrowband
        target's line bearings dashed), the other tracks faint.
    """
    rec = result.record
    fig = _figure((8, 7))
    ax = fig.subplots()
    level = np.asarray(rec.level, float)
    t_end = float(rec.time_s[-1]) if len(rec.time_s) else 1.0
    # saturate at twice the detection threshold: a loud ship would otherwise wash out the weak ones
    top = 2.0 * result.settings.threshold
    ax.imshow(level, aspect="auto", cmap="Greys", origin="upper", vmin=0.0, vmax=top, interpolation="nearest",
              extent=(float(rec.cone_deg[0]), float(rec.cone_deg[-1]), t_end, 0.0))
    nb = set(getattr(result, "narrowband_target_ids", None) or ())
    for tg in result.targets:
        m = tg.track
        kind = ", narrowband" if tg.target_id in nb else ""
        ax.plot(m.track_cone_deg, m.track_time_s, lw=1.6, ls="--" if kind else "-",
                label=f"target {tg.target_id} ({tg.side.side}{kind})")
    trk = result.tracks
    tid = np.asarray(trk.track_id)
    for other in np.setdiff1d(tid, [tg.track.track_id for tg in result.targets]):
        rows = tid == other
        ax.plot(np.asarray(trk.bearing_deg)[rows], np.asarray(trk.time_s)[rows], color="tab:orange", lw=0.6,
                alpha=0.5)
    ax.set(xlabel="cone angle from the array's forward axis (deg)", ylabel="time (s)",
           title=f"bearing-time record ({result.settings.front_end.method}) and bearing tracks")
    if result.targets:
        ax.legend(fontsize=8, loc="lower right")
    return fig


def _plausible(tma_result, min_range_m: float = 500.0) -> bool:
    """A fit worth drawing: range determined throughout and never on top of the array (a wrong side's best
    fit is often a 'target' travelling with the array a few metres away)."""
    from sonartrack.tma.solution_table import solution_columns

    cols = solution_columns(tma_result.solution, tma_result.ownship)
    return bool(tma_result.solution.range_flags().all() and np.min(cols["range_m"]) >= min_range_m)


def _draw_legs(ax, target, color: str) -> bool:
    """A target with a zig drawn by its leg-wise ML (systems/passive/target_legs.py): each leg a segment, the zig
    points marked (open diamonds), 95 % ellipses on the rows whose range is determined, and the label naming the
    legs; True when drawn (its constant-velocity ML, which the zig rejects, is then not drawn)."""
    legs = getattr(target, "legs", None)
    if legs is None or legs.result is None:
        return False
    sol = legs.result.solution
    X, P, det = np.asarray(sol.state), np.asarray(sol.covariance), sol.range_flags()
    k = legs.leg_of(sol.time_s)
    for j in range(int(k.max()) + 1):
        on = (k == j) & det
        ax.plot(X[on, 0] / 1e3, X[on, 1] / 1e3, "-", color=color, lw=1.5,
                label=f"target {target.target_id} ({int(k.max()) + 1} legs)" if j == 0 else None)
    zig_xy, _ = legs.fit.position_at(legs.fit.change_times_s)
    ax.plot(zig_xy[:, 0] / 1e3, zig_xy[:, 1] / 1e3, "D", color=color, ms=7, mfc="none")
    if det[-1]:
        ax.plot(X[-1, 0] / 1e3, X[-1, 1] / 1e3, "^", color=color, ms=8)
    if det.any():
        ellipses(ax, X[det], P[det], 6, color=color, alpha=0.8, label=None)
    return True


def tactical_picture(result):
    """The tactical picture.

    Parameters
    ----------
    result : PassiveResult
        The passive chain's result (its navigation and targets).

    Returns
    -------
    matplotlib.figure.Figure
        Ownship and array tracks, each target's ML track with 95 % ellipses, its rejected mirror faint; a target
        with a zig drawn by its legs instead (:func:`_draw_legs`).
    """
    nav = result.nav
    fig = _figure((8, 8))
    ax = fig.subplots()
    ax.plot(nav.x_m / 1e3, nav.y_m / 1e3, "b-", lw=1.5, label="ownship")
    ax.plot(nav.array_x_m / 1e3, nav.array_y_m / 1e3, "c--", lw=1.0, label="array centre")
    for k, tg in enumerate(result.targets):
        color = f"C{(k + 1) % 10}"
        X, P = np.asarray(tg.ml.solution.state), np.asarray(tg.ml.solution.covariance)
        if _draw_legs(ax, tg, color):
            continue
        if not tg.ml.solution.range_flags()[-1]:
            continue  # an undetermined range would draw a meaningless track; the summary line says so
        ax.plot(X[:, 0] / 1e3, X[:, 1] / 1e3, "-", color=color, lw=1.5, label=f"target {tg.target_id}")
        ax.plot(X[-1, 0] / 1e3, X[-1, 1] / 1e3, "^", color=color, ms=8)
        ellipses(ax, X, P, 6, color=color, alpha=0.8, label=None)
        mirror = tg.mirror_ml
        # the rejected side's fit often runs off to no range at all (it explains nothing): draw it only where
        # its own range is determined, near the picture
        if mirror is not None and tg.side.side != "unresolved" and _plausible(mirror):
            Xm = np.asarray(mirror.solution.state)
            ax.plot(Xm[:, 0] / 1e3, Xm[:, 1] / 1e3, ":", color=color, lw=1.0, alpha=0.35)
    ax.plot([], [], ":", color="0.5", alpha=0.5, label="rejected mirror (other side)")
    if any(getattr(tg, "legs", None) is not None and tg.legs.result is not None for tg in result.targets):
        ax.plot([], [], "D", color="0.3", ms=6, mfc="none", label="zig (leg-wise ML)")
    ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal", title="tactical picture (batch ML, 95 % "
                                                                               "ellipses)")
    ax.legend(fontsize=8, loc="best")
    return fig


#: most LOFAR panels drawn (one per target a line source feeds or became)
MAX_LOFAR_PANELS = 6
#: frequency span drawn each side of a source's line (Hz)
LOFAR_HALF_SPAN_HZ = 25.0


def _lofar_panels(result) -> list[tuple[str, np.ndarray, float | None]]:
    """(title, beam index per period, line frequency Hz or None) per panel: one per target a line source feeds or
    became (the beam nearest the target's cone angle, held before and after its track; its source's strongest
    line's frequency), else the broadside beam over the whole band."""
    gram = result.lofar
    lines = {ln.track_id: ln for ln in result.line_tracks}
    nb = set(result.narrowband_target_ids or ())
    by_id = {tg.target_id: tg for tg in result.targets}
    panels, seen = [], set()
    for src in result.line_sources:
        target = (result.source_targets or {}).get(src.source_id)
        if target is None or target in seen or target not in by_id or len(panels) >= MAX_LOFAR_PANELS:
            continue
        seen.add(target)
        top = max((lines[i] for i in src.track_ids), key=lambda ln: float(np.nanmean(ln.snr_db)))
        m = by_id[target].track
        cone = np.interp(gram.time_s, np.asarray(m.track_time_s, float), np.asarray(m.track_cone_deg, float))
        beams = np.argmin(np.abs(cone[:, None] - np.asarray(gram.cone_deg)[None, :]), axis=1)
        kind = "narrowband" if target in nb else "broadband"
        panels.append((f"target {target} ({kind}): line source {src.source_id}, {top.mean_frequency_hz:.1f} Hz",
                       beams, top.mean_frequency_hz))
    if not panels:
        mid = int(np.argmin(np.abs(np.asarray(gram.cone_deg) - 90.0)))
        panels.append(("no tracked line source: broadside beam", np.full(len(gram.time_s), mid), None))
    return panels


def lofar_picture(result):
    """The LOFAR gram on each tracked source's beam.

    Parameters
    ----------
    result : PassiveResult
        The passive chain's result with its gram (``lofar``) and line sources.

    Returns
    -------
    matplotlib.figure.Figure
        Per panel: the normalised statistic z (dB) over frequency (x) and time (y, downwards) on the beam that
        follows the target, +-``LOFAR_HALF_SPAN_HZ`` around its source's line.
    """
    gram = result.lofar
    panels = _lofar_panels(result)
    fig = _figure((4.2 * len(panels), 6))
    axes = fig.subplots(1, len(panels), squeeze=False)
    f = np.asarray(gram.freqs_hz, float)
    period = float(gram.time_s[1] - gram.time_s[0]) if len(gram.time_s) > 1 else 2.0 * float(gram.time_s[0])
    for ax, (title, beams, line_hz) in zip(axes[0], panels, strict=True):
        keep = np.ones(len(f), bool) if line_hz is None else np.abs(f - line_hz) <= LOFAR_HALF_SPAN_HZ
        z = np.asarray(gram.statistic, float)[np.arange(len(beams)), beams][:, keep]
        ax.imshow(10.0 * np.log10(np.maximum(z, 1e-3)), aspect="auto", cmap="viridis", origin="upper", vmin=0.0,
                  vmax=12.0, interpolation="nearest",
                  extent=(float(f[keep][0]), float(f[keep][-1]), float(gram.time_s[-1]) + period / 2, 0.0))
        ax.set(xlabel="frequency (Hz)", title=title)
        ax.title.set_fontsize(9)
    axes[0, 0].set_ylabel("time (s)")
    fig.suptitle("LOFAR: line over background, 10 log10 z (0-12 dB), on the target's beam", fontsize=10)
    return fig


def write_passive_figures(result, out) -> list[Path]:
    """Draw and save the chain's pictures.

    Parameters
    ----------
    result : PassiveResult
        The passive chain's result.
    out : path
        The output folder.

    Returns
    -------
    list of Path
        bearing_time.png, tactical.png and, when the narrowband pass made a gram, lofar.png in ``out``, saved
        atomically.
    """
    out = Path(out)
    figures = [("bearing_time.png", bearing_time_picture), ("tactical.png", tactical_picture)]
    if getattr(result, "lofar", None) is not None:
        figures.append(("lofar.png", lofar_picture))
    return [_save_png(draw(result), out / name) for name, draw in figures]

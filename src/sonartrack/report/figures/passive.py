"""Pictures of the passive chain (``sonartrack passive``): the bearing-time record with the tracks on it,
and the tactical picture (ownship, array, every target with its 95 % ellipses, rejected mirrors faint)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.io.atomic import save_figure
from sonartrack.report.figures.tma import ellipses


def bearing_time_picture(result):
    """The bearing-time record with the tracks on it.

    Parameters
    ----------
    result : PassiveResult
        The passive chain's result (systems/passive/chain.py).

    Returns
    -------
    matplotlib.figure.Figure
        Normalised beam level over cone angle (x) and time (y, downwards), the targets' tracks on top, the other
        tracks faint.
    """
    import matplotlib.pyplot as plt

    rec = result.record
    fig, ax = plt.subplots(figsize=(8, 7))
    level = np.asarray(rec.level, float)
    t_end = float(rec.time_s[-1]) if len(rec.time_s) else 1.0
    # saturate at twice the detection threshold: a loud ship would otherwise wash out the weak ones
    top = 2.0 * result.settings.threshold
    ax.imshow(level, aspect="auto", cmap="Greys", origin="upper", vmin=0.0, vmax=top, interpolation="nearest",
              extent=(float(rec.cone_deg[0]), float(rec.cone_deg[-1]), t_end, 0.0))
    for tg in result.targets:
        m = tg.track
        ax.plot(m.track_cone_deg, m.track_time_s, lw=1.6, label=f"target {tg.target_id} ({tg.side.side})")
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


def tactical_picture(result):
    """The tactical picture.

    Parameters
    ----------
    result : PassiveResult
        The passive chain's result (its navigation and targets).

    Returns
    -------
    matplotlib.figure.Figure
        Ownship and array tracks, each target's ML track with 95 % ellipses, its rejected mirror faint.
    """
    import matplotlib.pyplot as plt

    nav = result.nav
    fig, ax = plt.subplots(figsize=(8, 8))
    ax.plot(nav.x_m / 1e3, nav.y_m / 1e3, "b-", lw=1.5, label="ownship")
    ax.plot(nav.array_x_m / 1e3, nav.array_y_m / 1e3, "c--", lw=1.0, label="array centre")
    for k, tg in enumerate(result.targets):
        color = f"C{(k + 1) % 10}"
        X, P = np.asarray(tg.ml.solution.state), np.asarray(tg.ml.solution.covariance)
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
    ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal", title="tactical picture (batch ML, 95 % "
                                                                               "ellipses)")
    ax.legend(fontsize=8, loc="best")
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
        bearing_time.png and tactical.png in ``out``, saved atomically.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out)
    paths = []
    for name, fig in (("bearing_time.png", bearing_time_picture(result)), ("tactical.png", tactical_picture(result))):
        paths.append(save_figure(fig, out / name, dpi=110, bbox_inches="tight"))
        plt.close(fig)
    return paths

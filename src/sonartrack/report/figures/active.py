"""Pictures of the active chain (``sonartrack active``): range-bearing B-scans of pings with their detections,
and the tactical picture (PPI: ownship, source, array, the targets: decided tracks with 95 % ellipses, undecided
mirror pairs as dashed twins)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.io.atomic import save_figure


def _bscan_pings(n: int, shown: int) -> list[int]:
    """Indices of ``shown`` pings spread over ``n`` (first, last and between)."""
    return sorted(set(np.linspace(0, n - 1, min(shown, n)).round().astype(int).tolist())) if n else []


def bscan_picture(result, shown: int = 4):
    """B-scans of ``shown`` pings spread over the record: normalised level over cone angle (x) and bistatic range
    c t (y, km), single-ping (+) and MFTD (o) detections of that ping on top (Figure)."""
    import matplotlib.pyplot as plt

    b = result.bscan
    idx = _bscan_pings(len(b.time_s), shown)
    fig, axes = plt.subplots(1, max(len(idx), 1), figsize=(4.2 * max(len(idx), 1), 6), squeeze=False, sharey=True)
    c_km = result.settings.sound_speed_mps / 1e3
    thr_db = 10 * np.log10(max(float(b.level.max(initial=1.0)), 1.0))
    for ax, k in zip(axes[0], idx, strict=False):
        level_db = 10 * np.log10(np.maximum(b.level[k], 1e-3))
        extent = (float(b.cone_deg[0]), float(b.cone_deg[-1]), float(b.travel_time_s[-1] * c_km),
                  float(b.travel_time_s[0] * c_km))
        ax.imshow(level_db.T, aspect="auto", cmap="Greys", vmin=0.0, vmax=max(thr_db, 10.0), extent=extent,
                  interpolation="nearest")
        ping_no = result.single.ping[result.single.time_s == b.time_s[k]]
        for det, marker, color, name in ((result.single, "+", "tab:red", "single-ping"),
                                         (result.mftd, "o", "tab:blue", "MFTD")):
            m = det.time_s == b.time_s[k]
            style = {"c": color} if marker == "+" else {"facecolors": "none", "edgecolors": color}
            ax.scatter(det.cone_deg[m], det.travel_time_s[m] * c_km, marker=marker, s=18, lw=0.8, label=name, **style)
        ax.set(xlabel="cone angle (deg, 0 = ahead)", title=f"ping at {b.time_s[k]:.0f} s"
               + (f" (#{int(ping_no[0])})" if len(ping_no) else ""))
    axes[0][0].set_ylabel("bistatic range c t (km)")
    axes[0][0].legend(fontsize=8, loc="lower right")
    fig.suptitle("B-scans: normalised matched-filter level (dB), detections")
    return fig


def _confirmed_rows(t, tid: int) -> np.ndarray:
    return np.nonzero((t.track_id == tid) & t.confirmed)[0] if tid >= 0 else np.zeros(0, np.int64)


def _draw_target(ax, result, targets, k: int, color: str) -> None:
    """One target (systems/active/targets.py): each hypothesis dashed while the side is undecided, the target's
    track solid from the ping its side was decided on with 95 % ellipses and a triangle at its last position, the
    two hypotheses joined by a dotted line at that ping (or at their last common ping, undecided)."""
    from sonartrack.report.figures.tma import ellipses

    t, P = result.tracks.tracks, result.tracks.P
    when = float(targets.resolved_s[k])
    decided = targets.decision[k] == "decided"
    own, mirror = _confirmed_rows(t, int(targets.track_id[k])), _confirmed_rows(t, int(targets.mirror_track_id[k]))
    name = f"target {targets.target[k]}"
    for rows, main in ((own, True), (mirror, False)):
        if not len(rows):
            continue
        X = t.x[rows] / 1e3
        before = t.time_s[rows] <= when if decided and main else np.ones(len(rows), bool)
        undecided_label = f"{name} (undecided: both hypotheses)" if main and not decided else None
        ax.plot(X[before, 0], X[before, 1], "--", color=color, lw=1.0, alpha=0.8 if main else 0.5,
                label=undecided_label)
        if (~before).any():
            ax.plot(X[~before, 0], X[~before, 1], "-", color=color, lw=1.5, label=f"{name} ({targets.side[k]})")
            ellipses(ax, t.x[rows[~before]], P[rows[~before]], 5, color=color, alpha=0.8, label=None)
        ax.plot(X[-1, 0], X[-1, 1], "x" if decided and not main else "^", color=color, ms=7 if main else 5)
    _join(ax, t, own, mirror, when if decided else None, color)


def _join(ax, t, own, mirror, when: float | None, color: str) -> None:
    """A dotted line between the two hypotheses at the decision ping (or their last common ping)."""
    if not (len(own) and len(mirror)):
        return
    common = np.intersect1d(t.time_s[own], t.time_s[mirror])
    if not len(common):
        return
    at = common[-1] if when is None else common[np.argmin(np.abs(common - when))]
    a, b = own[t.time_s[own] == at][0], mirror[t.time_s[mirror] == at][0]
    ax.plot([t.x[a, 0] / 1e3, t.x[b, 0] / 1e3], [t.x[a, 1] / 1e3, t.x[b, 1] / 1e3], ":", color=color, lw=1.0)


def tactical_picture(result, nav, targets=None):
    """Ownship, source and array tracks and every target (Figure): a decided target's track solid from its
    decision with 95 % ellipses, an undecided mirror pair as two dashed twins of one colour joined by a dotted
    line (one target, two hypotheses), a decided target's hypotheses before its decision dashed (its rejected
    mirror fading, x at its end)."""
    import matplotlib.pyplot as plt

    from sonartrack.systems.active.targets import mirror_targets

    m = mirror_targets(result.tracks, result.geometry) if targets is None else targets
    fig, ax = plt.subplots(figsize=(8, 8))
    ax.plot(nav.own_xy[:, 0] / 1e3, nav.own_xy[:, 1] / 1e3, "b-", lw=1.5, label="ownship")
    ax.plot(nav.source_xy[:, 0] / 1e3, nav.source_xy[:, 1] / 1e3, "m:", lw=1.0, label="source")
    ax.plot(nav.array_xy[:, 0] / 1e3, nav.array_xy[:, 1] / 1e3, "c--", lw=1.0, label="array centre")
    for k in range(len(m)):
        _draw_target(ax, result, m, k, f"C{(k + 1) % 10}")
    ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal",
           title="tactical picture: targets (solid: side decided, 95 % ellipses; dashed twins: both hypotheses)")
    ax.legend(fontsize=8, loc="best")
    return fig


def figure_png(fig) -> bytes:
    """A figure as PNG bytes (closed afterwards)."""
    import io

    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=100, bbox_inches="tight")
    finally:
        plt.close(fig)
    return buf.getvalue()


def active_pngs(result, nav) -> dict[str, bytes]:
    """bscan.png and tactical.png as bytes (name -> PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    return {"bscan.png": figure_png(bscan_picture(result)), "tactical.png": figure_png(tactical_picture(result, nav))}


def write_active_figures(result, nav, out) -> list[Path]:
    """bscan.png and tactical.png in ``out``, saved atomically.

    Parameters
    ----------
    result : ActiveResult
        The chain's result (systems/active/run.py).
    nav : ActiveNav
        The navigation (ownship, source, array).
    out : str or path-like
        The folder.

    Returns
    -------
    list of Path
        The two files.
    """
    import matplotlib

    matplotlib.use("Agg")
    out = Path(out)
    return [save_figure(bscan_picture(result), out / "bscan.png", dpi=100, bbox_inches="tight"),
            save_figure(tactical_picture(result, nav), out / "tactical.png", dpi=100, bbox_inches="tight")]


def _bars(ax, summary: dict, key: str, ylabel: str) -> None:
    """Grouped bars (targets x variants) of a [mean, low, high] summary entry, with the interval as error bars."""
    targets, variants = summary["targets"], summary["variants"]
    width = 0.8 / len(variants)
    x = np.arange(len(targets))
    for j, v in enumerate(variants):
        vals = np.array([[np.nan if e is None else float(e) for e in summary[key][v][n]] for n in targets])
        err = np.abs(vals[:, 1:] - vals[:, :1]).T
        ax.bar(x + (j - (len(variants) - 1) / 2) * width, vals[:, 0], width, yerr=np.nan_to_num(err), capsize=2,
               label=v.replace("_", " "))
    ax.set_xticks(x, targets)
    ax.set(ylabel=ylabel)


def figures(summary: dict, config) -> dict:
    """The active-chain study's pictures: holding and CTT after the turn per target and tracking, and the position
    RMSE against the tracks' own sd after the turn (study active-chain)."""
    import matplotlib.pyplot as plt

    fig1, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    _bars(axes[0], summary, "hold", "fraction of pings held by a confirmed track")
    _bars(axes[1], summary, "ctt_after", "CTT rate after the ownship turn")
    axes[0].legend(fontsize=8)
    fig1.suptitle(f"active chain: {summary['runs']} runs; bars: mean, 95 % interval over runs")
    fig2, ax = plt.subplots(figsize=(7, 4.5))
    targets, variants = summary["targets"], summary["variants"]
    for j, v in enumerate(variants):
        rm = [np.nan if summary["rmse_after_m"][v][n] is None else summary["rmse_after_m"][v][n] for n in targets]
        sd = [np.nan if summary["sd_after_m"][v][n] is None else summary["sd_after_m"][v][n] for n in targets]
        ax.plot(np.arange(len(targets)) + 0.05 * j, rm, "o", color=f"C{j}", label=f"{v.replace('_', ' ')} RMSE")
        ax.plot(np.arange(len(targets)) + 0.05 * j, sd, "_", ms=14, color=f"C{j}")
    ax.set_xticks(np.arange(len(targets)), targets)
    ax.set(ylabel="position error after the turn (m)", title="RMSE (o) and the tracks' own RMS sd (-)")
    ax.legend(fontsize=8)
    return {"holding": fig1, "accuracy": fig2}

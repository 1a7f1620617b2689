"""TMA pictures for the command line: the tactical picture of a solved record, with the target's legs."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.io.atomic import save_figure

#: chi-square(2) 95 % quantile: the 95 % position ellipse is sqrt(5.991) standard deviations wide
CHI2_2DOF_95 = 5.991


def _bearing_lines(ax, record, ownship, length_m: float, n_lines: int = 40) -> None:
    """About ``n_lines`` measured bearing lines from the ownship, each ``length_m`` long (km axes)."""
    op = ownship.position_at(record.time_s)
    for k in range(0, len(record.time_s), max(1, len(record.time_s) // n_lines)):
        b = record.bearing_rad[k]
        ax.plot([op[k, 0] / 1e3, (op[k, 0] + length_m * np.sin(b)) / 1e3],
                [op[k, 1] / 1e3, (op[k, 1] + length_m * np.cos(b)) / 1e3], color="0.8", lw=0.6, zorder=1)
    ax.plot([], [], color="0.8", lw=0.6, label="measured bearings")


def ellipses(ax, state, covariance, n_ellipses: int, color: str = "r", alpha: float = 0.7,
             label: str | None = "95 % position ellipses") -> None:
    """95 % position ellipses (km axes) at ``n_ellipses`` evenly spread rows of ``state`` / ``covariance``."""
    from matplotlib.patches import Ellipse

    X, P = np.asarray(state, float), np.asarray(covariance, float)
    k95 = np.sqrt(CHI2_2DOF_95)
    idx = np.unique(np.linspace(0, len(X) - 1, n_ellipses).round().astype(int)) if n_ellipses > 0 else []
    for j, k in enumerate(idx):
        w, V = np.linalg.eigh(P[k, :2, :2])
        if not np.all(np.isfinite(w)):
            continue
        w = np.maximum(w, 0.0)
        angle_deg = np.degrees(np.arctan2(V[1, 1], V[0, 1]))
        ax.add_patch(Ellipse((X[k, 0] / 1e3, X[k, 1] / 1e3), 2 * k95 * np.sqrt(w[1]) / 1e3,
                             2 * k95 * np.sqrt(w[0]) / 1e3, angle=angle_deg, fill=False, color=color, lw=0.8,
                             alpha=alpha, zorder=2, label=label if j == 0 else None))


def draw_legs(ax, legs) -> int:
    """The target's determined legs (tma/leg_solution.py ``LegSolution``): each leg's track in its own colour, a
    diamond at each zig, the current leg's 95 % ellipse at the last time. Returns how many legs were drawn."""
    fit = None if legs is None or legs.report is None else legs.report.legs
    if fit is None:
        return 0
    colours = ["tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan"]
    drawn, zig_label = 0, "zig"
    for k, leg in enumerate(fit.legs):
        if not leg.determined:
            continue
        xy, _ = fit.position_at(np.linspace(leg.start_s, leg.end_s, 50))
        ax.plot(xy[:, 0] / 1e3, xy[:, 1] / 1e3, "-", color=colours[k % len(colours)], lw=2.0, zorder=3,
                label=f"leg {k + 1}: {leg.course_deg:03.0f} deg, {leg.speed_kn:.1f} kn")
        if k:
            ax.plot(xy[0, 0] / 1e3, xy[0, 1] / 1e3, "kD", ms=5, zorder=4, label=zig_label)
            zig_label = None
        drawn += 1
    last = fit.legs[-1]
    if last.determined:
        ellipses(ax, last.state[None], last.state_cov[None], 1, color="k", label="current leg, 95 % ellipse")
    return drawn


def tactical_picture(record, ownship, solution, n_ellipses: int = 8, title: str = "TMA", legs=None):
    """Ownship track, measured bearing lines, estimated target track and its 95 % position ellipses, and the
    target's determined legs when ``legs`` is given (Figure).

    Only the rows whose range is determined (``solution.range_flags()``) are drawn: a diverged, unobservable or
    otherwise undetermined position is not a position, so where no row is determined the picture shows the
    bearings (and the legs that are determined) and says why in its title."""
    import matplotlib.pyplot as plt

    ok = solution.range_flags() & np.all(np.isfinite(np.asarray(solution.state, float)), axis=1)
    X = np.asarray(solution.state, float)[ok]
    fig, ax = plt.subplots(figsize=(7, 7))
    est_range = list(np.hypot(*(X[:, :2] - ownship.position_at(np.asarray(solution.time_s)[ok])).T)) if ok.any() \
        else []
    est_range += [leg.range_m for leg in (legs.legs if legs is not None else ()) if leg.determined]
    length = 1.3 * float(np.max(est_range)) if len(est_range) else 10_000.0
    _bearing_lines(ax, record, ownship, length)
    ax.plot(np.asarray(ownship.x_m) / 1e3, np.asarray(ownship.y_m) / 1e3, "b-", lw=1.5, label="ownship", zorder=3)
    ax.plot(ownship.x_m[0] / 1e3, ownship.y_m[0] / 1e3, "bo", zorder=3)
    if ok.any():
        ax.plot(X[:, 0] / 1e3, X[:, 1] / 1e3, "r-", lw=1.5, label="target (estimated)", zorder=3)
        ax.plot(X[-1, 0] / 1e3, X[-1, 1] / 1e3, "r^", ms=8, zorder=4)
        ellipses(ax, X, np.asarray(solution.covariance, float)[ok], n_ellipses)
    n_legs = draw_legs(ax, legs)
    if not ok.any():
        reasons = solution.undetermined_reason
        why = sorted({str(r) for r in reasons if str(r)}) if reasons is not None else []
        title = f"{title}: range NOT DETERMINED ({', '.join(why) or 'see the summary'})"
        if n_legs:
            title += f"\n{n_legs} leg{'s' if n_legs > 1 else ''} determined (leg-wise ML)"
    ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal", title=title)
    ax.legend(fontsize=8, loc="best")
    return fig


def write_tactical_picture(path, result) -> Path:
    """The tactical picture of a :class:`~sonartrack.tma.solve.TmaResult`, saved atomically as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    s = result.settings
    title = f"TMA ({s.method}{', bearings + frequency' if s.frequency else ''})"
    fig = tactical_picture(result.record, result.ownship, result.solution, s.ellipses, title=title,
                           legs=getattr(result, "legs", None))
    return save_figure(fig, path, dpi=110, bbox_inches="tight")

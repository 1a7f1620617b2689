"""The observer-advice picture: the ownship's track and legs, the targets now and ahead, the advised leg and the
alternatives with their predicted range sds (``sonartrack advise``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.io.atomic import save_figure
from sonartrack.report.figures.tma import ellipses


def _when(delay_s: float) -> str:
    return "now" if delay_s == 0 else f"in {delay_s / 60:.0f} min"


def _draw_leg(ax, advice, index, tau, style: dict, label: str) -> None:
    path = advice.ownship_path(index, tau) / 1e3
    ax.plot(path[:, 0], path[:, 1], label=label, **style)
    ax.plot(path[-1, 0], path[-1, 1], marker="o", ms=4, color=style.get("color", "k"))


def advice_picture(result, title: str = "observer advice"):
    """The picture of an :class:`~sonartrack.systems.advise.run.AdviceResult` (Figure): ownship track (legs thick,
    turns thin), targets now with 95 % ellipses and their predicted tracks to the horizon, the advised leg, 2-3
    alternatives and holding course, each labelled with its predicted range sd."""
    import matplotlib.pyplot as plt

    a, own, legs = result.advice, result.ownship, result.legs
    fig, ax = plt.subplots(figsize=(7, 7))
    t, x, y = (np.asarray(v, float) for v in (own.time_s, own.x_m, own.y_m))
    past = t <= a.time_s
    ax.plot(x[past] / 1e3, y[past] / 1e3, color="b", lw=0.8, label="ownship (turns thin)")
    for s, e in zip(legs.start_s, legs.end_s, strict=True):
        on = past & (t >= s) & (t <= e)
        ax.plot(x[on] / 1e3, y[on] / 1e3, color="b", lw=2.2)
    tau = np.linspace(0.0, a.horizon_s, 60)
    X = np.array([tg.state for tg in result.targets])
    for k, tg in enumerate(result.targets):
        ahead = tg.state[:2] + np.outer(tau, tg.state[2:])
        ax.plot(ahead[:, 0] / 1e3, ahead[:, 1] / 1e3, "r--", lw=1.0, label="target ahead (constant velocity)"
                if k == 0 else None)
        ax.plot(tg.state[0] / 1e3, tg.state[1] / 1e3, "r^", ms=8, label="target now" if k == 0 else None)
    ellipses(ax, X, np.array([tg.covariance for tg in result.targets]), len(X), label="95 % position ellipse now")
    _draw_leg(ax, a, None, tau, dict(color="0.5", ls=":", lw=1.5), f"hold course: {a.hold_range_sd_m / 1e3:.2f} km")
    for j, i in enumerate(a.alternatives):
        _draw_leg(ax, a, int(i), tau, dict(color=("C1", "C4", "C5", "C6")[j % 4], ls="--", lw=1.3),
                  f"{a.course_deg[i]:03.0f} deg {_when(a.turn_delay_s[i])}: {a.range_sd_m[i] / 1e3:.2f} km")
    b = a.best
    _draw_leg(ax, a, b, tau, dict(color="g", lw=3.0),
              f"ADVICE {a.course_deg[b]:03.0f} deg {_when(a.turn_delay_s[b])}: {a.range_sd_m[b] / 1e3:.2f} km")
    ax.plot(*(np.asarray(a.own_xy_m) / 1e3), "bo", ms=6)
    ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal",
           title=f"{title}: predicted range sd after {a.horizon_s / 60:.0f} min (now {a.now_range_sd_m / 1e3:.2f} km)")
    ax.legend(fontsize=7, loc="best")
    return fig


def write_advice_picture(path, result) -> Path:
    """:func:`advice_picture` saved atomically as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    return save_figure(advice_picture(result), path, dpi=110, bbox_inches="tight")

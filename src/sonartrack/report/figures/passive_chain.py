"""Figures of the passive-chain study: an example scene of the family, and the checks against their requirements."""

from __future__ import annotations

import numpy as np

from sonartrack.studies.passive_chain import (
    AXIS_REQUIRED,
    CRB_SHARE,
    FALSE_PER_HOUR,
    HOLD_REQUIRED,
    IDENTITY_REQUIRED,
    example_scene,
)


def figures(summary: dict, config) -> dict:
    return {"scenario": _scenario(config), "checks": _checks(summary)}


def _scenario(config):
    """Ownship, array centre and ships over the family's example scene (truth), with each ship's start marked."""
    import matplotlib.pyplot as plt

    from sonartrack.sim.passive_scene import scene_geometry

    scene = example_scene(config)
    g = scene_geometry(scene, np.linspace(0.0, scene.duration_s, 241))
    fig, ax = plt.subplots(figsize=(7, 7))
    ax.plot(g.own_xy[:, 0] / 1e3, g.own_xy[:, 1] / 1e3, "b-", lw=1.8, label="ownship")
    ax.plot(g.array_xy[:, 0] / 1e3, g.array_xy[:, 1] / 1e3, "c--", lw=1.0, label="array centre")
    for s, ship in enumerate(scene.ships):
        xy = g.ship_xy[s] / 1e3
        ax.plot(xy[:, 0], xy[:, 1], "-", color=f"C{s + 1}", label=ship.name)
        ax.plot(xy[0, 0], xy[0, 1], "o", color=f"C{s + 1}")
    ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal",
           title=f"example scene: {scene.array.elements} elements x {scene.spacing_m:g} m, "
                                        f"{scene.duration_s / 60:.0f} min (o = start)")
    ax.legend(fontsize=8)
    return fig


def _bars(ax, names, values, low=None, high=None, line=None, ylabel="", title=""):
    x = np.arange(len(names))
    v = np.asarray(values, float)
    yerr = None
    if low is not None:
        yerr = np.abs(np.vstack([v - np.asarray(low, float), np.asarray(high, float) - v]))
        yerr = np.nan_to_num(yerr)
    ax.bar(x, np.nan_to_num(v), yerr=yerr, color="C0", alpha=0.8, capsize=3)
    for i in np.nonzero(~np.isfinite(v))[0]:
        ax.text(x[i], 0.02, "not judged", ha="center", va="bottom", fontsize=8, color="0.4", rotation=90)
    if line is not None:
        ax.axhline(line, color="r", ls="--", lw=1)
    ax.set_xticks(x, names, fontsize=8)
    ax.set(ylabel=ylabel, title=title)


def _checks(summary: dict):
    import matplotlib.pyplot as plt

    names = summary["ships"]
    fig, axes = plt.subplots(2, 2, figsize=(10, 7))
    hold = np.array([summary["hold"][n] for n in names], float).reshape(-1, 3)
    _bars(axes[0, 0], names, hold[:, 0], hold[:, 1], hold[:, 2], HOLD_REQUIRED, "fraction held",
          "detectable time held by a confirmed track")
    axes[0, 0].set_ylim(0.0, 1.05)
    shares = [summary[k] for k in ("identity", "axis", "crb")]
    _bars(axes[0, 1], ["identity\nthrough crossing", "bearing after\naxis crossing", "ML within\n2x CRB"],
          [_share_value(d) for d in shares], [d["low"] for d in shares], [d["high"] for d in shares],
          ylabel="share (95 % Clopper-Pearson)", title=f"required {IDENTITY_REQUIRED}, {AXIS_REQUIRED}, {CRB_SHARE}")
    axes[0, 1].set_ylim(0.0, 1.05)
    nees = [summary["ml_nees"], summary["imm_nees"]]
    _bars(axes[1, 0], ["ML", "IMM-MGEKF"], [d["anees"] for d in nees], line=4.0, ylabel="ANEES",
          title="final solutions' mean NEES (- : chi-square 95 % interval)")
    for x, d in enumerate(nees):
        axes[1, 0].plot([x, x], [d["low"], d["high"]], "k_", ms=20)
    axes[1, 0].set_yscale("symlog", linthresh=10.0)
    _bars(axes[1, 1], ["false targets"], [summary["false_per_hour"]], [summary["false_per_hour"]],
          [summary["false_per_hour_upper95"]], FALSE_PER_HOUR, "per hour", "confirmed false targets (95 % upper)")
    fig.tight_layout()
    return fig


def _share_value(d: dict) -> float:
    return float("nan") if d["share"] is None else float(d["share"])

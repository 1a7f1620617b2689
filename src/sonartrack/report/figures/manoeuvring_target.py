"""Figures of the manoeuvring-target study: an example scene of the family, and the zig shares by turn and range."""

from __future__ import annotations

import numpy as np


def figures(summary: dict, config) -> dict:
    return {"scenario": _scenario(config), "zigs": _zig_shares(summary)}


def _scenario(config):
    """Ownship and target (truth) of a few scenes of the family, the target's zigs marked."""
    import matplotlib.pyplot as plt

    from sonartrack.sim.manoeuvre_scene import draw_manoeuvre_scene

    fig, axes = plt.subplots(1, 3, figsize=(13, 4.6))
    for ax, seed in zip(axes, (1, 2, 4), strict=True):
        scene = draw_manoeuvre_scene(config.scene, np.random.default_rng(seed))
        tgt = scene.target_xy_m(scene.time_s) / 1e3
        own = scene.own_xy_m / 1e3
        ax.plot(own[:, 0], own[:, 1], "b-", lw=1.6, label=f"ownship ({scene.own_pattern})")
        ax.plot(tgt[:, 0], tgt[:, 1], "r-", lw=1.6, label="target")
        if len(scene.change_times_s):
            z = scene.target_xy_m(scene.change_times_s) / 1e3
            ax.plot(z[:, 0], z[:, 1], "kx", ms=8, label="zigs")
        ax.plot(own[0, 0], own[0, 1], "bo")
        ax.plot(tgt[0, 0], tgt[0, 1], "ro")
        ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal",
               title=f"{scene.time_s[-1] / 60:.0f} min, bearings every {np.median(np.diff(scene.time_s)):.0f} s")
        ax.legend(fontsize=7)
    fig.suptitle("example scenes of the family (o = start)")
    fig.tight_layout()
    return fig


def _zig_shares(summary: dict):
    """Shares of zigs detected within 120 s (latency), localised within 120 s, and detectable within 120 s, by turn
    size and by range, with their 95 % intervals."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2), sharey=True)
    for ax, key, what in ((axes[0], "by_turn", "turn size"), (axes[1], "by_range", "range at the zig")):
        bins = list(summary[key])
        x = np.arange(len(bins))
        for j, (name, label) in enumerate((("latency", "detected <= 120 s after"), ("localised", "time within 120 s"),
                                           ("detectable", "detectable within 120 s"))):
            d = [summary[key][b][name] for b in bins]
            v = np.array([np.nan if s["share"] is None else s["share"] for s in d], float)
            lo = np.array([s["low"] for s in d], float)
            hi = np.array([s["high"] for s in d], float)
            ax.bar(x + (j - 1) * 0.27, np.nan_to_num(v), 0.27, yerr=np.nan_to_num(np.abs(np.vstack([v - lo, hi - v]))),
                   capsize=3, label=label, color=f"C{j}", alpha=0.85)
        ax.axhline(0.9, color="r", ls="--", lw=1)
        ax.set_xticks(x, bins)
        ax.set(xlabel=what, ylabel="share of zigs", ylim=(0, 1.05))
        ax.legend(fontsize=8)
    fig.suptitle("zigs: latency and localisation within 120 s, and the share a test at the known time could detect")
    fig.tight_layout()
    return fig

"""Figures of the P3 sensitivity study (tma-sensitivity): South winter's EM/MAP RMSE per reading with intervals,
the SNR-range curves that explain it, East's tolerated SL-mismatch interval per reading, its sweep curves, and
the reading -> number -> verdict table."""

from __future__ import annotations

import textwrap

import numpy as np


def figures(summary: dict, config) -> dict:
    """South accuracy, South SNR curves, East intervals, East sweeps, table."""
    return {"south_accuracy": _south_accuracy(summary), "south_snr_curves": _snr_curves(summary, east=False),
            "east_tolerated": _east_tolerated(summary), "east_sweeps": _east_sweeps(summary),
            "east_snr_curves": _snr_curves(summary, east=True), "sensitivity_table": _table_figure(summary)}


def _rows(summary: dict, east: bool) -> list[dict]:
    """The South accuracy readings (east False) or the swept readings (East first, then the other seas)."""
    return [r for r in summary["readings"] if r["sweep"] == east]


def _nan(x) -> float:
    return np.nan if x is None else float(x)


def _south_accuracy(summary: dict):
    """Largest RMSE component (%) per reading with its 95 % bootstrap interval; per-component dots; 10 % line."""
    import matplotlib.pyplot as plt

    rows = _rows(summary, east=False)
    fig, ax = plt.subplots(figsize=(7.5, 0.45 * len(rows) + 1.8))
    y = np.arange(len(rows))
    for i, r in enumerate(rows):
        lo, hi = (_nan(v) for v in r["worst_ci_pct"])
        colour = {"holds": "C2", "fails": "C3"}.get(r["under_10pct"], "C1")
        ax.plot([lo, hi], [i, i], color=colour, lw=3, alpha=0.6)
        ax.plot(r["worst_pct"], i, "o", color=colour)
        ax.plot([_nan(v) for v in r["em_rmse_pct"]], [i] * 4, "k|", ms=8)
    ax.axvline(summary["rmse_limit_pct"], color="k", ls="--", lw=1)
    ax.set_yticks(y, [f"{r['env']}: {r['label']}" for r in rows])
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.set_xlabel("EM/MAP RMSE (%), largest of start/end X/Y (dot, 95 % bootstrap bar); ticks: the four components")
    ax.set_title(f"em_map_under_10pct under each reading ({summary['runs']} runs; green holds, red fails, "
                 "orange undecided)", fontsize=9)
    fig.tight_layout()
    return fig


def _snr_curves(summary: dict, east: bool):
    """True SNR against range per reading, the track's range span shaded, slope over it in the legend."""
    import matplotlib.pyplot as plt

    rows = _rows(summary, east)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for r in rows:
        f = r["flatness"]
        ax.plot(f["curve_km"], f["curve_db"], lw=1,
                label=f"{r['env']}: {r['label']} ({f['mean_abs_slope_db_per_km']:.2f} dB/km on track)")
        ax.axvspan(*f["track_range_km"], color="0.85", alpha=0.3)
    ax.set_xlabel("range (km)")
    ax.set_ylabel("mean SNR (dB)")
    ax.set_title("SNR-range curves; shaded: ranges the target track covers", fontsize=9)
    ax.legend(fontsize=6)
    fig.tight_layout()
    return fig


def _east_tolerated(summary: dict):
    """Tolerated SL-mismatch interval per East reading (bar), 95 % bootstrap intervals of its ends, paper's."""
    import matplotlib.pyplot as plt

    rows = _rows(summary, east=True)
    fig, ax = plt.subplots(figsize=(7.5, 0.5 * len(rows) + 1.8))
    for i, r in enumerate(rows):
        lo, hi = (_nan(v) for v in r["tolerated_db"])
        ax.plot([lo, hi], [i, i], color="C0", lw=6, alpha=0.6)
        for ci in (r["tolerated_lower_ci_db"], r["tolerated_upper_ci_db"]):
            ax.plot([_nan(v) for v in ci], [i + 0.2] * 2, "k|-", lw=1, ms=6)
        p = summary["paper_tolerated_db"].get(r["env"])
        if p:
            ax.plot(p, [i - 0.2] * 2, color="C3", lw=2)
    ax.axvline(0.0, color="k", lw=0.5)
    ax.set_yticks(np.arange(len(rows)), [f"{r['env']}: {r['label']}" for r in rows])
    ax.invert_yaxis()
    ax.set_xlabel("assumed - true SL (dB): ours (blue bar), 95 % bootstrap of the ends (black), paper (red)")
    ax.set_title("east_tolerates_low_sl: tolerated interval (pooled range RMSE < 10 %)", fontsize=9)
    fig.tight_layout()
    return fig


def _east_sweeps(summary: dict):
    """Pooled normalised range RMSE against SL mismatch per East reading, with bootstrap bands."""
    import matplotlib.pyplot as plt

    rows = [r for r in _rows(summary, east=True) if r["env"].startswith("east")]
    envs = sorted({r["env"] for r in rows})
    fig, axes = plt.subplots(1, len(envs), figsize=(5.5 * len(envs), 4), squeeze=False)
    for ax, env in zip(axes[0], envs, strict=True):
        for r in (r for r in rows if r["env"] == env):
            d = np.asarray(r["deltas_db"])
            ci = np.array([[_nan(v) for v in c] for c in r["sweep_rmse_ci_pct"]])
            line, = ax.plot(d, [_nan(v) for v in r["sweep_rmse_pct"]], "o-", ms=3, label=r["label"])
            ax.fill_between(d, ci[:, 0], ci[:, 1], color=line.get_color(), alpha=0.15)
        ax.axhline(summary["rmse_limit_pct"], color="k", ls="--", lw=1)
        ax.set_yscale("log")
        ax.set_title(env, fontsize=9)
        ax.set_xlabel("assumed - true SL (dB)")
        ax.set_ylabel("normalised range RMSE (%)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _table_figure(summary: dict):
    """The table: reading, claim, number with interval, verdict, why."""
    import matplotlib.pyplot as plt

    tab = summary["table"]
    cells = [[textwrap.fill(t["reading"], 34), t["claim"], textwrap.fill(t["number"], 30), t["verdict"],
              textwrap.fill(t["why"], 60)] for t in tab]
    fig, ax = plt.subplots(figsize=(15, 0.55 * len(tab) + 1.0))
    ax.axis("off")
    tbl = ax.table(cellText=cells, colLabels=["reading", "claim", "number (95 % interval)", "verdict", "why"],
                   loc="center", cellLoc="left")
    tbl.auto_set_font_size(False)
    tbl.set_fontsize(6.5)
    tbl.scale(1.0, 2.2)
    fig.tight_layout()
    return fig

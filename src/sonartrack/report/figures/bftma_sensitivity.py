"""Figures of the P2 sensitivity study (bftma-sensitivity): the claim ``mgekf-divergence-end`` of bftma-imm under
every reading of the open choices (grid), the one-factor-at-a-time table, per-pair counts, and the position
error and NEES against time that explain the q = 1e-5 result."""

from __future__ import annotations

import textwrap

import numpy as np

from sonartrack.studies.bftma_imm import FILTERS, MEASUREMENTS

#: one colour per filter in every figure of this study
COLOURS = {"mgekf": "C1", "ekf": "C0"}


def figures(summary: dict, config) -> dict:
    """Grid (definition x reading), table, per-pair counts, error and NEES against time."""
    return {"sensitivity_grid": _grid_figure(summary), "sensitivity_table": _table_figure(summary),
            "per_pair_counts": _per_pair_figure(summary), "error_and_nees": _series_figure(summary, config)}


def _grid_figure(summary: dict):
    """n_MGEKF - n_EKF per cell (blue: the claim holds, red: it does not); '*' where the 95 % interval of the
    paired difference excludes 0; the default cell boxed."""
    import matplotlib.pyplot as plt

    reads, defs = summary["readings"], summary["definitions"]
    diff = np.array([[summary["cells"][r["id"]][d["id"]]["diff"] for r in reads] for d in defs], float)
    lim = max(1.0, np.abs(diff).max())
    fig, ax = plt.subplots(figsize=(1.05 * len(reads) + 3.5, 0.36 * len(defs) + 2.2))
    ax.imshow(diff, cmap="coolwarm", vmin=-lim, vmax=lim, aspect="auto")
    for i, d in enumerate(defs):
        for j, r in enumerate(reads):
            c = summary["cells"][r["id"]][d["id"]]
            sure = c["diff_ci"][0] > 0 or c["diff_ci"][1] < 0
            ax.text(j, i, f"{c['diff']:+d}{'*' if sure else ''}", ha="center", va="center", fontsize=7)
    j0 = [r["id"] for r in reads].index(summary["default_reading"])
    i0 = [d["id"] for d in defs].index(summary["default_definition"])
    ax.add_patch(plt.Rectangle((j0 - 0.5, i0 - 0.5), 1, 1, fill=False, lw=2, ec="k"))
    ax.set_xticks(range(len(reads)), [r["label"] for r in reads], rotation=35, ha="right", fontsize=7)
    ax.set_yticks(range(len(defs)), [d["label"] for d in defs], fontsize=7)
    ax.set_title(f"mgekf-divergence-end: n_MGEKF - n_EKF diverged ({summary['runs']} runs x pairs); "
                 "blue = claim holds, * = 95 % CI excludes 0", fontsize=9)
    fig.tight_layout()
    return fig


def _table_rows(summary: dict) -> list[list[str]]:
    rows = []
    for r in summary["table"]:
        rows.append([r["reading"], r["definition"],
                     f"{r['n_mgekf']} [{r['mgekf_ci'][0]:.0f}, {r['mgekf_ci'][1]:.0f}]",
                     f"{r['n_ekf']} [{r['ekf_ci'][0]:.0f}, {r['ekf_ci'][1]:.0f}]",
                     f"{r['diff']:+d} [{r['diff_ci'][0]:+.0f}, {r['diff_ci'][1]:+.0f}]", f"{r['total']}",
                     "holds" if r["holds"] else "fails"])
    return rows


def _table_figure(summary: dict):
    """One factor at a time: every reading under the default definition, then every definition under the
    default reading; counts with Clopper-Pearson 95 % intervals, the paired difference with its 95 % interval."""
    import matplotlib.pyplot as plt

    rows = _table_rows(summary)
    head = ["reading", "divergence definition", "MGEKF diverged [CP 95%]", "EKF diverged [CP 95%]",
            "MGEKF - EKF [95% CI, paired]", "of", "claim"]
    fig, ax = plt.subplots(figsize=(13.5, 0.25 * len(rows) + 1.0))
    ax.axis("off")
    tab = ax.table(cellText=rows, colLabels=head, loc="center", cellLoc="left",
                   colWidths=[0.22, 0.22, 0.15, 0.15, 0.15, 0.04, 0.06])
    tab.auto_set_font_size(False)
    tab.set_fontsize(7)
    tab.scale(1.0, 1.15)
    for i, row in enumerate(rows, start=1):
        tab[i, 6].set_facecolor("#cfe3f7" if row[6] == "holds" else "#f7d0cb")
    ax.set_title(f"mgekf-divergence-end under each reading ({summary['runs']} runs; counts over runs x pairs)",
                 fontsize=9)
    note = "\n".join(textwrap.fill(f, 190) for f in summary.get("findings", []))
    fig.text(0.01, 0.0, note, fontsize=7, va="top", ha="left")
    fig.tight_layout()
    return fig


def _per_pair_figure(summary: dict):
    """Default reading: diverged runs of MGEKF and EKF per single q and per IMM bank, four definitions."""
    import matplotlib.pyplot as plt

    pp = summary["per_pair"]
    names, counts = pp["names"], pp["counts"]
    fig, axes = plt.subplots(2, 2, figsize=(13, 7.5), sharey=True)
    xs = np.arange(len(names))
    labels = {d["id"]: d["label"] for d in summary["definitions"]}
    for ax, did in zip(axes.ravel(), counts, strict=True):
        for k, (meas, filt) in enumerate((m, f) for m in MEASUREMENTS for f in FILTERS):
            vals = [counts[did][n][meas][list(FILTERS).index(filt)] for n in names]
            ax.bar(xs + (k - 1.5) * 0.2, vals, 0.2, color=COLOURS[filt],
                   hatch="" if meas == "bf" else "//", edgecolor="k", lw=0.4, label=f"{FILTERS[filt]} ({meas})")
        ax.set_xticks(xs, [pp["labels"][n] for n in names], rotation=30, ha="right", fontsize=7)
        ax.set(ylabel=f"diverged runs (of {summary['runs']})", title=labels[did])
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig


def _series_figure(summary: dict, config):
    """Median position error / range (quartile band) and median position NEES against time, single filters of
    the IMM bank, EKF vs MGEKF with and without frequency; the turn and the thresholds marked."""
    import matplotlib.pyplot as plt

    t_min = np.asarray(summary["time_s"]) / 60.0
    qs = list(config.imm.q_values)
    fig, axes = plt.subplots(2, len(qs), figsize=(4.6 * len(qs), 7), sharex=True, squeeze=False)
    for col, q in enumerate(qs):
        for meas in MEASUREMENTS:
            for filt in FILTERS:
                s = summary["series"].get(f"{meas}_{filt}_q{q:g}")
                if s is None:
                    continue
                style = dict(color=COLOURS[filt], ls="-" if meas == "bf" else "--")
                lab = f"{FILTERS[filt]} ({meas})"
                axes[0, col].plot(t_min, s["rel_median"], label=lab, **style)
                axes[0, col].fill_between(t_min, s["rel_q25"], s["rel_q75"], color=style["color"], alpha=0.12)
                axes[1, col].plot(t_min, s["nees_median"], label=lab, **style)
        axes[0, col].axhline(config.divergence_rel_threshold, color="k", lw=0.8, ls=":")
        axes[1, col].axhline(summary["chi2_threshold"], color="k", lw=0.8, ls=":")
        for ax in axes[:, col]:
            ax.axvline(summary["turn_time_s"] / 60.0, color="r", ls=":", lw=1)
            ax.set_yscale("log")
        axes[0, col].set(title=f"single filters, q = {q:g} m²/s³", ylabel="position error / range (median, IQR)")
        axes[1, col].set(xlabel="time (min)", ylabel="position NEES (median)")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig

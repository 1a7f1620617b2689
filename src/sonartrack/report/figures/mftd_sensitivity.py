"""Figures of the P1 sensitivity study (mftd-sensitivity): the three failing mftd claims under every reading
(plane x prior density x final decision) as a table, Pd against sigma_a per reading, and Pd against N per
plane beside the share of trials whose true first cell survives the first pruning."""

from __future__ import annotations

import textwrap

import numpy as np

from sonartrack.studies.mftd_sensitivity import CLAIM_IDS

#: line style per (prior density, final decision)
STYLES = {("smoothed", "branches"): ("C0", "-"), ("smoothed", "kept"): ("C0", "--"),
          ("centre", "branches"): ("C3", "-"), ("centre", "kept"): ("C3", "--")}
SHORT = {"pd_falls_with_sigma_a": "Pd falls with σa (N default)",
         "pd_falls_with_sigma_a_large_n": "Pd falls with σa (large N)",
         "pd_rises_with_n_and_saturates": "Pd rises with N, saturates"}


def figures(summary: dict, config) -> dict:
    """Table of verdicts, Pd vs sigma_a per reading, Pd vs N per plane with first-cell survival."""
    return {"sensitivity_table": _table_figure(summary), "pd_vs_sigma_a": _sigma_figure(summary),
            "pd_vs_n_saturation": _n_figure(summary)}


def _fmt_points(points: list[dict]) -> str:
    return ", ".join(f"{p['pd']:.3f} [{p['pd_low']:.3f}, {p['pd_high']:.3f}]" for p in points)


def _table_rows(summary: dict) -> list[list[str]]:
    """reading, claim, Pd [CP 95 %] per curve, first-cell survival, verdict."""
    key = {"pd_falls_with_sigma_a": "sigma", "pd_falls_with_sigma_a_large_n": "sigma_large_n",
           "pd_rises_with_n_and_saturates": "n"}
    rows = []
    for c in summary["readings"]:
        for cid in CLAIM_IDS:
            v = c["claims"][cid]
            kept = np.atleast_1d(v["first_cell_kept"])
            extra = (f"; saturated from N={v['saturated_from_n']}" if "saturated_from_n" in v
                     else ("; a significant rise against" if v.get("against") else ""))
            unpaired = v.get("unpaired_holds")
            unpaired_txt = "-" if unpaired is None else ("holds" if unpaired else "fails")
            label = c["id"] + (" (mftd default)" if c["id"] == summary.get("default_reading") else "")
            rows.append([label, SHORT[cid], _fmt_points(c["points"][key[cid]]) + extra,
                         "/".join(f"{k:.0%}" for k in kept), "holds" if v["holds"] else "fails", unpaired_txt])
    return rows


def _table_figure(summary: dict):
    """Every reading x claim: Pd with Clopper-Pearson 95 % intervals, first-cell survival, verdict."""
    import matplotlib.pyplot as plt

    rows = _table_rows(summary)
    head = ["reading (plane_density_final)", "claim", "Pd at Pfa [CP 95%] along the family",
            "first cell kept (per σa, or per N)", "claim", "unpaired SE"]
    fig, ax = plt.subplots(figsize=(16, 0.24 * len(rows) + 1.6))
    ax.axis("off")
    tab = ax.table(cellText=rows, colLabels=head, loc="center", cellLoc="left",
                   colWidths=[0.14, 0.13, 0.50, 0.12, 0.05, 0.06])
    tab.auto_set_font_size(False)
    tab.set_fontsize(6.5)
    tab.scale(1.0, 1.1)
    for i, row in enumerate(rows, start=1):
        for j in (4, 5):
            if row[j] != "-":
                tab[i, j].set_facecolor("#cfe3f7" if row[j] == "holds" else "#f7d0cb")
    ax.set_title(f"mftd claims under each reading ({summary['runs']} trials, Pfa = {summary['pfa']:g}; a step counts "
                 "when larger than 1.96 SE of the difference, paired (bootstrap of the trials, thresholds "
                 "re-estimated), as in mftd; 'unpaired SE': the same with the binomial SE of independent curves)",
                 fontsize=9)
    note = "\n".join(textwrap.fill(f, 220) for f in summary.get("findings", []))
    fig.text(0.01, 0.0, note, fontsize=7, va="top", ha="left")
    fig.tight_layout()
    return fig


def _errorbar(ax, x, points: list[dict], colour: str, ls: str, label: str) -> None:
    pd = np.array([p["pd"] for p in points])
    err = np.array([[p["pd"] - p["pd_low"] for p in points], [p["pd_high"] - p["pd"] for p in points]])
    ax.errorbar(x, pd, yerr=err, color=colour, ls=ls, marker="o", ms=3, capsize=2, label=label)


def _planes(summary: dict) -> list[str]:
    return list(summary["planes"])


def _sigma_figure(summary: dict):
    """Pd at the claim Pfa against sigma_a, one column per plane, rows N default / large N; a line per
    density x final reading (95 % Clopper-Pearson bars)."""
    import matplotlib.pyplot as plt

    planes, a = _planes(summary), summary["sigma_a_family_mps2"]
    fig, axes = plt.subplots(2, len(planes), figsize=(4.2 * len(planes), 6.5), squeeze=False, sharex=True)
    for col, pid in enumerate(planes):
        for row, (fam, n) in enumerate((("sigma", summary["n_default"]), ("sigma_large_n", summary["large_n"]))):
            ax = axes[row, col]
            mine = [c for c in summary["readings"] if c["id"].startswith(pid + "_")]
            for k, c in enumerate(mine):
                colour, ls = STYLES.get((c["prior_density"], c["final"]), ("k", ":"))
                shift = 1.0 + 0.04 * (k - (len(mine) - 1) / 2)  # side by side, so the bars do not overlap
                _errorbar(ax, np.asarray(a) * shift, c["points"][fam], colour, ls,
                          f"{c['prior_density']}, {c['final']}")
            ax.set(xscale="log", title=f"{pid} (M = {summary['planes'][pid]['n_cells']}), N = {n}",
                   xlabel="σa (m/s²)", ylabel=f"Pd at Pfa {summary['pfa']:g}")
            ax.set_xticks(a, [f"{x:g}" for x in a])
            ax.minorticks_off()
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig


def _n_figure(summary: dict):
    """Top: Pd against N per plane (default density/final solid, the others thin). Bottom: share of trials
    whose true first cell survives the first pruning (rank < N) per plane, at the default sigma_a."""
    import matplotlib.pyplot as plt

    ns = summary["n_family"]
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(7.5, 8), sharex=True)
    for k, pid in enumerate(_planes(summary)):
        for c in summary["readings"]:
            if not c["id"].startswith(pid + "_"):
                continue
            first = c is next(r for r in summary["readings"] if r["id"].startswith(pid + "_"))
            _errorbar(ax, ns, c["points"]["n"], f"C{k}", "-" if first else ":",
                      f"{pid}: {c['prior_density']}, {c['final']}" if first else None)
            if first:
                bx.plot(ns, c["claims"]["pd_rises_with_n_and_saturates"]["first_cell_kept"], f"C{k}o-",
                        label=f"{pid} (M = {summary['planes'][pid]['n_cells']})")
    ax.set(xscale="log", ylabel=f"Pd at Pfa {summary['pfa']:g}",
           title="Pd vs N (95 % CP bars; solid: first reading of each plane, dotted: the other readings)")
    bx.set(xscale="log", xlabel="N (tracks kept)", ylabel="true first cell kept by the first pruning", ylim=(0, 1.02))
    for a_ in (ax, bx):
        a_.grid(alpha=0.3)
        a_.legend(fontsize=7)
        a_.set_xticks(ns, [str(n) for n in ns])
        a_.minorticks_off()
    fig.tight_layout()
    return fig

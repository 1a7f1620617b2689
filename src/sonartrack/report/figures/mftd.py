"""Figures of study P1 (mftd): the scenario, the three ROC families, and the checks."""

from __future__ import annotations

import numpy as np

from sonartrack.report.figures.detection import frames_figure


def figures(summary: dict, config) -> dict:
    """Scenario (an example target over the frames), the three ROC families, the prior-density and K = 1 checks."""
    return {"scenario": scenario_figure(config), "roc_families": _families_figure(summary, config),
            "roc_checks": _checks_figure(summary, config)}


def scenario_figure(config):
    """K frames of one target-present trial (SNR at the default), true cells and the best MFTD track."""
    from sonartrack.studies.mftd import scenario_example

    y, track, res = scenario_example(config)
    grid, d = config.grid(), config.detector
    fig, axes = frames_figure(
        y, grid, f"{grid.n_range} x {grid.n_doppler} range-Doppler cells ({grid.range_cell_m:.1f} m x "
                 f"{grid.range_rate_cell_mps:.3f} m/s), SNR {d.snr_db:g} dB, σa={d.sigma_a_mps2:g} m/s²; "
                 f"statistic {res.statistic:.2f}")
    centres = grid.centres()
    for k, ax in enumerate(axes):
        tc = centres[track.cells[k, 0] * grid.n_doppler + track.cells[k, 1]]
        bc = centres[res.tracks[0, k, 0] * grid.n_doppler + res.tracks[0, k, 1]]
        ax.plot(*tc, "rs", mfc="none", ms=9, label="target cell")
        ax.plot(*bc, "wx", ms=7, label="best MFTD track")
    axes[0].legend(fontsize=6, loc="lower left")
    fig.tight_layout()
    return fig


def _roc_panel(ax, summary: dict, config, fam: str, title: str) -> None:
    """The ROC curves of one family (95 % Pd bands) with the clairvoyant and single-frame bounds."""
    import matplotlib.pyplot as plt

    pfa = np.asarray(summary["pfa"])
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    members = config.family(fam)
    for i, (label, name) in enumerate(members):
        c, col = summary["curves"][name], colours[i % len(colours)]
        ax.plot(pfa, c["pd"], "o-", color=col, ms=3, label=label)
        ax.fill_between(pfa, c["pd_low"], c["pd_high"], color=col, alpha=0.15)
    snrs = sorted({summary["curves"][name]["snr_db"] for _, name in members})
    for s in snrs:
        r = summary["references"][f"{s:g}"]
        tag = f" ({s:g} dB)" if len(snrs) > 1 else ""
        ax.plot(pfa, r["clairvoyant"], "k--", lw=0.8, label="clairvoyant known track" + tag)
        ax.plot(pfa, r["single_frame"], "k:", lw=0.8, label="single frame over the plane" + tag)
    ax.set(xscale="log", xlabel="Pfa (system)", ylabel="Pd", ylim=(0, 1.02), title=title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6)


def _families_figure(summary: dict, config):
    """Figs. 4-6: SNR, target mobility, tracks kept."""
    import matplotlib.pyplot as plt

    d = config.detector
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    _roc_panel(axes[0], summary, config, "snr", f"SNR (Fig. 4): N={d.n_tracks}, σa={d.sigma_a_mps2:g}")
    _roc_panel(axes[1], summary, config, "sigma", f"Target mobility (Fig. 5): SNR {d.snr_db:g} dB, N={d.n_tracks}")
    _roc_panel(axes[2], summary, config, "n", f"Tracks kept (Fig. 6): SNR {d.snr_db:g} dB, σa={d.sigma_a_mps2:g}")
    fig.tight_layout()
    return fig


def _checks_figure(summary: dict, config):
    """Mobility at a large N, eq. 19 as printed against the smoothed density, and the K = 1 closed form."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    _roc_panel(axes[0], summary, config, "sigma_large_n", f"Target mobility with N={config.large_n}")
    _roc_panel(axes[1], summary, config, "density", "Prior density: eq. 19 as printed vs smoothed")
    ax, k1, pfa = axes[2], summary["k1"], np.asarray(summary["pfa"])
    ax.plot(pfa, k1["closed_form"], "k-", label="Pfa^(1/(1+ρ))")
    ax.errorbar(pfa, k1["pd"], yerr=[np.subtract(k1["pd"], k1["pd_low"]), np.subtract(k1["pd_high"], k1["pd"])],
                fmt="o", ms=3, label="Monte Carlo, K=1, one cell")
    ax.set(xscale="log", xlabel="Pfa", ylabel="Pd", title="K = 1 check", ylim=(0, 1.02))
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig

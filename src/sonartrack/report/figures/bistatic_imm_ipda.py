"""Figures of study P4 (bistatic IMM-IPDA): scenario, measurement error, CTT rate, range RMSE, false
tracks and mode probabilities, from the study's summary (studies/bistatic_imm_ipda.py)."""

from __future__ import annotations

import numpy as np

from sonartrack.sim.bistatic_sonar import simulate_scan
from sonartrack.studies.bistatic_imm_ipda import EXPERIMENTS, LABELS


def figures(summary: dict, config) -> dict:
    """Scenario, measurement error, CTT rate, range RMSE, mode probabilities, false tracks."""
    figs = {"scenario": scenario_figure(config), "measurement_error": measurement_error_figure(summary)}
    panels = (("ctt_rate", "CTT rate", "ctt_rate", "Confirmed true track rate (Figs. 6, 9)"),
              ("range_rmse_m", "range RMSE of CTTs (m)", "range_rmse", "Range RMSE (Figs. 7, 10)"),
              ("cft_per_scan", "confirmed false tracks / scan", "false_tracks", "Confirmed false tracks"))
    for key, ylabel, name, title in panels:
        figs[name] = experiments_figure(summary, key, ylabel, title)
    figs["mode_probabilities"] = mode_probability_figure(summary)
    return figs


def measurement_error_figure(summary: dict):
    import matplotlib.pyplot as plt

    k = np.arange(summary["n_scans"])
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.plot(k, summary["meas_error_rms_m"], label="RMS over runs")
    ax.plot(k, summary["meas_error_mean_m"], label="mean over runs")
    ax.plot(k, summary["meas_bias_m"], label="|bias| (mean error vector)")
    ax.axvline(summary["turn_scan"], color="k", ls=":", lw=1)
    ax.set(xlabel="scan", ylabel="target measurement error (m)", title="Measurement error (paper Fig. 5)")
    ax.legend()
    return fig


def experiments_figure(summary: dict, key: str, ylabel: str, title: str):
    """One per-scan curve of ``key`` per tracker, experiment 1 on the left, 2 on the right."""
    import matplotlib.pyplot as plt

    k = np.arange(summary["n_scans"])
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8), sharey=True)
    for ax, (exp, cases) in zip(axes, EXPERIMENTS.items(), strict=True):
        for c in cases:
            ax.plot(k, summary["cases"][c][key], label=LABELS[c] + f" q={summary['cases'][c]['q']}")
        ax.axvline(summary["turn_scan"], color="k", ls=":", lw=1)
        ax.set(xlabel="scan", ylabel=ylabel, title=f"{title}: {exp}")
        ax.legend(fontsize=7)
    return fig


def mode_probability_figure(summary: dict):
    import matplotlib.pyplot as plt

    k = np.arange(summary["n_scans"])
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.5), sharey=True)
    for ax, imm in zip(axes, ("imm2", "imm3"), strict=True):
        mu = np.asarray(summary["cases"][imm]["mode_prob"], float)
        for j, q in enumerate(summary["cases"][imm]["q"]):
            if mu.ndim == 2:
                ax.plot(k, mu[:, j], label=f"q = {q:g}")
        ax.axvline(summary["turn_scan"], color="k", ls=":", lw=1)
        ax.set(xlabel="scan", ylabel="mode probability", ylim=(0, 1), title=f"{LABELS[imm]} (Figs. 8, 11)")
        ax.legend()
    return fig


def scenario_figure(config):
    """Ownship, Tx, Rx and target tracks, the clutter region and one illustrative scan (paper Fig. 4)."""
    import matplotlib.pyplot as plt

    ship, sonar = config.ownship(), config.sonar()
    t = config.times_s()
    pos, _, _ = ship.state(t)
    tx, _ = ship.towed(t, config.tx_cable_m)
    rx, _ = ship.towed(t, config.rx_cable_m)
    truth = config.target_states()
    rng = np.random.default_rng(0)  # an illustrative scan, not a trial
    scan = simulate_scan(rng, sonar, ship, float(t[config.turn_scan]), truth[config.turn_scan, :2])
    fig, ax = plt.subplots(figsize=(6, 6.5))
    ax.plot(pos[:, 0] / 1e3, pos[:, 1] / 1e3, "b-", label="ownship")
    ax.plot(tx[:, 0] / 1e3, tx[:, 1] / 1e3, "c--", lw=0.8, label=f"Tx ({config.tx_cable_m:g} m behind)")
    ax.plot(rx[:, 0] / 1e3, rx[:, 1] / 1e3, "g--", lw=0.8, label=f"Rx ({config.rx_cable_m:g} m behind)")
    ax.plot(truth[:, 0] / 1e3, truth[:, 1] / 1e3, "r-", label="target")
    ax.plot(truth[0, 0] / 1e3, truth[0, 1] / 1e3, "ro")
    ax.plot(pos[0, 0] / 1e3, pos[0, 1] / 1e3, "bo")
    ax.plot(pos[config.turn_scan, 0] / 1e3, pos[config.turn_scan, 1] / 1e3, "b^", label="turn starts")
    ax.plot(scan.z[:, 0] / 1e3, scan.z[:, 1] / 1e3, ".", color="0.6", ms=3,
            label=f"one scan's clutter (t = {scan.time_s:.0f} s)")
    x0, x1, y0, y1 = config.region_m
    ax.add_patch(plt.Rectangle((x0 / 1e3, y0 / 1e3), (x1 - x0) / 1e3, (y1 - y0) / 1e3, fill=False, ls=":", color="0.4"))
    ax.set(xlabel="x east (km)", ylabel="y north (km)", title="Scenario (paper Fig. 4)", aspect="equal")
    ax.legend(fontsize=7, loc="lower left")
    return fig

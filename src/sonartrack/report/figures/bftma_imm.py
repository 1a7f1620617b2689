"""Figures of study P2 (bftma-imm): the scenario, RMSE against time, mode probabilities, divergence counts."""

from __future__ import annotations

import numpy as np

from sonartrack.studies.bftma_imm import FILTERS, MEASUREMENTS


def figures(summary: dict, config) -> dict:
    """Scenario, position/velocity/course-speed RMSE against time, mode probabilities, divergence."""
    return {"scenario": scenario_figure(config),
            "rmse_position": _rmse_figure(summary, config, "rmse_pos_m", "position RMSE (m)", "Position RMSE"),
            "rmse_velocity": _rmse_figure(summary, config, "rmse_vel_mps", "velocity RMSE (m/s)", "Velocity RMSE"),
            "rmse_course_speed": _course_speed_figure(summary, config),
            "mode_probabilities": _mode_figure(summary),
            "divergence": _divergence_figure(summary, config)}


def _rmse_panel(ax, summary: dict, config, meas: str, key: str) -> None:
    """The single-q MGEKFs, IMM-EKF (dashed) and IMM-MGEKF (bold) of one measurement set; the turn dotted."""
    t_min = np.asarray(summary["time_s"]) / 60.0
    cs = summary["cases"]
    for i in range(len(config.imm.q_values)):
        ax.plot(t_min, cs[f"{meas}_mgekf_q{i}"][key], lw=1, label=cs[f"{meas}_mgekf_q{i}"]["label"])
    ax.plot(t_min, cs[f"{meas}_ekf_imm"][key], "k--", lw=1.2, label=cs[f"{meas}_ekf_imm"]["label"])
    ax.plot(t_min, cs[f"{meas}_mgekf_imm"][key], "k-", lw=2, label=cs[f"{meas}_mgekf_imm"]["label"])
    ax.axvline(summary["turn_time_s"] / 60.0, color="r", ls=":", lw=1)
    ax.set_yscale("log")


def _rmse_figure(summary: dict, config, key: str, ylabel: str, title: str):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4), sharey=True)
    for ax, meas in zip(axes, MEASUREMENTS, strict=True):
        _rmse_panel(ax, summary, config, meas, key)
        ax.set(xlabel="time (min)", ylabel=ylabel, title=f"{title}: {MEASUREMENTS[meas]}")
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _course_speed_figure(summary: dict, config):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11.5, 7), sharex=True)
    for col, meas in enumerate(MEASUREMENTS):
        for row, (key, ylabel) in enumerate((("rmse_course_deg", "course RMSE (deg)"),
                                             ("rmse_speed_kn", "speed RMSE (kn)"))):
            ax = axes[row, col]
            _rmse_panel(ax, summary, config, meas, key)
            ax.set(ylabel=ylabel, title=MEASUREMENTS[meas])
            if row == 1:
                ax.set_xlabel("time (min)")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig


def _mode_figure(summary: dict):
    import matplotlib.pyplot as plt

    t_min = np.asarray(summary["time_s"]) / 60.0
    cs = summary["cases"]
    imms = [c for c in ("bf_mgekf_imm", "b_mgekf_imm", "bf_ekf_imm") if "mode_prob" in cs[c]]
    fig, axes = plt.subplots(1, len(imms), figsize=(4.2 * len(imms), 3.6), sharey=True, squeeze=False)
    for ax, c in zip(axes[0], imms, strict=True):
        mu = np.asarray(cs[c]["mode_prob"], float)
        for j, q in enumerate(cs[c]["q"]):
            ax.plot(t_min, mu[:, j], label=f"q = {q:g} m²/s³")
        ax.axvline(summary["turn_time_s"] / 60.0, color="r", ls=":", lw=1)
        ax.set(xlabel="time (min)", ylabel="mean mode probability", ylim=(0, 1), title=cs[c]["label"])
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _divergence_figure(summary: dict, config):
    import matplotlib.pyplot as plt

    cs = summary["cases"]
    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4), sharey=True)
    names = [f"q{i}" for i in range(len(config.imm.q_values))] + ["imm"]
    xs = np.arange(len(names))
    bars = (("ekf", "diverged_turn", ""), ("mgekf", "diverged_turn", ""), ("ekf", "diverged_end", "//"),
            ("mgekf", "diverged_end", "//"))
    for ax, meas in zip(axes, MEASUREMENTS, strict=True):
        for off, (filt, key, hatch) in enumerate(bars):
            vals = [cs[f"{meas}_{filt}_{n}"][key] for n in names]
            ax.bar(xs + (off - 1.5) * 0.2, vals, 0.2, hatch=hatch, color="C0" if filt == "ekf" else "C1",
                   edgecolor="k", lw=0.5, label=f"{FILTERS[filt]}, {'at turn' if key.endswith('turn') else 'at end'}")
        ax.set_xticks(xs, [f"q={q:g}" for q in config.imm.q_values] + ["IMM"])
        ax.set(ylabel=f"diverged runs (of {summary['runs']})", title=f"Divergence: {MEASUREMENTS[meas]}")
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def scenario_figure(config):
    """Observer and target tracks with the turns and a few lines of sight."""
    import matplotlib.pyplot as plt

    t = config.times_s()
    po, _, _ = config.observer().state(t)
    pt, _, _ = config.target().state(t)
    k0 = int(np.searchsorted(t, config.target_turn_start_s))
    fig, ax = plt.subplots(figsize=(6.5, 6.5))
    ax.plot(po[:, 0] / 1e3, po[:, 1] / 1e3, "b-", label=f"observer ({config.observer_speed_kn:g} kn)")
    ax.plot(pt[:, 0] / 1e3, pt[:, 1] / 1e3, "r-", label=f"target ({config.target_speed_kn:g} kn)")
    ax.plot(po[0, 0] / 1e3, po[0, 1] / 1e3, "bo")
    ax.plot(pt[0, 0] / 1e3, pt[0, 1] / 1e3, "ro")
    ax.plot(pt[k0, 0] / 1e3, pt[k0, 1] / 1e3, "r^", label=f"target turn ({config.target_turn_start_s:g} s)")
    for a, _, _ in config.observer_turns:
        k = int(np.searchsorted(t, a))
        ax.plot(po[k, 0] / 1e3, po[k, 1] / 1e3, "bs", ms=5)
    for k in range(0, len(t), max(1, len(t) // 12)):
        ax.plot([po[k, 0] / 1e3, pt[k, 0] / 1e3], [po[k, 1] / 1e3, pt[k, 1] / 1e3], color="0.75", lw=0.6)
    ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal",
           title=f"Scenario: {config.duration_s / 60:g} min, T = {config.sample_period_s:g} s, "
                 f"f0 = {config.f0_hz:g} Hz")
    ax.legend(fontsize=8, loc="upper left")
    return fig

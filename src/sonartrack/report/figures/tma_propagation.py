"""Figures of study P3 (tma-propagation): scenario, profiles, TL fields, SNR against range, errors, SL mismatch."""

from __future__ import annotations

import numpy as np

from sonartrack.studies.tma_propagation import RMSE_LIMIT_PCT, as_floats


def figures(summary: dict, config) -> dict:
    """Scenario, sound-speed profiles, TL fields, SNR against range, start-point errors, SL mismatch (Fig. 7)."""
    return {"scenario": scenario_figure(summary, config), "sound_speed": _profiles_figure(config),
            "tl_fields": _tl_fields_figure(config), "snr_vs_range": _snr_figure(summary, config),
            "error_scatter": _error_figure(summary, config), "sl_mismatch": _mismatch_figure(summary)}


def _profiles_figure(config):
    import matplotlib.pyplot as plt

    from sonartrack.acoustics.environment import load_environment

    fig, axes = plt.subplots(1, 3, figsize=(13, 4.5))
    for ax, sea in zip(axes, ("east", "yellow", "south"), strict=True):
        for env in [e for e in config.environments if e.startswith(sea)]:
            e = load_environment(env)
            ax.plot(e.sound_speed_mps, e.depth_m, label=env)
        ax.invert_yaxis()
        ax.set(xlabel="sound speed (m/s)", ylabel="depth (m)", title=f"{sea.title()} Sea profiles (TEOS-10)")
        if ax.lines:
            ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _tl_fields_figure(config):
    import matplotlib.pyplot as plt

    from sonartrack.acoustics.environment import load_environment
    from sonartrack.io.environment import cached_tl_field

    fig, axes = plt.subplots(2, 3, figsize=(15, 7))
    for ax, env in zip(axes.T.ravel(), config.environments, strict=False):
        depth = config.sensor_depth_m[config.sea(env)]
        f = cached_tl_field(load_environment(env), config.freq_hz, depth, rmax_m=1.05 * config.em_map.r_max_m)
        im = ax.pcolormesh(f.ranges_m / 1e3, f.depths_m, f.tl_db, vmin=50, vmax=110, cmap="jet_r", shading="auto")
        ax.invert_yaxis()
        ax.set(title=f"TL {env}, source {depth:g} m", xlabel="range (km)", ylabel="depth (m)")
        fig.colorbar(im, ax=ax, label="TL (dB)")
    fig.tight_layout()
    return fig


def _snr_figure(summary: dict, config):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 4.5))
    for env, v in summary["environments"].items():
        line, = ax.plot(v["snr_ranges_km"], v["snr_db"], lw=1, label=env)
        ax.axvline(v["initial_range_m"] / 1e3, color=line.get_color(), ls=":", lw=1)
    ax.axhline(config.detection_threshold_db, color="k", lw=0.8)
    ax.set(xlabel="range (km)", ylabel="SNR (dB)", title="SNR = SL - TL + DI - NL at the sensor depth "
           "(dotted: the target's initial range)", ylim=(-40, 60))
    ax.legend(fontsize=7)
    return fig


def _error_figure(summary: dict, config):
    import matplotlib.pyplot as plt

    envs = summary["environments"]
    fig, axes = plt.subplots(2, 3, figsize=(13, 7.5))
    for ax, env in zip(axes.T.ravel(), config.environments, strict=False):
        em = np.array([as_floats(r) for r in envs[env]["start_errors_em"]]).reshape(-1, 2)
        ml = np.array([as_floats(r) for r in envs[env]["start_errors_ml"]]).reshape(-1, 2)
        ax.plot(ml[:, 0], ml[:, 1], "x", ms=4, label="bearings-only ML")
        ax.plot(em[:, 0], em[:, 1], "o", ms=3, label="EM/MAP")
        ax.axhline(0, color="k", lw=0.5)
        ax.axvline(0, color="k", lw=0.5)
        ax.set(title=f"start-point errors {env}", xlabel="X error (% of range)", ylabel="Y error (% of range)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _mismatch_figure(summary: dict):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 4.5))
    for env, v in summary["environments"].items():
        ax.plot(summary["deltas_db"], as_floats(v["sweep_rmse_pct"]), "o-", ms=3, label=env)
    ax.axhline(RMSE_LIMIT_PCT, color="k", ls="--", lw=0.8)
    ax.set(yscale="log", xlabel="assumed SL - true SL (dB)", ylabel="normalised range RMSE (%)",
           title="SL mismatch (paper Fig. 7)")
    ax.legend(fontsize=7)
    return fig


def scenario_figure(summary: dict, config):
    """The observer's track and, per sea, the summer target's track from its placed initial range."""
    import matplotlib.pyplot as plt

    t = config.times_s()
    po, _, _ = config.observer().state(t)
    fig, ax = plt.subplots(figsize=(7, 6))
    ax.plot(po[:, 0] / 1e3, po[:, 1] / 1e3, "k-", lw=2, label="observer (two course changes)")
    for env, v in summary["environments"].items():
        if env.endswith("summer"):
            pt, _, _ = config.target(v["initial_range_m"]).state(t)
            ax.plot(pt[:, 0] / 1e3, pt[:, 1] / 1e3, "-",
                    label=f"target, {config.sea(env)} Sea ({v['initial_range_m'] / 1e3:.1f} km)")
            ax.plot(pt[0, 0] / 1e3, pt[0, 1] / 1e3, "o", color=ax.lines[-1].get_color())
    ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal",
           title=f"{config.n_frames} frames x {config.frame_period_s:g} s; target from bearing "
                 f"{config.target_bearing_deg:g} deg")
    ax.legend(fontsize=7)
    return fig

"""Figures of the quiet-target study: the fraction of time the quiet target is held against its level for each
front end (the signal-level scenes), and Pd against level for single-window and MFTD detection on the bearing-time
record (both cell statistics) and for the narrowband line detector with one window and with long integration."""

from __future__ import annotations


def figures(summary: dict, config) -> dict:
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    for ax, stat in zip(axes[:2], ("gaussian", "exponential"), strict=True):
        s = summary[stat]
        ax.plot(s["snr_db"], s["pd_single"], "o-", label="single window")
        ax.plot(s["snr_db"], s["pd_mftd"], "s-", label=f"MFTD, K = {summary['frames']}")
        ax.set(xlabel="target cell SNR (dB)", ylabel="Pd", ylim=(0, 1.02),
               title=f"{stat} cells, pfa {summary['pfa']:g} per beam and window")
        ax.legend(fontsize=8)
    lf = summary["lofar"]
    axes[2].plot(lf["tonal_db"], lf["pd_1"], "o-", label="one window")
    axes[2].plot(lf["tonal_db"], lf["pd_long"], "s-", label=f"{lf['integration']} windows averaged")
    axes[2].set(xlabel="tonal bin SNR (dB)", ylabel="Pd", ylim=(0, 1.02), title="narrowband line detection")
    axes[2].legend(fontsize=8)
    fig.tight_layout()
    out = {"pd": fig}
    if "scenes" in summary:
        out = {"held": held_figure(summary["scenes"]), **out}
    return out


#: the front ends of the scene sweep as the summary names them, and their labels
FRONT_ENDS = {"broadband": "broadband (start at z >= 6)", "broadband_low_init": "broadband (start at z >= 4)",
              "mftd": "MFTD on the bearing-time record", "narrowband": "narrowband (LOFAR lines)"}


def held_figure(scenes: dict):
    """Held fraction of the quiet target against its broadband level per hydrophone, one curve per front end,
    with the 80 % line and each front end's detection level (its interval as a bar)."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    x = scenes["levels_db"]
    for key, label in FRONT_ENDS.items():
        if f"held_{key}" not in scenes:
            continue
        line, = ax.plot(x, scenes[f"held_{key}"], "o-", label=label)
        lvl = scenes.get(f"level80_{key}")
        if lvl and all(v is not None for v in lvl):
            shift = 0.0 if key != "narrowband" else x[0] - scenes["tonal_db"][0]  # tonal level -> broadband axis
            ax.errorbar([lvl[0] + shift], [0.8], xerr=[[lvl[0] - lvl[1]], [lvl[2] - lvl[0]]], fmt="D",
                        color=line.get_color(), capsize=3)
    ax.axhline(0.8, color="0.6", lw=0.8, ls="--")
    gap = scenes["tonal_db"][0] - x[0]
    ax.set(xlabel=f"quiet target broadband level per hydrophone (dB; its tonal {gap:+.0f} dB)",
           ylabel="fraction of judged windows held", ylim=(-0.02, 1.05),
           title="Quiet target beside louder traffic: held against level")
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    return fig

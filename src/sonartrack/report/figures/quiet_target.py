"""Figures of the quiet-target study: Pd against level for single-window and MFTD detection on the bearing-time
record (both cell statistics), and for the narrowband line detector with one window and with long integration."""

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
    return {"pd": fig}

"""Figures of study P0 (JPDA vs JPDA_A): the end-to-end waterfall, success rates against psi and L, a
synthetic crossing, and the paper's peak-model histograms (studies/jpda_amplitude.py)."""

from __future__ import annotations

import numpy as np

from sonartrack.studies import jpda_amplitude as study


def figures(summary: dict, config) -> dict:
    figs = {"scenario": waterfall_figure(summary["e2e"], "End-to-end from sound: peaks and tracks "
                                                         "(Figs. 2, 9-11 analogue)"),
            "success_rates": success_rates_figure(summary)}
    e = study.synthetic_example(config)
    figs["synthetic_example"] = waterfall_figure(e, f"Synthetic peaks, crossing at psi = {e['psi_deg']:g} deg, "
                                                    "strong/weak")
    figs["peak_model"] = peak_model_figure(*study.peak_model_sample(config), gate_deg=config.tracker.gate_deg)
    return figs


def success_rates_figure(summary: dict):
    """Success rate with its 95 % interval against psi and L, both cases and trackers (paper Fig. 8)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4))
    for ax, kind, xlabel in ((axes[0], "psi", "crossing angle psi (deg)"), (axes[1], "L", "minimum distance L (deg)")):
        for case, ls in (("strong_weak", "-"), ("similar", "--")):
            for tr, mk in (("jpda", "o"), ("jpda_a", "s")):
                v, r, lo, hi = study.split_rates(summary, f"{case}_{tr}", kind)
                ax.errorbar(v, r, yerr=[r - lo, hi - r], ls=ls, marker=mk, ms=4, capsize=2,
                            label=f"{'JPDA_A' if tr == 'jpda_a' else 'JPDA'}, {case.replace('_', '/')}")
        ax.set(xlabel=xlabel, ylabel="success rate", ylim=(0, 1.05), title=f"Success vs {kind} (paper Fig. 8)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    return fig


def waterfall_figure(e: dict, title: str):
    """Peaks (amplitude as colour) with the true bearings and both trackers' estimates, side by side."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    truth = np.asarray(e["truth"])
    t = np.arange(len(truth))
    for ax, tr in zip(axes, study.TRACKERS, strict=True):
        sc = ax.scatter(e["peaks_b"], e["peaks_t"], c=e["peaks_a"], s=4, cmap="viridis", vmin=5000, vmax=30000)
        ax.plot(truth[:, 0], t, "k:", lw=1)
        ax.plot(truth[:, 1], t, "k:", lw=1)
        est = np.asarray(e[f"est_{tr}"])
        ax.plot(est[:, 0], t, "r-", lw=1.5, label="track 1")
        ax.plot(est[:, 1], t, "m-", lw=1.5, label="track 2")
        ax.set(xlabel="cone angle (deg)", title=f"{'JPDA_A' if tr == 'jpda_a' else 'JPDA'}: "
               f"{'kept' if e[f'success_{tr}'] else 'swapped/lost'}", xlim=(0, 180))
        ax.legend(fontsize=7)
    axes[0].set_ylabel("time (s)")
    axes[0].invert_yaxis()
    fig.colorbar(sc, ax=axes, label="peak amplitude")
    fig.suptitle(title)
    return fig


def peak_model_figure(scans, truth, fit, *, gate_deg: float):
    """The paper's histograms of the peak model with the fitted parameters in the title."""
    fig = peak_histograms_figure(scans, truth, gate_deg)
    fig.suptitle(f"Peak model ({len(scans)} synthetic scans, threshold 0); fitted: lambda V {fit.false_rate:.2f}, "
                 f"alpha {fit.false_amplitude_rate:.2e}, sigma_p {np.round(fit.sigma_p_deg, 2).tolist()} deg, z_a "
                 f"{np.round(fit.amplitude_mean, -1).tolist()}, sigma_a {np.round(fit.amplitude_sd, -1).tolist()}",
                 fontsize=8)
    fig.tight_layout()
    return fig


def _gate_samples(scans, ref, gate_deg: float):
    """Per track: peak counts per gate, positions and amplitudes inside it; amplitudes outside every gate."""
    n = ref.shape[1]
    counts, pos, amp = ([[] for _ in range(n)] for _ in range(3))
    background = []
    for (b, a), r in zip(scans, ref, strict=True):
        b, a = np.asarray(b), np.asarray(a)
        near = np.zeros(len(b), dtype=bool)
        for i in range(n):
            inside = np.abs(b - r[i]) <= gate_deg / 2
            near |= inside
            counts[i].append(int(inside.sum()))
            pos[i].extend((b[inside] - r[i]).tolist())
            amp[i].extend(a[inside].tolist())
        background.extend(a[~near].tolist())
    return counts, pos, amp, background


def peak_histograms_figure(scans, reference_deg, gate_deg: float = 10.0, labels=("strong track", "weak track")):
    """The paper's histograms: peaks per gate, positions about each track, amplitudes (tracks, background)."""
    import matplotlib.pyplot as plt

    ref = np.atleast_2d(np.asarray(reference_deg, dtype=float))
    counts, pos, amp, background = _gate_samples(scans, ref, gate_deg)
    fig, axes = plt.subplots(1, 3, figsize=(14, 3.8))
    for i in range(ref.shape[1]):
        lab = labels[i] if i < len(labels) else f"track {i + 1}"
        axes[0].hist(counts[i], bins=np.arange(0, max(max(counts[i], default=0), 1) + 2) - 0.5, alpha=0.5, label=lab)
        axes[1].hist(pos[i], bins=40, alpha=0.5, label=lab)
        axes[2].hist(amp[i], bins=40, alpha=0.5, label=lab)
    axes[2].hist(background, bins=40, alpha=0.5, label="background")
    axes[0].set(xlabel="peaks in the gate", ylabel="scans", title="Peak count per gate")
    axes[1].set(xlabel="peak - track bearing (deg)", title="Peak positions")
    axes[2].set(xlabel="amplitude", title="Peak amplitudes")
    for ax in axes:
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig

"""Range-Doppler pictures: frames as images with tracks over them (``sonartrack detect``, study P1)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.io.atomic import save_figure


def frames_figure(frames: np.ndarray, grid, title: str = ""):
    """One panel per frame (range across, range-rate up, cell value as colour); returns (fig, axes).

    A bare :class:`matplotlib.figure.Figure` (no pyplot state, any backend): save it or show it."""
    from matplotlib.figure import Figure

    K = frames.shape[0]
    r0, r1, v0, v1 = grid.extent()
    fig = Figure(figsize=(2.3 * K, 3.6))
    axes = fig.subplots(1, K, sharey=True, squeeze=False)
    axes = axes[0]
    for k, ax in enumerate(axes):
        ax.imshow(frames[k].T, origin="lower", aspect="auto", extent=(r0, r1, v0, v1), cmap="viridis")
        ax.set(title=f"frame {k + 1}", xlabel="range (m)")
    axes[0].set_ylabel("range-rate (m/s)")
    if title:
        fig.suptitle(title, fontsize=9)
    return fig, axes


def detection_png(path: Path, detection) -> Path:
    """The frames a detection saw with its best track drawn over them (red: the track's cell), saved atomically."""
    verdict = "target present" if detection.present else "no target"
    fig, axes = frames_figure(detection.frames, detection.grid,
                              f"{verdict}: statistic {detection.statistic:.2f}, threshold {detection.threshold:.2f}; "
                              "red: best track")
    c = detection.best_track_centres()
    for k, ax in enumerate(axes):
        ax.plot(c[: k + 1, 0], c[: k + 1, 1], "w-", lw=0.8)
        ax.plot(*c[k], "rs", mfc="none", ms=9)
    fig.tight_layout()
    return save_figure(fig, path, dpi=100)

"""Position-track pictures: confirmed tracks drawn over the contacts (``sonartrack track --contacts``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.io.atomic import save_figure


def tracks_png(path: Path, contacts_xy_m, table) -> Path:
    """Confirmed tracks of ``table`` (tracking/run.py's track_contacts) over the contacts (k, 2), in km."""
    import matplotlib.pyplot as plt

    z = np.asarray(contacts_xy_m, float)
    fig, ax = plt.subplots(figsize=(7, 7))
    ax.plot(z[:, 0] / 1e3, z[:, 1] / 1e3, ".", color="0.7", ms=2, label="contacts")
    conf = table[table.status == "confirmed"]
    for tid, g in conf.groupby("track_id"):
        ax.plot(g.x_m / 1e3, g.y_m / 1e3, "-", lw=1.5, label=f"track {tid}")
    ax.set(xlabel="x east (km)", ylabel="y north (km)", title="Confirmed tracks over contacts", aspect="equal")
    if conf.track_id.nunique() <= 12:
        ax.legend(fontsize=7)
    return save_figure(fig, path, dpi=110, bbox_inches="tight", format="png")

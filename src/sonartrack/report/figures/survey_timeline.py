"""The survey's targets over time: one row per recording, a bar per target from its first to its last ML solution,
in UTC when every recording's start is known, else in hours from the recording's start."""

from __future__ import annotations

from datetime import datetime, timedelta
from pathlib import Path


def write_targets_timeline(targets, names: list[str], starts: dict, path) -> Path | None:
    """Draw the chart (module doc) into ``path`` (PNG, atomically).

    Parameters
    ----------
    targets : pandas.DataFrame
        systems/survey/files.py ``survey_targets``: recording, target_id, first_s, last_s.
    names : list of str
        The recordings with status ok, one row each, in this order.
    starts : dict
        Recording name -> its UTC start (ISO text) or None.
    path : path
        The PNG file.

    Returns
    -------
    Path or None
        ``path``; None (nothing written) when there is no target.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from sonartrack.io.atomic import save_figure

    if targets.empty:
        return None
    utc = all(starts.get(n) for n in targets["recording"])
    fig = Figure(figsize=(9, 1.2 + 0.45 * len(names)))
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    counts = targets.groupby("recording").size()
    for j, (_, t) in enumerate(targets.iterrows()):
        k = j - int(targets.index[targets["recording"] == t["recording"]][0])  # the target's place in its row
        y = names.index(t["recording"]) + 0.6 * ((k + 0.5) / counts[t["recording"]] - 0.5)
        if utc:
            s0 = datetime.fromisoformat(starts[t["recording"]])
            x0, x1 = s0 + timedelta(seconds=float(t["first_s"])), s0 + timedelta(seconds=float(t["last_s"]))
        else:
            x0, x1 = float(t["first_s"]) / 3600.0, float(t["last_s"]) / 3600.0
        ax.plot([x0, x1], [y, y], lw=4, solid_capstyle="butt", alpha=0.8)
        ax.annotate(f"{t['target_id']}", (x1, y), xytext=(3, 0), textcoords="offset points", va="center", fontsize=7)
    ax.set_yticks(range(len(names)), names)
    ax.set_ylim(-0.7, len(names) - 0.3)
    ax.set_xlabel("time (UTC)" if utc else "hours from the recording's start")
    ax.set_title("targets over time (a bar per target, labelled by its id: first to last ML solution)")
    if utc:
        fig.autofmt_xdate()
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)

"""The active chain on files: a scene folder (pings/, ping_table.csv) and a navigation CSV in, tables out.

Reading goes through the checked readers of ``systems/active/scene_files.py`` (one ping in memory at a time).
Written into the output folder, all or nothing (every file is rendered in memory before the first is written,
and each is written atomically, so a failure leaves no half-written output):

* detections.csv: one row per detection of both detectors (``detector`` = mftd | single): ping, time_s,
  cone_deg, travel_time_s, doppler_hz, range_rate_mps (NaN for an LFM), statistic (single: the normalised
  statistic s; mftd: P1's log statistic S), beam, delay_cell, doppler_cell;
* contacts.csv: the tracked detector's mirror pairs, in the Cartesian contact format of ``sonartrack track``
  (time_s, x_m, y_m, var_x_m2, var_y_m2, cov_xy_m2) plus ping, detection (row of detections.csv among the
  tracked detector's), side (starboard | port), range_rate_mps, rx_range_m, statistic and gated (False: kept
  from the tracker by the range-rate gate);
* tracks.csv: one row per live track per ping: time_s, track_id, status (confirmed | tentative), existence,
  x_m, y_m, vx_mps, vy_mps, sd_x_m, sd_y_m, mode_prob_<j> (tracking/run.py), and sd_vx_mps, sd_vy_mps,
  cov_xy_m2;
* sides.csv: the left/right decision of each confirmed track (systems/active/sides.py: decision, side, ln LR,
  time resolved).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sonartrack.core.errors import require
from sonartrack.systems.active.run import ActiveResult, run_active
from sonartrack.systems.active.settings import ActiveSettings

DETECTION_COLUMNS = ["detector", "ping", "time_s", "cone_deg", "travel_time_s", "doppler_hz", "range_rate_mps",
                     "statistic", "beam", "delay_cell", "doppler_cell"]
CONTACT_COLUMNS = ["time_s", "x_m", "y_m", "var_x_m2", "var_y_m2", "cov_xy_m2", "ping", "detection", "side",
                   "range_rate_mps", "rx_range_m", "statistic", "gated"]


def scene_folder(pings) -> Path:
    """The folder holding ping_table.csv: ``pings`` itself, or its parent when ``pings`` is the pings/ folder.

    Parameters
    ----------
    pings : str or path-like
        The scene folder or its pings/ folder; an InputError when it is not a folder or neither it nor its parent
        holds ping_table.csv.

    Returns
    -------
    Path
        The scene folder (the first of ``pings``, its parent that holds ping_table.csv).
    """
    from sonartrack.systems.active.scene_files import PING_TABLE

    p = Path(pings)
    require(p.is_dir(), f"--pings {p}: no such folder: give the scene folder holding {PING_TABLE} and pings/")
    found = [folder for folder in (p, p.parent) if (folder / PING_TABLE).is_file()]
    require(bool(found), f"--pings {p}: no {PING_TABLE} in it or its parent: give the scene folder of the pings")
    return found[0]


def run_active_files(pings, nav_path, settings: ActiveSettings, *, progress=None) -> ActiveResult:
    """Read the ping table and the navigation, check them, and run the chain over the pings.

    Parameters
    ----------
    pings : str or path-like
        The scene folder (ping_table.csv and pings/), or its pings/ folder.
    nav_path : str or path-like
        The navigation CSV (source, array centre and axis against time).
    settings : ActiveSettings
        The chain's settings (``spacing_m`` required).
    progress : optional
        Progress hooks, advanced once per ping.

    Returns
    -------
    ActiveResult
        The chain's result.
    """
    from sonartrack.systems.active import scene_files as sf

    folder = scene_folder(pings)
    table = sf.read_ping_table(folder / sf.PING_TABLE)
    require(len(table) >= 1, f"{folder / sf.PING_TABLE} lists no ping")
    nav = sf.read_active_nav(nav_path)
    sf.check_nav_covers(table, nav)
    return run_active(sf.iter_pings(folder, table), table, nav, settings, progress=progress)


def detections_table(result: ActiveResult):
    """detections.csv (module doc).

    Parameters
    ----------
    result : ActiveResult
        The chain's result (its ``mftd`` and ``single`` detections).

    Returns
    -------
    pandas.DataFrame
        The MFTD detections then the single-ping ones, columns ``DETECTION_COLUMNS`` (times s, cone angle deg from
        the array axis, Doppler Hz, range rate m/s).
    """
    import pandas as pd

    parts = []
    for name, d in (("mftd", result.mftd), ("single", result.single)):
        cols = {c: getattr(d, c) for c in DETECTION_COLUMNS[1:]}
        parts.append(pd.DataFrame({"detector": np.full(len(d), name), **cols}))
    return pd.concat(parts, ignore_index=True)


def contacts_table(result: ActiveResult):
    """contacts.csv (module doc).

    Parameters
    ----------
    result : ActiveResult
        The chain's result (its ``contacts`` and ``gated_out``).

    Returns
    -------
    pandas.DataFrame
        One row per contact, columns ``CONTACT_COLUMNS``: positions x east, y north (m), covariance (m^2),
        ``side`` starboard | port.
    """
    import pandas as pd

    c = result.contacts
    return pd.DataFrame({"time_s": c.time_s, "x_m": c.xy[:, 0], "y_m": c.xy[:, 1], "var_x_m2": c.R[:, 0, 0],
                         "var_y_m2": c.R[:, 1, 1], "cov_xy_m2": c.R[:, 0, 1], "ping": c.ping, "detection": c.detection,
                         "side": np.where(c.side > 0, "starboard", "port"), "range_rate_mps": c.range_rate_mps,
                         "rx_range_m": c.rx_range_m, "statistic": c.statistic, "gated": result.gated_out},
                        columns=CONTACT_COLUMNS)


def tracks_table(result: ActiveResult):
    """tracks.csv (module doc).

    Parameters
    ----------
    result : ActiveResult
        The chain's result (its ``tracks``).

    Returns
    -------
    pandas.DataFrame
        The tracker's frame plus ``sd_vx_mps``, ``sd_vy_mps`` (m/s) and ``cov_xy_m2`` (m^2) from the covariances.
    """
    t, P = result.tracks.tracks, result.tracks.P
    df = t.to_frame()
    df["sd_vx_mps"], df["sd_vy_mps"], df["cov_xy_m2"] = np.sqrt(P[:, 2, 2]), np.sqrt(P[:, 3, 3]), P[:, 0, 1]
    return df


def sides_table(result: ActiveResult):
    """sides.csv: the side decision of each track.

    Parameters
    ----------
    result : ActiveResult
        The chain's result (its ``tracks.sides``, None when no side decision was made).

    Returns
    -------
    pandas.DataFrame
        Columns track_id, decision, side, log_lr, resolved_s (s), contacts; no rows when there are no decisions.
    """
    import pandas as pd

    d = result.tracks.sides
    cols = ["track_id", "decision", "side", "log_lr", "resolved_s", "contacts"]
    if d is None:
        return pd.DataFrame(columns=cols)
    return pd.DataFrame({c: getattr(d, c) for c in cols}, columns=cols)


def write_active_tables(result: ActiveResult, out, extra: dict | None = None) -> list[Path]:
    """detections.csv, contacts.csv and tracks.csv (and ``extra`` files) into ``out``, all or nothing.

    Every file is rendered in memory first (a failure there writes nothing), then written to its hidden temporary
    sibling (io/atomic.py ``atomic_path``); only when every one is complete are they renamed over their names, one
    rename each. A failure while writing (a full disk, a file-size limit) removes the temporaries and leaves
    ``out`` as it was, an earlier run's files included.

    Parameters
    ----------
    result : ActiveResult
        The chain's result.
    out : str or path-like
        The output folder (created).
    extra : dict, optional
        More files: name -> content (str or bytes), e.g. the pictures and the page.

    Returns
    -------
    list of Path
        The files written, in ``out``.
    """
    from contextlib import ExitStack

    from sonartrack.io.atomic import atomic_path
    from sonartrack.systems.active.scene_files import write_error

    files = {name: frame.to_csv(index=False) for name, frame in (("detections.csv", detections_table(result)),
                                                                   ("contacts.csv", contacts_table(result)),
                                                                   ("tracks.csv", tracks_table(result)),
                                                                   ("sides.csv", sides_table(result)))}
    files.update(extra or {})
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with ExitStack() as renames:  # each atomic_path renames on a clean exit, all of them after the last write
        for name, data in files.items():
            tmp = renames.enter_context(atomic_path(out / name))
            try:
                tmp.write_bytes(data if isinstance(data, bytes) else data.encode("utf-8"))
            except OSError as exc:  # the file's name in the one-line message (a write error carries none)
                raise write_error(exc, out / name) from None
    return [out / name for name in files]


def _side(result: ActiveResult, t_s: float, xy) -> str:
    """starboard / port of the array axis at ``t_s`` for a position."""
    g = result.geometry
    h = float(g.heading_at(t_s))
    d = np.asarray(xy, float) - g.rx_at(t_s)
    return "starboard" if np.sin(np.arctan2(d[0], d[1]) - h) >= 0 else "port"


def track_line(result: ActiveResult, track_id: int) -> str:
    """One line for a confirmed track: span, last estimate with sds, speed and course, existence, modes, side.

    Parameters
    ----------
    result : ActiveResult
        The chain's result.
    track_id : int
        A track that was confirmed at least once.

    Returns
    -------
    str
        Positions and sds in km (x east, y north), speed in knots, course in deg clockwise from north, side of the
        array axis at the last estimate, and the side decision in words.
    """
    t = result.tracks.tracks
    rows = np.nonzero(t.track_id == track_id)[0]
    conf = rows[t.confirmed[rows]]
    last = rows[-1]
    x = t.x[last]
    speed = float(np.hypot(x[2], x[3]))
    course = float(np.rad2deg(np.arctan2(x[2], x[3])) % 360.0)
    modes = "/".join(f"{m:.2f}" for m in t.mode_prob[last])
    return (f"track {track_id}: confirmed {t.time_s[conf[0]]:.0f}..{t.time_s[conf[-1]]:.0f} s ({len(conf)} pings); "
            f"at {t.time_s[last]:.0f} s ({x[0] / 1e3:.2f}, {x[1] / 1e3:.2f}) km ± ({t.sd_x_m[last] / 1e3:.2f}, "
            f"{t.sd_y_m[last] / 1e3:.2f}), {speed / 0.514444:.1f} kn course {course:.0f} deg, "
            f"{_side(result, t.time_s[last], x[:2])} of the array; existence {t.existence[last]:.2f}, "
            f"mode probabilities {modes}; {_side_text(result, track_id)}")


def _side_text(result: ActiveResult, track_id: int) -> str:
    """The track's side decision in words (sides.py)."""
    d = result.tracks.sides
    k = None if d is None else d.of(track_id)
    if k is None or d.decision[k] == "undecided":
        lr = "" if k is None else f" (ln LR {d.log_lr[k]:+.1f})"
        return f"side undecided{lr}"
    what = "on its target's side" if d.decision[k] == "track" else "a mirror ghost"
    return f"{what}: target {d.side[k]} (ln LR {d.log_lr[k]:+.1f}, from {d.resolved_s[k]:.0f} s)"


def summary_lines(result: ActiveResult) -> list[str]:
    """One line per confirmed track, or one line saying that nothing was confirmed.

    Parameters
    ----------
    result : ActiveResult
        The chain's result.

    Returns
    -------
    list of str
        :func:`track_line` of each confirmed track in order of first confirmation, or one line with the numbers
        of pings, detections and contacts.
    """
    t = result.tracks.tracks
    ids = list(dict.fromkeys(t.track_id[t.confirmed].tolist()))
    if not ids:
        return [f"active: no confirmed track in {len(result.ping_time_s)} pings ({len(result.detections)} "
                f"{result.settings.detector} detections, {len(result.contacts)} contacts)"]
    return [track_line(result, i) for i in ids]

"""The active chain on files: a scene folder (pings/, ping_table.csv) and a navigation CSV in, tables out.

Reading goes through the checked readers of ``systems/active/scene_files.py`` (one ping in memory at a time).
Written into the output folder, all or nothing (every file is rendered in memory before the first is written,
and each is written atomically, so a failure leaves no half-written output):

* detections.csv: first the tracked detections, the rows contacts.csv's ``detection`` counts (``detector`` = mftd
  or strong, a strong single-ping one the MFTD missed; single when the single-ping detector is tracked), then,
  when the MFTD ran, every single-ping detection (``detector`` = single; a strong one appears in both): ping, time_s,
  cone_deg, travel_time_s, doppler_hz, range_rate_mps (NaN for an LFM), statistic (single: the normalised
  statistic s; mftd: P1's log statistic S), beam, delay_cell, doppler_cell;
* contacts.csv: the tracked detector's mirror pairs, in the Cartesian contact format of ``sonartrack track``
  (time_s, x_m, y_m, var_x_m2, var_y_m2, cov_xy_m2) plus ping, detection (row of detections.csv among the
  tracked detector's), side (starboard | port), range_rate_mps, rx_range_m, statistic and gated (False: kept
  from the tracker by the range-rate gate);
* tracks.csv: one row per live track per ping: time_s, track_id, status (confirmed | tentative), existence,
  x_m, y_m, vx_mps, vy_mps, sd_x_m, sd_y_m, mode_prob_<j> (tracking/run.py), sd_vx_mps, sd_vy_mps, cov_xy_m2, and
  the row's ``target`` and ``hypothesis`` (below; target empty and hypothesis "" for a track never confirmed);
* sides.csv: one row per target (below): target, decision (decided | undecided), side (the target's side when
  decided), track_id and track_side (decided: the track on the target's side; undecided: the pair's
  first-confirmed track and its side of the array), mirror_track_id (the other hypothesis's track; empty: none
  confirmed), log_lr (ln LR of track_id's side against the other, systems/active/sides.py), resolved_s (the ping
  the side was decided from), first_s, last_s (confirmed span), x_m, y_m (track_id's last position) and
  mirror_x_m, mirror_y_m (the other hypothesis's: its track's last position, or the reflection of x_m, y_m about
  the array's axis when undecided with no confirmed twin; empty for a decided target with no twin).

Targets, not tracks (systems/active/targets.py). A line array gives each echo two mirror contacts, so a target is
tracked on both sides of the array until the array's turn decides its side. A confirmed track and its mirror twin
(the track that took the other contact of the same detections) are ONE target with two hypotheses: ``target``
numbers them 1.. in order of first confirmation, and each track row says which hypothesis it is: ``starboard`` |
``port`` while the side is undecided (the target is here if it is on that side of the array), ``decided`` from
the ping its side was decided on, ``mirror`` for the rejected twin of a decided target (which the chain deletes
at the next ping). The summary lines and the page list targets (decided ones, then undecided mirror pairs with
both positions), never a ghost as a target of its own.
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
        The chain's result (its tracked ``detections`` and ``single`` ones).

    Returns
    -------
    pandas.DataFrame
        The tracked detections (the rows contacts.csv's ``detection`` counts) then, when the MFTD ran, every
        single-ping one; columns ``DETECTION_COLUMNS`` (times s, cone angle deg from the array axis, Doppler Hz,
        range rate m/s).
    """
    import pandas as pd

    tracked = result.detections
    kind = result.detection_kind if len(result.detection_kind) == len(tracked) else np.full(
        len(tracked), result.settings.detector, dtype=object)
    blocks = [(kind, tracked)] + ([(np.full(len(result.single), "single", dtype=object), result.single)]
                                  if tracked is not result.single else [])
    parts = [pd.DataFrame({"detector": k, **{c: getattr(d, c) for c in DETECTION_COLUMNS[1:]}}) for k, d in blocks]
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


def targets_of(result: ActiveResult):
    """The run's targets: confirmed tracks grouped with their mirror twins (systems/active/targets.py).

    Parameters
    ----------
    result : ActiveResult
        The chain's result (its tracks, side decisions and geometry).

    Returns
    -------
    MirrorTargets
        One row per target.
    """
    from sonartrack.systems.active.targets import mirror_targets

    return mirror_targets(result.tracks, result.geometry)


def _ids(v):
    """Track ids as a nullable integer column (-1, none, written empty)."""
    import pandas as pd

    return pd.array(np.where(np.asarray(v) < 0, None, np.asarray(v)), dtype="Int64")


def tracks_table(result: ActiveResult, targets=None):
    """tracks.csv (module doc).

    Parameters
    ----------
    result : ActiveResult
        The chain's result (its ``tracks``).
    targets : MirrorTargets, optional
        Its targets (default: :func:`targets_of`).

    Returns
    -------
    pandas.DataFrame
        The tracker's frame plus ``sd_vx_mps``, ``sd_vy_mps`` (m/s) and ``cov_xy_m2`` (m^2) from the covariances, and
        each row's ``target`` (empty: never confirmed) and ``hypothesis``.
    """
    from sonartrack.systems.active.targets import track_hypotheses

    t, P = result.tracks.tracks, result.tracks.P
    df = t.to_frame()
    df["sd_vx_mps"], df["sd_vy_mps"], df["cov_xy_m2"] = np.sqrt(P[:, 2, 2]), np.sqrt(P[:, 3, 3]), P[:, 0, 1]
    target, hypothesis = track_hypotheses(result.tracks, targets_of(result) if targets is None else targets,
                                          result.geometry)
    df["target"], df["hypothesis"] = _ids(target), hypothesis
    return df


SIDE_COLUMNS = ["target", "decision", "side", "track_id", "track_side", "mirror_track_id", "log_lr", "resolved_s",
                "first_s", "last_s", "x_m", "y_m", "mirror_x_m", "mirror_y_m"]


def sides_table(result: ActiveResult, targets=None):
    """sides.csv: one row per target, both hypotheses (module doc).

    Parameters
    ----------
    result : ActiveResult
        The chain's result.
    targets : MirrorTargets, optional
        Its targets (default: :func:`targets_of`).

    Returns
    -------
    pandas.DataFrame
        Columns ``SIDE_COLUMNS`` (times s, positions m x east, y north); no rows when no track was confirmed.
    """
    import pandas as pd

    m = targets_of(result) if targets is None else targets
    cols = {c: getattr(m, c) for c in SIDE_COLUMNS[:10]}
    cols["track_id"], cols["mirror_track_id"] = _ids(m.track_id), _ids(m.mirror_track_id)
    cols.update(x_m=m.xy[:, 0], y_m=m.xy[:, 1], mirror_x_m=m.mirror_xy[:, 0], mirror_y_m=m.mirror_xy[:, 1])
    return pd.DataFrame(cols, columns=SIDE_COLUMNS)


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
    """A confirmed track's estimate in words: span, last estimate with sds, speed and course, existence, modes.

    Parameters
    ----------
    result : ActiveResult
        The chain's result.
    track_id : int
        A track that was confirmed at least once.

    Returns
    -------
    str
        Positions and sds in km (x east, y north), speed in knots, course in deg clockwise from north.
    """
    t = result.tracks.tracks
    rows = np.nonzero(t.track_id == track_id)[0]
    conf = rows[t.confirmed[rows]]
    last = rows[-1]
    x = t.x[last]
    speed = float(np.hypot(x[2], x[3]))
    course = float(np.rad2deg(np.arctan2(x[2], x[3])) % 360.0)
    modes = "/".join(f"{m:.2f}" for m in t.mode_prob[last])
    return (f"track {track_id} confirmed {t.time_s[conf[0]]:.0f}..{t.time_s[conf[-1]]:.0f} s ({len(conf)} pings), "
            f"at {t.time_s[last]:.0f} s ({x[0] / 1e3:.2f}, {x[1] / 1e3:.2f}) km ± ({t.sd_x_m[last] / 1e3:.2f}, "
            f"{t.sd_y_m[last] / 1e3:.2f}), {speed / 0.514444:.1f} kn course {course:.0f} deg, existence "
            f"{t.existence[last]:.2f}, mode probabilities {modes}")


def target_line(result: ActiveResult, targets, k: int) -> str:
    """One line for target row ``k``: decided (its side, ln LR, when, the mirror dropped) or an undecided mirror
    pair (both hypotheses' positions), then its track's estimate (:func:`track_line`).

    Parameters
    ----------
    result : ActiveResult
        The chain's result.
    targets : MirrorTargets
        Its targets (:func:`targets_of`).
    k : int
        The row.

    Returns
    -------
    str
        The line (positions in km, x east, y north).
    """
    m = targets
    own, mirror = int(m.track_id[k]), int(m.mirror_track_id[k])
    km = lambda xy: f"({xy[0] / 1e3:.2f}, {xy[1] / 1e3:.2f}) km"  # noqa: E731
    head = f"target {m.target[k]}: "
    if m.decision[k] == "decided":
        drop = f"; mirror track {mirror} dropped" if mirror >= 0 else ""
        head += (f"{m.side[k]}, decided at {m.resolved_s[k]:.0f} s (ln LR {m.log_lr[k]:+.1f}{drop})")
        if own < 0:
            return head + f"; only its mirror was tracked (track {mirror}, last at {km(m.mirror_xy[k])})"
        return head + "; " + track_line(result, own)
    other = m.track_side[k] == "starboard" and "port" or "starboard"
    twin = f"track {mirror}" if mirror >= 0 else "not tracked"
    return (head + f"side undecided (ln LR {m.log_lr[k]:+.1f}): {m.track_side[k]} at {km(m.xy[k])} or {other} at "
            f"{km(m.mirror_xy[k])} ({twin}); " + track_line(result, own))


def summary_lines(result: ActiveResult) -> list[str]:
    """One line for the targets' count, then one per target, or one line saying that nothing was confirmed.

    Parameters
    ----------
    result : ActiveResult
        The chain's result.

    Returns
    -------
    list of str
        The count line and :func:`target_line` of each target in order of first confirmation (decided and
        undecided mirror pairs alike, each pair once), or one line with the numbers of pings, detections and
        contacts.
    """
    m = targets_of(result)
    if not len(m):
        return [f"active: no confirmed track in {len(result.ping_time_s)} pings ({len(result.detections)} "
                f"{result.settings.detector} detections, {len(result.contacts)} contacts)"]
    decided = int((m.decision == "decided").sum())
    pairs = int(((m.decision == "undecided") & (m.mirror_track_id >= 0)).sum())
    head = (f"active: {len(m)} targets in {len(result.ping_time_s)} pings: {decided} with the side decided, "
            f"{len(m) - decided} undecided ({pairs} of them tracked on both sides: one target, two hypotheses)")
    return [head] + [target_line(result, m, k) for k in range(len(m))]

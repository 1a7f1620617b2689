"""Study active-chain's scoring as the user sees the targets: false rows, acquisition latency, turns held on one row.

``sonartrack active`` lists one row per target (systems/active/targets.py :func:`mirror_targets`): an undecided mirror
pair is ONE target with two hypotheses, and segments of one target joined by the chain (``ActiveTracks.joins``) are
one row (issue 34 item 4). The study counts what the user sees:

* a **false row** is a row none of whose confirmed tracks ever came within the gate of a true target or of its
  mirror (a ghost is a hypothesis of a real target, not a false one); the confirmed false tracks are counted beside
  it (a false undecided pair: 1 row, 2 tracks);
* **acquisition latency** (issue 34 item 5): a target *enters* the listening window on its first detectable ping
  (the study's truth grid: expected echo-to-background ratio >= ``detectable_ebr_db``, in the window, clear of
  the blast); its latency is the number of pings from that ping (counted as 1) to the first ping on which a
  confirmed track holds it; it is *at 15 dB* when the median echo-to-background ratio of its first
  ``acquire_pings`` pings from entering is >= the level (pings out of reach count as below);
* **a turn held on one row** (issue 34 item 5): the pings from the last at or before the turn's start to the first at
  or after its end; judged when the target is detectable at both of those end pings; held on one row when a confirmed
  track holds it at both ends and every track holding it in between belongs to the same row (a track of no row, a
  fleeting fragment the chain does not list, is a row of its own);
* **why a detectable ping is not held** (:func:`unheld_causes`, used by benchmarks/bench_active_held.py): the
  detector's miss, acquisition, the holding track deleted, wandered off or given to another target by the
  assignment, and what is near the target then (an undecided track on its mirror, a tentative track, nothing).
"""

from __future__ import annotations

import numpy as np


def row_of_tracks(targets) -> dict[int, int]:
    """Track id -> row index (0-based) of every track of every row (both hypotheses, all joined segments).

    Parameters
    ----------
    targets : MirrorTargets
        The rows (systems/active/targets.py :func:`mirror_targets`).

    Returns
    -------
    dict
        {track id: row index}.
    """
    out: dict[int, int] = {}
    for k in range(len(targets)):
        own, other = targets.chains[k] if targets.chains is not None else ((targets.track_id[k],),
                                                                            (targets.mirror_track_id[k],))
        for tid in (*own, *other):
            if int(tid) >= 0:
                out.setdefault(int(tid), k)
    return out


def near_track_ids(tracks, t_truth, xy_truth, xy_mirror, gate_m: float) -> set[int]:
    """Ids of the confirmed tracks that came within ``gate_m`` of a target or of its mirror at the same time.

    Parameters
    ----------
    tracks : PositionTracks
        The per-ping track table (``time_s``, ``track_id``, ``confirmed``, ``x``).
    t_truth : array (m,)
        Truth times (s).
    xy_truth, xy_mirror : arrays (m, 2)
        True positions and their mirrors about the array's axis (m).
    gate_m : float
        The gate (m).

    Returns
    -------
    set of int
        The track ids.
    """
    t_truth = np.asarray(t_truth, float)
    if not len(t_truth):
        return set()
    order = np.argsort(t_truth, kind="stable")
    ts = t_truth[order]
    points = np.asarray(xy_truth, float)[order], np.asarray(xy_mirror, float)[order]
    tol = 1e-6 * max(1.0, float(np.max(np.abs(ts))))
    near: set[int] = set()
    for r in np.nonzero(tracks.confirmed)[0]:
        tid = int(tracks.track_id[r])
        if tid in near:
            continue
        lo, hi = np.searchsorted(ts, tracks.time_s[r] - tol), np.searchsorted(ts, tracks.time_s[r] + tol, "right")
        if hi > lo and min(np.hypot(*(p[lo:hi] - tracks.x[r, :2]).T).min() for p in points) < gate_m:
            near.add(tid)
    return near


def false_rows(active_tracks, geometry, t_truth, xy_truth, xy_mirror, gate_m: float) -> tuple[int, int, int]:
    """(false rows, rows, false confirmed tracks) of one tracking (module doc); no truth: every row is false.

    Parameters
    ----------
    active_tracks : ActiveTracks
        The chain's tracks (with their side decisions and joins).
    geometry : ActiveGeometry
        The receiver and array heading (the rows' mirror hypotheses).
    t_truth, xy_truth, xy_mirror : arrays (m,), (m, 2), (m, 2)
        Truth times (s), positions and mirrors (m); empty on a reverberation-only scene.
    gate_m : float
        A track within this of a target or its mirror is not false (m).

    Returns
    -------
    tuple of int
        False rows, all rows, false confirmed tracks.
    """
    from sonartrack.systems.active.targets import mirror_targets

    tr = active_tracks.tracks
    near = near_track_ids(tr, t_truth, xy_truth, xy_mirror, gate_m)
    targets = mirror_targets(active_tracks, geometry)
    rows: dict[int, list[int]] = {}
    for tid, k in row_of_tracks(targets).items():
        rows.setdefault(k, []).append(tid)
    n_false = sum(not any(t in near for t in ids) for ids in rows.values())
    tracks_false = sum(int(t) not in near for t in np.unique(tr.track_id[tr.confirmed]))
    return n_false, len(targets), tracks_false


def acquisition_pings(detectable, held) -> np.ndarray:
    """Pings from entering (the first detectable ping, counted as 1) to the first ping at or after it on which the
    target is held (module doc).

    Parameters
    ----------
    detectable, held : bool arrays (..., pings)
        Per target (and run) and ping.

    Returns
    -------
    numpy.ndarray
        (...,) latency in pings: 1 held on its entering ping; inf never held from then; NaN never detectable.
    """
    det, held = np.asarray(detectable, bool), np.asarray(held, bool)
    k = np.arange(det.shape[-1])
    first = np.argmax(det, axis=-1)
    after = held & (k >= first[..., None])
    lat = np.where(after.any(axis=-1), np.argmax(after, axis=-1) - first + 1.0, np.inf)
    return np.where(det.any(axis=-1), lat, np.nan)


def entering_level_db(snr_db, detectable, pings: int) -> np.ndarray:
    """Median echo level (dB: the study's echo-to-background ebr_db, or the echo-to-noise snr_db) of the ``pings``
    pings from a target's entering ping (module doc; NaN, out of reach, counts as below); NaN where the target
    never enters or the scene ends before its ``pings`` pings.

    Parameters
    ----------
    snr_db : array (..., P)
        Echo level per ping, EBR or SNR (NaN where out of reach).
    detectable : bool array (..., P)
        The truth grid's detectable pings.
    pings : int
        The acquisition window (pings).

    Returns
    -------
    numpy.ndarray
        (...,) dB.
    """
    snr, det = np.asarray(snr_db, float), np.asarray(detectable, bool)
    n_p = snr.shape[-1]
    first = np.argmax(det, axis=-1)
    idx = np.clip(first[..., None] + np.arange(max(pings, 1)), 0, n_p - 1)
    window = np.take_along_axis(np.where(np.isfinite(snr), snr, -np.inf), idx, axis=-1)
    med = np.median(window, axis=-1)
    return np.where(det.any(axis=-1) & (first + pings <= n_p), med, np.nan)


def turn_window(ping_time_s, start_s: float | None, turn_deg: float, rate_deg_s: float) -> np.ndarray:
    """(P,) bool: the pings from the last at or before a turn's start to the first at or after its end (all False
    for a target that does not turn or whose turn starts after the last ping).

    Parameters
    ----------
    ping_time_s : array (P,)
        Ping times (s), increasing.
    start_s : float or None
        The turn's start (s); None: no turn.
    turn_deg, rate_deg_s : float
        Course change (deg, either sign) and its rate (deg/s).

    Returns
    -------
    numpy.ndarray
        The window.
    """
    t = np.asarray(ping_time_s, float)
    out = np.zeros(len(t), bool)
    if start_s is None or turn_deg == 0 or not len(t) or start_s > t[-1]:
        return out
    end_s = start_s + abs(turn_deg) / rate_deg_s
    a = max(int(np.searchsorted(t, start_s, "right")) - 1, 0)
    b = min(int(np.searchsorted(t, end_s, "left")), len(t) - 1)
    out[a:b + 1] = True
    return out


def one_row_through(track_of, window, detectable, row_of: dict[int, int]) -> tuple[float, float]:
    """(verdict, held fraction of the window) of one target's turn (module doc): 1 held on one row, 0 not, NaN not
    judged.

    Parameters
    ----------
    track_of : int array (P,)
        The confirmed track holding the target at each ping (-1: none).
    window, detectable : bool arrays (P,)
        The turn's pings (:func:`turn_window`) and the detectable pings.
    row_of : dict
        Track id -> row (:func:`row_of_tracks`).

    Returns
    -------
    tuple of float
        Verdict and held fraction (NaN, NaN when the target does not turn).
    """
    k = np.nonzero(np.asarray(window, bool))[0]
    if not len(k):
        return float("nan"), float("nan")
    tid = np.asarray(track_of, np.int64)[k]
    held = tid >= 0
    frac = float(held.mean())
    det = np.asarray(detectable, bool)
    if not (det[k[0]] and det[k[-1]]):
        return float("nan"), frac
    rows = {row_of.get(int(t), ("track", int(t))) for t in tid[held]}
    return float(bool(held[0] and held[-1] and len(rows) == 1)), frac


#: the causes of a counted ping not held (:func:`unheld_causes`), in the order they are tested
UNHELD_CAUSES = ("miss", "acquiring", "deleted", "off", "assigned-other")
#: what else is near the target on such a ping (:func:`unheld_causes`)
UNHELD_NEAR = ("mirror", "tentative", "none")


def _unheld_state(tracks, rows, last: int, xy, gate_m: float) -> str:
    """The track state behind one not-held ping (:func:`unheld_causes`): ``rows`` the track table's rows at the ping,
    ``last`` the confirmed track that last held the target (-1: none yet)."""
    if last < 0:
        return "acquiring"
    own = rows[tracks.track_id[rows] == last]
    if not len(own):
        return "deleted"
    # confirmation is kept for a track's life (tracking/deleters.py): the last holder within the gate is confirmed
    return "off" if np.hypot(*(tracks.x[own[0], :2] - xy)) >= gate_m else "assigned-other"


def _unheld_near(tracks, rows, xy, xy_mirror, gate_m: float, undecided, t_s: float) -> str:
    """"mirror" an undecided confirmed track within the gate of the target's mirror, else "tentative" a tentative
    track within the gate of the target, else "none"."""
    conf = np.asarray(tracks.confirmed[rows], bool)
    dm = np.hypot(*(tracks.x[rows, :2] - xy_mirror).T)
    if (conf & (dm < gate_m) & np.array([bool(undecided(int(k), t_s)) for k in tracks.track_id[rows]], bool)).any():
        return "mirror"
    return "tentative" if (~conf & (np.hypot(*(tracks.x[rows, :2] - xy).T) < gate_m)).any() else "none"


def unheld_causes(counted, held_by, hit, time_s, xy, xy_mirror, tracks, gate_m: float,
                  undecided=lambda tid, t_s: True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each counted ping on which no confirmed track holds the target, given ONE cause, tested in this order:
    ``miss`` no detection on the target's echo (the detector's miss: a track must coast); ``acquiring`` no confirmed
    track has held the target yet; ``deleted`` the confirmed track that last held it is gone; ``off`` that track
    lives but farther than the gate; ``assigned-other`` that track, within the gate, is assigned to another target.
    Beside it, the track state (the cause but for the miss) and what is near: ``mirror`` an undecided confirmed
    track within the gate of the target's mirror (its row lists the target's true position as its other hypothesis,
    systems/active/targets.py), else ``tentative`` a tentative track within the gate of the target, else ``none``.

    Parameters
    ----------
    counted, hit : bool arrays (targets, pings)
        The pings the held fraction counts, and those with a detection on the echo.
    held_by : int array (targets, pings)
        The confirmed track holding each target (-1: none; the study's assignment).
    time_s : array (targets, pings)
        The pings' times (s), as the track table's.
    xy, xy_mirror : arrays (targets, pings, 2)
        The targets' positions and their mirrors about the array's axis (m).
    tracks : PositionTracks
        The per-ping track table (``time_s``, ``track_id``, ``confirmed``, ``x``).
    gate_m : float
        The study's ``match_m`` (m).
    undecided : callable
        (track id, time s) -> whether the track's side is undecided then (default: all are; the study's:
        :func:`undecided_at` with its side decisions).

    Returns
    -------
    tuple of numpy.ndarray
        (targets, pings) object arrays, "" where the ping is not counted or is held: the cause, the track state and
        what is near.
    """
    counted, held_by, hit = np.asarray(counted, bool), np.asarray(held_by, np.int64), np.asarray(hit, bool)
    out = tuple(np.full(counted.shape, "", object) for _ in range(3))
    for i, p in zip(*np.nonzero(counted & (held_by < 0)), strict=True):
        before = np.nonzero(held_by[i, :p] >= 0)[0]
        rows = np.nonzero(np.isclose(tracks.time_s, time_s[i, p]))[0]
        state = _unheld_state(tracks, rows, int(held_by[i, before[-1]]) if len(before) else -1, xy[i, p], gate_m)
        out[0][i, p], out[1][i, p] = "miss" if not hit[i, p] else state, state
        out[2][i, p] = _unheld_near(tracks, rows, xy[i, p], xy_mirror[i, p], gate_m, undecided, float(time_s[i, p]))
    return out


def undecided_at(sides, track_id: int, t_s: float) -> bool:
    """Whether a confirmed track's side was undecided at ``t_s``: no decision, or one reached only later
    (``SideDecisions.resolved_s``, systems/active/sides.py); a track without a side row counts as undecided."""
    k = None if sides is None else sides.of(int(track_id))
    if k is None or str(sides.decision[k]) == "undecided":
        return True
    r = float(sides.resolved_s[k])
    return not np.isfinite(r) or t_s < r

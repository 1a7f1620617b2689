"""One target per mirror pair: the active chain's confirmed tracks grouped into targets with their side hypotheses.

A line array cannot tell port from starboard, so each detection gives two mirror contacts (contacts.py) and a
target is tracked on both sides of the array: two confirmed tracks, the target's and its mirror's (its "twin",
sides.py :meth:`~sonartrack.systems.active.sides.SideTracker.twins`: the track that took the other contact of the
same detections). Until the side is decided (sides.py: the likelihood ratio once the array has turned) the two
are ONE target with two hypotheses, "the target is on the starboard side (here)" and "on the port side (there)";
once decided, the track on the target's side is the target and its twin is the rejected mirror (the chain then
deletes it: run.py). A confirmed track with no confirmed twin is a target of its own, its other hypothesis the
reflection of its position about the array's axis through the receiver (exact for a monostatic geometry, the
bistatic mirror is within the source's offset from the axis of it).

:func:`mirror_targets` makes the per-target table (sides.csv, the summary lines, the page's two tables);
:func:`track_hypotheses` labels each row of the per-ping track table with its target and hypothesis
(tracks.csv's ``target`` and ``hypothesis``: starboard | port while undecided, decided | mirror from the ping the
side was decided on).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: hypothesis labels of a track row (tracks.csv ``hypothesis``)
HYPOTHESES = ("starboard", "port", "decided", "mirror")
#: pings a target's tracks must have been confirmed on (together) to make a row, unless still confirmed at the last
#: ping: a track confirmed on one or two pings and then lost is a fleeting fragment, not a target to report (the
#: default scene with LFM listed a 1-ping ghost as a fifth target); it stays in tracks.csv, with no target
MIN_ROW_PINGS = 3


@dataclass(frozen=True, slots=True)
class MirrorTargets:
    """One row per target (arrays (n,)), numbered 1.. in order of first confirmation.

    ``target``; ``decision`` decided | undecided; ``side`` the target's side of the array when decided (starboard |
    port), "" when not; ``track_id`` the track on the target's side (decided; -1 when only its mirror was
    confirmed) or, undecided, the pair's first-confirmed track; ``track_side`` that track's side of the array at
    its last confirmed ping; ``mirror_track_id`` the other hypothesis's track (-1: none confirmed); ``log_lr`` ln LR
    of ``track_id``'s side against the other; ``resolved_s`` the ping time the side was decided from (NaN: not);
    ``first_s``, ``last_s`` the first and last confirmed pings of either track; ``xy (n, 2)`` ``track_id``'s last
    confirmed position (m; NaN: no track), ``mirror_xy (n, 2)`` the other hypothesis's (its track's last
    position, or, undecided with no twin, the reflection of ``xy``; NaN for a decided target without a twin);
    ``chains`` per row (the target's side's segments, the other side's segments): every confirmed track of the
    target, earlier segments joined to later ones (``ActiveTracks.joins``), of which ``track_id`` and
    ``mirror_track_id`` are the latest (None: one track a side)."""

    target: np.ndarray
    decision: np.ndarray
    side: np.ndarray
    track_id: np.ndarray
    track_side: np.ndarray
    mirror_track_id: np.ndarray
    log_lr: np.ndarray
    resolved_s: np.ndarray
    first_s: np.ndarray
    last_s: np.ndarray
    xy: np.ndarray
    mirror_xy: np.ndarray
    chains: tuple | None = None

    def __len__(self) -> int:
        return len(self.target)

    def of_track(self, track_id: int) -> int | None:
        """Row of the target ``track_id`` belongs to (either hypothesis), None when it belongs to none.

        Parameters
        ----------
        track_id : int
            A track's id.

        Returns
        -------
        int or None
            The row, or None.
        """
        hit = np.nonzero((self.track_id == track_id) | (self.mirror_track_id == track_id))[0]
        if not len(hit) and self.chains is not None:
            hit = [k for k, (own, other) in enumerate(self.chains) if track_id in own or track_id in other]
        return int(hit[0]) if len(hit) else None


def _reflect(geometry, t_s: float, xy) -> np.ndarray:
    """A position reflected about the array's axis through the receiver at ``t_s`` (m)."""
    rx, h = np.asarray(geometry.rx_at(t_s), float), float(geometry.heading_at(t_s))
    a = np.array([np.sin(h), np.cos(h)])
    d = np.asarray(xy, float) - rx
    return rx + 2.0 * float(d @ a) * a - d


def _last(tracks, tid: int) -> tuple[float, np.ndarray, float] | None:
    """(last confirmed time, position, first confirmed time) of a track; None when never confirmed."""
    rows = np.nonzero((tracks.track_id == tid) & tracks.confirmed)[0]
    if tid < 0 or not len(rows):
        return None
    return float(tracks.time_s[rows[-1]]), tracks.x[rows[-1], :2], float(tracks.time_s[rows[0]])


def _decide(d, members: list[int]) -> tuple[int, int, float, float, str] | None:
    """(target's track, mirror track, ln LR, resolved time, side) from the members' decisions: the decided member
    of the largest |ln LR| (a track decided a ghost puts the target on its twin); None when none is decided."""
    best = None
    for m in members:
        k = d.of(m)
        if k is None or d.decision[k] == "undecided" or (best and abs(d.log_lr[k]) <= abs(best[2])):
            continue
        other = int(d.twin[k])
        own, mirror = (m, other) if d.decision[k] == "track" else (other, m)
        best = (own, mirror, float(d.log_lr[k]) * (1 if own == m else -1), float(d.resolved_s[k]), str(d.side[k]))
    return best


def _groups(tracks, d, joins: tuple | dict | None = None) -> list[tuple[list, list]]:
    """Confirmed tracks grouped into targets, in order of first confirmation: (the segments on the side of the
    group's first track, the segments on the other side). Tracks are linked on the same side by ``joins`` ((a later
    segment, an earlier one) pairs, or a dict later -> earlier) and across by their mirror twins (sides.py); a group
    is a connected set of links, each track's side its parity along them from the first (a breadth-first walk; a
    track reached twice keeps its first side)."""
    order = list(dict.fromkeys(tracks.track_id[tracks.confirmed].tolist()))
    live = set(order)
    links: dict[int, list[tuple[int, int]]] = {t: [] for t in order}

    def link(a: int, b: int, parity: int) -> None:
        if a in live and b in live and a != b:
            links[a].append((b, parity))
            links[b].append((a, parity))

    for a, b in (joins.items() if isinstance(joins, dict) else joins or ()):
        link(int(a), int(b), 0)
    for m in order:
        k = d.of(m) if d is not None else None
        if k is not None and d.twin[k] >= 0:
            link(m, int(d.twin[k]), 1)
    side: dict[int, int] = {}
    out = []
    for tid in order:
        if tid in side:
            continue
        side[tid], queue, members = 0, [tid], [tid]
        while queue:
            a = queue.pop(0)
            for b, parity in links[a]:
                if b not in side:
                    side[b] = side[a] ^ parity
                    queue.append(b)
                    members.append(b)
        members.sort(key=order.index)
        out.append(([m for m in members if side[m] == 0], [m for m in members if side[m] == 1]))
    return out


def _latest(tracks, chain: list[int]) -> int:
    """The segment of a chain confirmed last (-1: an empty chain)."""
    spans = [(s[0], m) for m in chain if (s := _last(tracks, m)) is not None]
    return max(spans)[1] if spans else -1


def mirror_targets(active_tracks, geometry) -> MirrorTargets:
    """The targets of a run: each confirmed track with its mirror twin, one row per pair (module doc).

    Parameters
    ----------
    active_tracks : ActiveTracks
        The chain's tracks and side decisions (systems/active/run.py).
    geometry : ActiveGeometry
        Receiver and array heading (for a lone track's mirror position and its side).

    Returns
    -------
    MirrorTargets
        One row per target.
    """
    tracks, d = active_tracks.tracks, active_tracks.sides
    rows, chains = [], []
    groups = _groups(tracks, d, getattr(active_tracks, "joins", None))
    n, end_s = 0, float(np.max(tracks.time_s)) if len(tracks.time_s) else np.nan
    for first_chain, twin_chain in groups:
        group = first_chain + twin_chain
        pings = np.unique(tracks.time_s[np.isin(tracks.track_id, group) & tracks.confirmed])
        if len(pings) < MIN_ROW_PINGS and pings[-1] < end_s:
            continue
        n += 1
        spans = [s for s in (_last(tracks, m) for m in group) if s is not None]
        first, last = min(s[2] for s in spans), max(s[0] for s in spans)
        decided = _decide(d, group) if d is not None else None
        if decided is not None:
            own, mirror, lr, when, side = decided
            flip = own in twin_chain or mirror in first_chain
            own_chain, mirror_chain = (twin_chain, first_chain) if flip else (first_chain, twin_chain)
            if any(own in c and mirror in c for c in (first_chain, twin_chain)):  # joins put a decided track and
                own_chain, mirror_chain = first_chain, twin_chain  # its twin on one side: the decision names them
            else:
                own, mirror = _latest(tracks, own_chain), _latest(tracks, mirror_chain)
        else:
            own_chain, mirror_chain = first_chain, twin_chain
            own, mirror, when, side = _latest(tracks, first_chain), _latest(tracks, twin_chain), np.nan, ""
            k = d.of(own) if d is not None else None
            lr = float(d.log_lr[k]) if k is not None else 0.0
        chains.append((tuple(own_chain), tuple(mirror_chain)))
        a, b = _last(tracks, own), _last(tracks, mirror)
        xy = a[1] if a is not None else np.full(2, np.nan)
        if b is not None:
            mxy = b[1]
        else:
            mxy = _reflect(geometry, a[0], a[1]) if decided is None and a is not None else np.full(2, np.nan)
        tside = "" if a is None else ("starboard" if geometry.side_of(a[0], a[1][None])[0] > 0 else "port")
        rows.append((n, "undecided" if decided is None else "decided", side, own if a is not None else -1, tside,
                     mirror if b is not None else -1, lr, when, first, last, xy, mxy))
    cols = list(zip(*rows, strict=True)) if rows else [[] for _ in range(12)]
    kinds = (np.int64, object, object, np.int64, object, np.int64, float, float, float, float)
    arrays = [np.array(c, dtype=k) for c, k in zip(cols[:10], kinds, strict=True)]
    return MirrorTargets(*arrays, np.array(cols[10], float).reshape(-1, 2), np.array(cols[11], float).reshape(-1, 2),
                         tuple(chains))


def track_hypotheses(active_tracks, targets: MirrorTargets, geometry) -> tuple[np.ndarray, np.ndarray]:
    """Each row of the per-ping track table labelled with its target and hypothesis (module doc).

    Parameters
    ----------
    active_tracks : ActiveTracks
        The chain's tracks.
    targets : MirrorTargets
        Their targets (:func:`mirror_targets`).
    geometry : ActiveGeometry
        Receiver and array heading (the side of a row while undecided).

    Returns
    -------
    target : numpy.ndarray
        (rows,) int, the target number of each row (-1: a track never confirmed).
    hypothesis : numpy.ndarray
        (rows,) str: starboard | port (undecided: the target is here if on that side), decided (on the target's
        decided side), mirror (the rejected mirror of a decided target), "" (a track never confirmed).
    """
    t = active_tracks.tracks
    target = np.full(len(t), -1, np.int64)
    hyp = np.full(len(t), "", dtype=object)
    if not len(t):
        return target, hyp
    side = np.where(geometry.side_of(t.time_s, t.x[:, :2]) > 0, "starboard", "port").astype(object)
    for k in range(len(targets)):
        own, other = targets.chains[k] if targets.chains is not None else ((targets.track_id[k],),
                                                                            (targets.mirror_track_id[k],))
        for ids, label in ((own, "decided"), (other, "mirror")):
            rows = np.isin(t.track_id, [i for i in ids if i >= 0])
            if not rows.any():
                continue
            target[rows] = targets.target[k]
            after = rows & (t.time_s >= targets.resolved_s[k])  # NaN: never
            hyp[rows] = side[rows]
            hyp[after] = label
    return target, hyp


def truth_scores(active_tracks, targets: MirrorTargets, truth, geometry, match_m: float = 1500.0) -> dict:
    """Held fraction and false targets against a truth table (a simulated scene's truth.csv).

    A true target is held at a ping when a confirmed row of a target's track (either hypothesis while undecided,
    the decided one after: never a rejected mirror) lies within ``match_m`` of it; a target is false when none of
    its tracks' confirmed rows ever came within ``match_m`` of a true target or of its mirror about the array's
    axis (a ghost is not false: it is a hypothesis of a real target).

    Parameters
    ----------
    active_tracks : ActiveTracks
        The chain's tracks.
    targets : MirrorTargets
        Their targets.
    truth : pandas.DataFrame
        Columns time_s, target (name), x_m, y_m (m); rows at the ping times.
    geometry : ActiveGeometry
        Receiver and array heading (the mirrors).
    match_m : float
        Distance (m) within which a track holds a target.

    Returns
    -------
    dict
        ``held`` {name: fraction of that target's pings held}, ``held_all`` over every (target, ping),
        ``false_targets`` the number of false targets.
    """
    t = active_tracks.tracks
    tg, hyp = track_hypotheses(active_tracks, targets, geometry)
    ok = t.confirmed & (tg >= 0) & (hyp != "mirror")
    tt, names = np.asarray(truth["time_s"], float), np.asarray(truth["target"]).astype(str)
    xy = np.stack([np.asarray(truth["x_m"], float), np.asarray(truth["y_m"], float)], -1)
    mirror = np.array([_reflect(geometry, a, b) for a, b in zip(tt, xy, strict=True)]).reshape(-1, 2)
    near = np.zeros(len(targets), bool)
    hit = np.zeros(len(tt), bool)
    for r in np.nonzero(t.confirmed & (tg >= 0))[0]:
        at = np.isclose(tt, t.time_s[r])
        d = np.hypot(*(xy[at] - t.x[r, :2]).T)
        dm = np.hypot(*(mirror[at] - t.x[r, :2]).T)
        near[tg[r] - 1] |= bool((d < match_m).any() or (dm < match_m).any())
        if ok[r]:
            hit[np.nonzero(at)[0][d < match_m]] = True
    held = {n: float(hit[names == n].mean()) for n in dict.fromkeys(names.tolist())}
    return {"held": held, "held_all": float(hit.mean()) if len(hit) else float("nan"),
            "false_targets": int((~near).sum())}

"""A ship's track pieces put back together: pairings swapped at crossings undone, fragments joined across gaps.

Both decide by constant-velocity fits of the pieces' own measurements (systems/passive/measurements.py): a
pairing or a join is kept when one fit of the joined pieces leaves a residual variance close to that of their
separate fits (:data:`MAX_JOIN_VARIANCE_RATIO`, :data:`MUTUAL_JOIN_VARIANCE_RATIO`); a joined target's tonal
line is joined with it when the two lines agree (:func:`tonals_agree`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sonartrack.systems.passive.measurements import TrackMeasurements, _without, unfolded_image, within_one_beam


def _union(a: TrackMeasurements, b: TrackMeasurements, b_on_branch: bool = False) -> TrackMeasurements:
    """``a`` extended by ``b``'s scans that ``a`` lacks (``a``'s values where both have one); ``b_on_branch``: b's
    unfolded angles are already on a's fold branch (:func:`_join_branch`), else each is imaged nearest a's."""
    def join(ta, xa, tb, xb):
        extra = ~np.isin(tb, ta)
        t = np.concatenate([ta, tb[extra]])
        order = np.argsort(t, kind="stable")
        return t[order], [np.concatenate([u, v[extra]])[order] for u, v in zip(xa, xb, strict=True)]

    ua = a.unfolded_deg if a.unfolded_deg is not None else a.cone_deg
    # b's unfolded images brought to a's branch where they meet (the same target, possibly another fold)
    if b.unfolded_deg is None:
        ub = b.cone_deg
    elif b_on_branch:
        ub = b.unfolded_deg
    else:
        ub = unfolded_image(b.cone_deg, np.interp(b.time_s, a.time_s, ua))
    t, (cone, amp, phi) = join(a.time_s, (a.cone_deg, a.amplitude, ua), b.time_s, (b.cone_deg, b.amplitude, ub))
    tt, (tc,) = join(a.track_time_s, (a.track_cone_deg,), b.track_time_s, (b.track_cone_deg,))
    return TrackMeasurements(a.track_id, t, cone, amp, tt, tc, phi if a.unfolded_deg is not None else None)


def _fragments_joined(a: TrackMeasurements, b: TrackMeasurements, nav=None) -> TrackMeasurements:
    """``a`` continued by the later fragment ``b`` (:func:`join_fragments`): the peaks of both (:func:`_union`), and
    the filtered track a's before b's begins and b's from then on. Not a's filtered track wherever a has one, as for
    two tracks on the same peaks (:func:`_union`): after its last peak the earlier fragment's track coasts or follows
    another ship (passive-chain study trial 1: the pair-near ship's joined target read the pair-far ship's cone
    angle, 25 deg away, from 505 s on, so the crosser's TMA kept the scans that the pair-near ship shared its beam
    with)."""
    joined = _union(a, b) if nav is None else _union(a, _join_branch(a, b, nav), b_on_branch=True)
    t0 = float(b.track_time_s[0]) if len(b.track_time_s) else np.inf
    before = np.asarray(a.track_time_s, float) < t0
    return replace(joined, track_time_s=np.concatenate([a.track_time_s[before], b.track_time_s]),
                   track_cone_deg=np.concatenate([a.track_cone_deg[before], b.track_cone_deg]))


#: the spans (s) before and after a crossing over which :func:`swap_at_crossings` fits each pairing
CROSSING_SPAN_S = 200.0


def _close_spans(a: TrackMeasurements, b: TrackMeasurements, min_separation_deg: float) -> list[tuple[float, float]]:
    """Maximal spans (s) in which the two filtered tracks lie within one beam of width ``min_separation_deg`` at
    broadside (:func:`within_one_beam`; gaps up to 10 s bridged)."""
    common, ia, ib = np.intersect1d(a.track_time_s, b.track_time_s, return_indices=True)
    t = common[within_one_beam(a.track_cone_deg[ia], b.track_cone_deg[ib], min_separation_deg)]
    if not len(t):
        return []
    cuts = np.nonzero(np.diff(t) > 10.0)[0] + 1
    return [(float(u[0]), float(u[-1])) for u in np.split(t, cuts)]


def _piece(m: TrackMeasurements, lo: float, hi: float) -> TrackMeasurements:
    return _without(m, (m.time_s < lo) | (m.time_s > hi))


def _split_at(m: TrackMeasurements, t: float) -> tuple[TrackMeasurements, TrackMeasurements]:
    """(m before t, m after t): measurements and filtered track."""
    def part(keep, track_keep):
        return replace(_without(m, ~keep), track_time_s=m.track_time_s[track_keep],
                       track_cone_deg=m.track_cone_deg[track_keep])
    return part(m.time_s <= t, m.track_time_s <= t), part(m.time_s > t, m.track_time_s > t)


def _joined(a: TrackMeasurements, b: TrackMeasurements) -> TrackMeasurements:
    """a's part then b's (disjoint in time), with a's id."""
    cat = np.concatenate
    unf = None
    if a.unfolded_deg is not None and b.unfolded_deg is not None:
        ub = b.unfolded_deg
        if len(ub) and len(a.unfolded_deg):  # b's unfolded angles on a's branch of the fold where they meet
            ub = np.rad2deg(_on_branch(np.deg2rad(ub), np.deg2rad(a.unfolded_deg[-1])))
        unf = cat([a.unfolded_deg, ub])
    return TrackMeasurements(a.track_id, cat([a.time_s, b.time_s]), cat([a.cone_deg, b.cone_deg]),
                             cat([a.amplitude, b.amplitude]), cat([a.track_time_s, b.track_time_s]),
                             cat([a.track_cone_deg, b.track_cone_deg]), unf, a.joined_track_ids)


def swap_at_crossings(tracks: list[TrackMeasurements], nav, min_separation_deg: float,
                      max_ratio: float = 3.0) -> list[TrackMeasurements]:
    """Two tracks that came within one beam of each other (a crossing in cone angle; :func:`within_one_beam`, the
    beam ``min_separation_deg`` wide at broadside and wider in cone angle towards endfire) and went on:
    their parts after the crossing are exchanged when each one's part before it and the other's part after it are
    one constant-velocity target each far better than the parts as the tracker left them, i.e. the sum of the two
    variance ratios of :func:`_join_statistic` is less than half as large with the exchange and both exchanged
    ratios are at most ``max_ratio`` (the 2 x 2 assignment of track-to-track association across the crossing,
    Bar-Shalom, Willett & Tian, Tracking and Data Fusion, 2011, sec. 7.2; the tracker's identities swap where two
    ships share one peak, Blackman & Popoli 1999, ch. 10). Each side is fitted over ``CROSSING_SPAN_S`` before and
    after the crossing. The thresholds are loose (one target gives a ratio near 1, two ships far larger) and
    DEVIATE from a chi-square test for the reason given at ``MAX_JOIN_VARIANCE_RATIO``; on the passive-chain
    study's 32 scenes (seed 2017) it was made once, where the tracker had swapped two ships (trial 3: as left
    21.4 + 5.0, exchanged 2.1 + 1.2), and nowhere else. A track whose part after the crossing holds fewer than 10
    peaks (to the end of its record) cannot be tested, so that part is left out: which ship it follows is unknown
    (measured, study trial 30: two ships one beam apart for 180 s, each track's last 3 peaks after it were the other
    ship's and made both batch ML fits fail).

    Parameters
    ----------
    tracks : list of TrackMeasurements
        The tracks' measurements.
    nav : Navigation
        The array's position and heading (io/navigation.py).
    min_separation_deg : float
        The broadside beamwidth (deg): two filtered tracks within one beam are crossing.
    max_ratio : float
        Largest variance ratio of an exchanged pairing.

    Returns
    -------
    list of TrackMeasurements
        The tracks, parts exchanged where the crossing swapped them.
    """
    out = list(tracks)
    for i in range(len(out)):
        for j in range(i + 1, len(out)):
            for c0, c1 in _close_spans(out[i], out[j], min_separation_deg):
                a, b = out[i], out[j]
                pre = [_piece(m, c0 - CROSSING_SPAN_S, c0) for m in (a, b)]
                if min(len(m.time_s) for m in pre) < 10:
                    continue
                tails = [int(np.count_nonzero(m.time_s > c1)) for m in (a, b)]
                if min(tails) < 10:  # a part after the crossing too short to test is not attributed to either
                    cut = [_split_at(m, c1)[0] if 0 < n < 10 else m for m, n in zip((a, b), tails, strict=True)]
                    out[i], out[j] = cut
                    continue
                post = [_piece(m, c1, c1 + CROSSING_SPAN_S) for m in (a, b)]
                if min(len(m.time_s) for m in post) < 10:
                    continue
                if _crossing_swapped(pre, post, nav, max_ratio):
                    (a0, a1), (b0, b1) = _split_at(a, c1), _split_at(b, c1)
                    out[i], out[j] = _joined(a0, b1), _joined(b0, a1)
    return out


def _crossing_swapped(pre: list[TrackMeasurements], post: list[TrackMeasurements], nav, max_ratio: float) -> bool:
    """The test of :func:`swap_at_crossings` on the two tracks' parts before (``pre``) and after (``post``) one
    crossing: the exchanged pairings' variance ratios sum to less than half the kept ones' and neither exceeds
    ``max_ratio``. The exchanged ratios come first: once one exceeds ``max_ratio`` the answer is no and the kept
    pairings are not fitted (at most crossings the tracker kept its ships, and an exchanged ratio is hundreds). Each
    part's own fit is made once for the (up to) four pairings (``costs``)."""
    costs: dict = {}
    swap = []
    for k in (0, 1):
        swap.append(_join_statistic(pre[k], post[1 - k], nav, costs))
        if swap[-1] > max_ratio:  # max(swap) > max_ratio whatever the other ratio is
            return False
    keep = [_join_statistic(pre[k], post[k], nav, costs) for k in (0, 1)]
    return 2.0 * sum(swap) < sum(keep) and max(swap) <= max_ratio


#: two fragments are one target when one constant-velocity fit of both leaves a residual variance at most this many
#: times that of their separate fits (scene with a crossing: fragments of one ship 1.05, of two ships ~400; a
#: chi-square test on ~1000 scans counts the peaks' slow biases of ~0.05 deg as evidence against the join)
MAX_JOIN_VARIANCE_RATIO = 1.5
#: two fragments that are each other's best match (the later one's best predecessor, the earlier one's best
#: successor) are one target up to this ratio: where a ship's track breaks at a crossing, the one-to-one assignment
#: of the fragments that end to those that start there with the lowest costs (global nearest neighbour
#: track-to-track association, Blackman & Popoli, Design and Analysis of Modern Tracking Systems, 1999, sec. 6.6)
#: keeps two ships apart when the absolute ratio alone cannot (measured on the passive-chain study's crossings with
#: an own-ship turn in the gap: fragments of one ship 2.6 - 2.9, the other ship's fragment there 4.0 - 13; the
#: pair's slow peak biases of ~0.1 deg through the turn are what raise the ratio of one ship)
MUTUAL_JOIN_VARIANCE_RATIO = 3.0
#: largest gap (s) between two fragments of one target that are tried for a join
MAX_JOIN_GAP_S = 300.0


def _phi_rad(m: TrackMeasurements) -> np.ndarray:
    return np.deg2rad(m.unfolded_deg if m.unfolded_deg is not None else m.cone_deg)


def _on_branch(phi_b: np.ndarray, target_rad: float) -> np.ndarray:
    """phi_b moved to the fold branch (phi + 2 pi m or -phi + 2 pi m: the same cone angles) whose first value lies
    nearest ``target_rad``."""
    up, down = _branches(phi_b, target_rad)
    return up if abs(up[0] - target_rad) <= abs(down[0] - target_rad) else down


def _branches(phi_b: np.ndarray, target_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """phi_b on its two fold branches, phi + 2 pi m and -phi + 2 pi m (the same cone angles), each with the m that
    puts its first value nearest ``target_rad``."""
    up = phi_b + 2.0 * np.pi * np.round((target_rad - phi_b[0]) / (2.0 * np.pi))
    down = -phi_b + 2.0 * np.pi * np.round((target_rad + phi_b[0]) / (2.0 * np.pi))
    return up, down


def _cv_cost(t, phi, nav) -> float:
    """The lowest bearings-only CV ML cost (rad^2) over the two mirror hypotheses b = h +- phi (tma/sides.py)."""
    from sonartrack.tma.sides import fit_cv_target, mirror_bearings_rad

    xy, heading = nav.array_at(t)
    best = np.inf
    for z in mirror_bearings_rad(phi, heading):
        f = fit_cv_target(z, t, xy)
        if f is not None and f.objective < best:
            best = f.objective
    return best


def _own_cost(m: TrackMeasurements, first: int, nav, costs: dict | None) -> float:
    """:func:`_cv_cost` of m's measurements from index ``first`` on, looked up in ``costs`` (keyed by the fragment
    object and ``first``; the caller keeps the fragments alive while it holds ``costs``) or fitted and stored."""
    key = (id(m), first)
    if costs is None or key not in costs:
        cost = _cv_cost(m.time_s[first:], _phi_rad(m)[first:], nav)
        if costs is None:
            return cost
        costs[key] = cost
    return costs[key]


def _join_statistic(a: TrackMeasurements, b: TrackMeasurements, nav, costs: dict | None = None) -> float:
    """Fragments a then b as one constant-velocity target: the residual variance of one fit of both,
    J_ab / (n - 4), over that of their separate fits, (J_a + J_b) / (n - 8) (at least (0.1 deg)^2): about 1 for
    one target (an F ratio), large for two.

    Which fold branch b continues a on (b's angles phi or their mirror -phi through the array's axis, the same cone
    angles) is a discrete unknown of the one-target hypothesis: J_ab is the lower of the two branches' costs (the
    generalised likelihood ratio maximises the likelihood over unknown parameters, Kay, Fundamentals of
    Statistical Signal Processing vol. II, sec. 6.4). The branch a linear extrapolation of a's end predicts is
    wrong when the array turns during the gap (measured: a 0.5 deg/s rate at a's end, from the array's turn,
    carried over 70 s put b on the mirror branch and a ratio of 2000 where the true branch gives 3).

    ``costs``: a dict the caller keeps across calls on the same fragments, which holds each fragment's own fit
    (J_a, J_b) so that it is made once (None: no reuse)."""
    ta, tb = a.time_s, b.time_s[b.time_s > a.time_s[-1]]
    if len(ta) < 10 or len(tb) < 10:
        return np.inf
    # b's times increase: its part after a's end is its last len(tb) measurements
    j_a, j_b = _own_cost(a, 0, nav, costs), _own_cost(b, len(b.time_s) - len(tb), nav, costs)
    n = len(ta) + len(tb)
    j_up, j_down, _, _ = _branch_costs(a, b, nav)
    separate = max((j_a + j_b) / (n - 8), np.deg2rad(0.1) ** 2)
    return float(min(j_up, j_down) / (n - 4) / separate)


def _continuing_branches(a: TrackMeasurements, b: TrackMeasurements) -> tuple[np.ndarray, np.ndarray]:
    """b's part after a's end on its phi and on its -phi fold branch (:func:`_branches`), each with the 2 pi m that
    puts it nearest a linear extrapolation of a's end."""
    ta, pa = a.time_s, _phi_rad(a)
    after = b.time_s > ta[-1]
    rate = np.polyfit(ta[-20:] - ta[-1], pa[-20:], 1)[0] if len(ta) >= 2 else 0.0
    return _branches(_phi_rad(b)[after], pa[-1] + rate * (b.time_s[after][0] - ta[-1]))


def _branch_costs(a: TrackMeasurements, b: TrackMeasurements, nav) -> tuple[float, float, np.ndarray, np.ndarray]:
    """(one-target cost of a then b's part after a's end on its phi branch, the same on its -phi branch, that part
    on each branch: :func:`_continuing_branches`) (:func:`_join_statistic`, :func:`_join_branch`)."""
    up, down = _continuing_branches(a, b)
    t_ab, pa = np.concatenate([a.time_s, b.time_s[b.time_s > a.time_s[-1]]]), _phi_rad(a)
    return _cv_cost(t_ab, np.concatenate([pa, up]), nav), _cv_cost(t_ab, np.concatenate([pa, down]), nav), up, down


def _join_branch(a: TrackMeasurements, b: TrackMeasurements, nav) -> TrackMeasurements:
    """b with its unfolded angles on the fold branch that continues a (phi + 2 pi m or -phi + 2 pi m, the same cone
    angles): the branch of the lower one-target cost, as :func:`_join_statistic` chose it when it tested the join.
    Imaging each of b's angles nearest a's last unfolded angle instead (:func:`_union` alone) folds b back onto a's
    side of the axis when the ship crossed the array's axis (endfire) in the gap or during b (measured on the
    passive-chain study's 32 scenes, seed 2017: 5 of the 10 joined targets had their part after the junction on the
    mirror branch of the truth)."""
    if a.unfolded_deg is None or b.unfolded_deg is None:
        return b
    after = b.time_s > a.time_s[-1]
    if not after.any():
        return b
    pa, pb = _phi_rad(a), _phi_rad(b)
    if len(a.time_s) >= 10 and after.sum() >= 10:
        j_up, j_down, up, down = _branch_costs(a, b, nav)
        use_up = j_up <= j_down
    else:
        up, down = _continuing_branches(a, b)
        use_up = abs(up[0] - pa[-1]) <= abs(down[0] - pa[-1])
    phi = pb + (up[0] - pb[after][0]) if use_up else -pb + (down[0] + pb[after][0])
    return replace(b, unfolded_deg=np.rad2deg(phi))


def join_fragments(tracks: list[TrackMeasurements], nav, max_gap_s: float = MAX_JOIN_GAP_S,
                   max_ratio: float = MUTUAL_JOIN_VARIANCE_RATIO, min_fragment_s: float = 120.0, *,
                   tonals: dict | None = None) -> list[TrackMeasurements]:
    """Track-to-track association: join a confirmed track that starts after another ended (within ``max_gap_s``)
    into it when one constant-velocity target explains both bearing histories (the variance ratio of
    :func:`_join_statistic`; track-to-track association as a test of one target against two, Bar-Shalom, Willett &
    Tian, Tracking and Data Fusion, sec. 7.2, with an F ratio in place of its chi-square: DEVIATION, see
    ``MAX_JOIN_VARIANCE_RATIO``). The fragments that end are assigned one-to-one to those that start after them
    (:func:`_join_assignment`: global nearest neighbour track-to-track association, Blackman & Popoli, Design and
    Analysis of Modern Tracking Systems, 1999, sec. 6.6), over the pairs whose ratio is at most ``max_ratio``; an
    assigned pair is joined. Where two ships' tracks break at one crossing, the assignment of the fragments ending
    there to those starting there tells them apart where each pair's ratio alone cannot, and it is the assignment,
    not each fragment's best match, that does so (measured, study trial 1: ratios 1.72 and 2.98 for the wrong
    pairing, 1.79 and 2.10 for the right one; best-match-first joined the wrong one).
    A ship whose track broke at a crossing or turn becomes one target, its fragments' ids in ``joined_track_ids``.
    Where both fragments carry a tonal line (``tonals``), the line must also agree across the junction
    (:func:`tonals_agree`): a ship keeps its line, so two ships' fragments with lines apart are not joined however
    well one constant-velocity track explains their bearings.

    Parameters
    ----------
    tracks : list of TrackMeasurements
        The confirmed tracks' measurements.
    nav : Navigation
        The array's position and heading (io/navigation.py).
    max_gap_s : float
        Largest gap (s) between the end of one fragment and the start of the next.
    max_ratio : float
        A pair of fragments takes part in the assignment when its ratio is at most this.
    min_fragment_s : float
        Both fragments must span at least this (s): a shorter one's own CV fit explains almost any bearings, so the
        test cannot tell (measured: a 90 s fragment before a turn joined to its ship's later track gave an ML range
        off by 10 km that its covariance did not cover).
    tonals : dict, optional
        track id -> its tonal line (``time_s``, ``frequency_hz`` with NaN where not seen, ``sigma_hz``; e.g.
        acoustics/tonal.py ``TonalTrack``) or None; tracks without one are judged on their bearings alone.

    Returns
    -------
    list of TrackMeasurements
        The tracks, fragments joined into the earlier one, in order of first scan.
    """
    out = sorted(tracks, key=lambda m: (m.time_s[0] if len(m.time_s) else np.inf, m.track_id))
    lines = {k: _line(v) for k, v in (tonals or {}).items() if v is not None}
    ratio = _cached_ratio(nav)
    i = 0
    while i < len(out):
        j = None
        if any(_may_join(a, out[i], max_gap_s, min_fragment_s, lines) for a in out[:i]):
            j = _join_assignment(out, ratio, max_ratio, max_gap_s, min_fragment_s, lines).get(i)
        if j is None:
            i += 1
            continue
        a, b = out[j], out[i]
        joined = _fragments_joined(a, b, nav)
        out[j] = replace(joined, joined_track_ids=a.joined_track_ids + (b.track_id,) + b.joined_track_ids)
        if b.track_id in lines:  # the joined target's line runs on with the later fragment's
            lines[a.track_id] = _joined_line(lines.get(a.track_id), lines[b.track_id])
        del out[i]
    return out


def _cached_ratio(nav):
    """:func:`_join_statistic` of (a, b), each pair computed once (the fragments are immutable and kept alive by
    the cache while it is used; a joined fragment is a new object)."""
    cache: dict = {}

    def ratio(a: TrackMeasurements, b: TrackMeasurements) -> float:
        key = (id(a), id(b))
        if key not in cache:
            cache[key] = (a, b, _join_statistic(a, b, nav))
        return cache[key][2]

    return ratio


def _may_join(a: TrackMeasurements, b: TrackMeasurements, max_gap_s: float, min_fragment_s: float,
              lines: dict) -> bool:
    """Whether b may continue a at all: both long enough, b starting after a ends (30 s of overlap allowed) and
    within ``max_gap_s`` of it, their tonal lines not apart."""
    return (min(a.duration_s, b.duration_s) >= min_fragment_s
            and a.time_s[-1] < b.time_s[0] + 30.0 and b.time_s[0] - a.time_s[-1] <= max_gap_s
            and tonals_agree(lines.get(a.track_id), lines.get(b.track_id)))


def _join_assignment(out: list[TrackMeasurements], ratio, max_ratio: float, max_gap_s: float,
                     min_fragment_s: float, lines: dict) -> dict[int, int]:
    """The one-to-one assignment of fragment ends to fragment starts (later index -> earlier index): among the
    pairs that may join (:func:`_may_join`) with a ratio at most ``max_ratio``, the set, each fragment at most once
    as the earlier and once as the later, that maximises the summed margin ``max_ratio`` - ratio (the linear
    assignment of global nearest neighbour association, Blackman & Popoli 1999, sec. 6.6; a pair left out costs
    nothing, so a pair is taken only where no better use of either fragment exists)."""
    from scipy.optimize import linear_sum_assignment

    n = len(out)
    cost = np.zeros((n, n))
    for j, a in enumerate(out):
        for i, b in enumerate(out):
            if i != j and _may_join(a, b, max_gap_s, min_fragment_s, lines):
                cost[j, i] = min(ratio(a, b) - max_ratio, 0.0)
    rows, cols = linear_sum_assignment(cost)
    return {int(i): int(j) for j, i in zip(rows, cols, strict=True) if cost[j, i] < 0.0}


#: a ship's received line moves with its range rate, f_r = f (1 - rdot / c): across a junction (up to
#: ``MAX_JOIN_GAP_S`` plus the two end spans) the range rate of a ship is taken to change by at most this (m/s)
MAX_RANGE_RATE_CHANGE_MPS = 5.0
#: the span (s) at each fragment's end over which its line's frequency is taken (median)
TONAL_END_SPAN_S = 60.0
SOUND_SPEED_MPS = 1500.0


def _joined_line(la, lb):
    return lb if la is None else (np.concatenate([la[0], lb[0]]), np.concatenate([la[1], lb[1]]), max(la[2], lb[2]))


def _line(tonal) -> tuple[np.ndarray, np.ndarray, float]:
    t, f = np.asarray(tonal.time_s, float), np.asarray(tonal.frequency_hz, float)
    ok = np.isfinite(f)
    return t[ok], f[ok], float(tonal.sigma_hz)


def tonals_agree(a, b) -> bool:
    """Whether fragment a's tonal line at its end and fragment b's at its start can be one ship's line: the medians
    over ``TONAL_END_SPAN_S`` differ by at most 3 sqrt(sigma_a^2 + sigma_b^2) + f rdot_max / c (the measurement
    noise, and the Doppler shift a change of range rate of ``MAX_RANGE_RATE_CHANGE_MPS`` makes; received frequency
    f_r = f (1 - rdot / c), paper P2 eq. 3). True when either has no line (nothing to say).

    Parameters
    ----------
    a, b : (ndarray, ndarray, float) or None
        Each fragment's line: times (s), frequencies (Hz) where seen, and its frequency noise sigma (Hz).

    Returns
    -------
    bool
        False only when both have a line and the lines differ by more than the tolerance.
    """
    if a is None or b is None or not len(a[0]) or not len(b[0]):
        return True
    fa = float(np.median(a[1][a[0] >= a[0][-1] - TONAL_END_SPAN_S]))
    fb = float(np.median(b[1][b[0] <= b[0][0] + TONAL_END_SPAN_S]))
    tol = 3.0 * float(np.hypot(a[2], b[2])) + max(fa, fb) * MAX_RANGE_RATE_CHANGE_MPS / SOUND_SPEED_MPS
    return abs(fa - fb) <= tol


def joined_tonal(track: TrackMeasurements, tonals: dict):
    """The tonal line of a target joined from fragments: the fragments' lines, in time order, as one line.

    Parameters
    ----------
    track : TrackMeasurements
        The target (its ``track_id`` and ``joined_track_ids``).
    tonals : dict
        track id -> the fragment's line (acoustics/tonal.py ``TonalTrack``) or None.

    Returns
    -------
    TonalTrack or None
        The first fragment's line and SNR with every fragment's per-window frequencies (the earliest fragment's
        where two overlap) and the largest of their sigma_hz; None when no fragment carries a line.
    """
    from dataclasses import replace

    parts = [tonals.get(i) for i in (track.track_id, *track.joined_track_ids)]
    parts = [p for p in parts if p is not None]
    if not parts:
        return None
    t, f = np.asarray(parts[0].time_s, float), np.asarray(parts[0].frequency_hz, float)
    for p in parts[1:]:
        extra = ~np.isin(p.time_s, t)
        t, f = np.concatenate([t, np.asarray(p.time_s, float)[extra]]), np.concatenate([f, p.frequency_hz[extra]])
    order = np.argsort(t, kind="stable")
    return replace(parts[0], time_s=t[order], frequency_hz=f[order], sigma_hz=max(p.sigma_hz for p in parts))

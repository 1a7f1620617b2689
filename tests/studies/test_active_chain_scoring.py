"""Study active-chain's scoring as the user sees the targets (studies/active_chain_scoring.py): false rows (an
undecided mirror pair counted once), acquisition latency, a turn held on one row, and the false-row rate's Poisson
bounds per clutter model. Every case is a hand-made track table or grid whose answer is worked out by hand here."""

import numpy as np
import pytest

from sonartrack.metrics.track_quality import associate_tracks
from sonartrack.sim.active_scene import ActiveSceneSettings, TargetSettings
from sonartrack.studies import active_chain as ac
from sonartrack.studies.active_chain_claims import _false_claim, _poisson_rate, acquisition_summary, family_summary
from sonartrack.studies.active_chain_family import AXES, FamilySettings
from sonartrack.studies.active_chain_scoring import (
    acquisition_pings,
    entering_level_db,
    false_rows,
    one_row_through,
    row_of_tracks,
    turn_window,
    undecided_at,
    unheld_causes,
)
from sonartrack.systems.active.contacts import ActiveGeometry
from sonartrack.systems.active.run import ActiveTracks
from sonartrack.systems.active.sides import SideDecisions
from sonartrack.systems.active.targets import mirror_targets
from sonartrack.tracking.run import PositionTracks

TIMES = np.arange(4) * 30.0


def _geometry():
    """A receiver at (0, 0) with the array's axis north (the mirror of (x, y) is (-x, y))."""
    t = np.array([-100.0, 1000.0])
    return ActiveGeometry(t, np.zeros((2, 2)), np.zeros((2, 2)), np.zeros(2))


def _tracks(paths: dict, twins: dict, joins: dict | None = None) -> ActiveTracks:
    """ActiveTracks from {track id: (x, y)} confirmed at every time of TIMES, undecided sides, mirror twins."""
    rows = [(t, tid, xy) for t in TIMES for tid, xy in paths.items()]
    n = len(rows)
    x = np.array([[*xy, 0.0, 0.0] for _, _, xy in rows], float)
    tracks = PositionTracks(np.array([r[0] for r in rows]), np.array([r[1] for r in rows], np.int64),
                            np.ones(n, bool), np.ones(n), x, np.full(n, 100.0), np.full(n, 100.0),
                            np.full((n, 2), 0.5))
    ids = np.array(list(paths), np.int64)
    m = len(ids)
    sides = SideDecisions(ids, np.array(["undecided"] * m, object), np.array([""] * m, object), np.zeros(m),
                          np.full(m, np.nan), np.full(m, 4), np.array([twins.get(int(i), -1) for i in ids]))
    return ActiveTracks(tracks, np.broadcast_to(np.eye(4), (n, 4, 4)).copy(), sides, joins)


def _scene_tracks():
    """A target at (3000, 6000) (still) with its track 3, its mirror twin 4 and a later segment 7 joined to 3 that
    wandered 5 km off; an undecided false pair 1 / 2 (twins, at (8000, 9000) and its mirror); a lone false track 5."""
    paths = {1: (8000.0, 9000.0), 2: (-8000.0, 9000.0), 3: (3100.0, 6000.0), 4: (-2950.0, 6000.0),
             5: (0.0, -7000.0), 7: (3000.0, 11000.0)}
    return _tracks(paths, {1: 2, 2: 1, 3: 4, 4: 3}, joins={7: 3})


def test_an_undecided_false_pair_is_one_false_row_and_its_two_tracks_are_shown():
    active = _scene_tracks()
    t_truth = TIMES
    xy = np.tile([3000.0, 6000.0], (len(TIMES), 1))
    mirror = xy * [-1.0, 1.0]
    # by hand: rows {1, 2} (false), {3, 4, 7} (the target: 3 on it, 4 on its mirror), {5} (false): 2 false of 3;
    # false tracks 1, 2, 5 and 7 (the joined segment never came near: its row is the target's, it is not)
    assert false_rows(active, _geometry(), t_truth, xy, mirror, 1000.0) == (2, 3, 4)
    # a reverberation-only scene (no truth): every row is false, the pair still once
    empty = np.zeros((0, 2))
    assert false_rows(active, _geometry(), np.zeros(0), empty, empty, 1000.0) == (3, 3, 6)
    # the study's track count agrees with its own helper
    assert ac._false_track_count(active, t_truth, xy, mirror, 1000.0) == 4


def test_rows_of_tracks_follow_the_listing():
    m = mirror_targets(_scene_tracks(), _geometry())
    rows = row_of_tracks(m)
    assert rows[1] == rows[2] and rows[3] == rows[4] == rows[7] and len({rows[1], rows[3], rows[5]}) == 3
    assert sorted(rows) == [1, 2, 3, 4, 5, 7]


def test_acquisition_latency_on_a_hand_made_track_table():
    """One target at (0, 5000) m, detectable from ping 3 (index 2); a confirmed track near it from ping 6 (a
    tentative one from ping 4, and a confirmed one 4 km off at ping 3): latency 6 - 3 + 1 = 4 pings."""
    pings = 10
    t = np.arange(pings) * 10.0
    scene = ActiveSceneSettings(duration_s=100.0, ping_interval_s=10.0, targets=[
        TargetSettings(name="a", x_m=0.0, y_m=5000.0, course_deg=0.0, speed_kn=0.0, target_strength_db=10.0)])
    config = ac.Config(scene=scene)
    snr = np.where(np.arange(pings) >= 2, 20.0, 5.0)
    truth = {"ping": np.arange(1, pings + 1), "time_s": t, "target": np.array(["a"] * pings, object),
             "x_m": np.zeros(pings), "y_m": np.full(pings, 5000.0), "ebr_db": snr, "snr_db": snr + 12.0,
             "in_window": np.ones(pings, bool), "in_blast": np.zeros(pings, bool)}  # snr: detectable from ping 1
    tr_t = np.concatenate([t[3:], t[2:3]])
    tr_id = np.concatenate([np.full(pings - 3, 8), [9]])
    tr_xy = np.concatenate([np.tile([50.0, 5050.0], (pings - 3, 1)), [[4000.0, 5000.0]]])
    confirmed = np.concatenate([np.arange(3, pings) >= 5, [True]])
    truth_xy = np.stack([truth["x_m"], truth["y_m"]], -1)
    assoc = associate_tracks(t, np.zeros(pings, np.int64), truth_xy, tr_t, tr_id, tr_xy, 1500.0, confirmed=confirmed)
    track_of = ac._by_ping(config, truth, assoc.time_s, assoc.track_of, -1)
    assert track_of.tolist() == [[-1] * 5 + [8] * 5]
    det = ac.detectable_grid(config, truth) > 0.5
    assert acquisition_pings(det, track_of >= 0).tolist() == [4.0]


def test_acquisition_latency_and_level_on_a_hand_grid():
    det = np.zeros((4, 12), bool)
    held = np.zeros((4, 12), bool)
    det[0, 2:] = True
    held[0, 5:] = True             # entering ping index 2, held from index 5: 4 pings
    held[1, :] = True              # never detectable: NaN (held or not)
    det[2, 1:] = True
    held[2, 0] = True              # held only before entering: never after, inf
    det[3, 7:] = held[3, 7:] = True  # held on its entering ping: 1
    lat = acquisition_pings(det, held)
    assert lat[0] == 4 and np.isnan(lat[1]) and np.isinf(lat[2]) and lat[3] == 1
    snr = np.full((4, 12), 20.0)
    snr[0, 3:5] = np.nan           # out of reach twice in its window: median of (20, -inf, -inf, 20, 20) = 20
    snr[3, 8:] = 10.0              # median of (20, 10, 10, 10, 10) = 10
    level = entering_level_db(snr, det, 5)
    assert level[0] == 20.0 and np.isnan(level[1]) and level[2] == 20.0 and level[3] == 10.0
    assert np.isnan(entering_level_db(snr, det, 6)[3])  # index 7 + 6 pings > 12: too near the end


def test_acquisition_summary_counts_judged_targets():
    p = 20
    det, held, snr = np.zeros((1, 5, p), bool), np.zeros((1, 4, 5, p), bool), np.full((1, 5, p), 20.0)
    det[0, 0, 2:] = True
    held[0, 0, 0, 6:] = True   # A: enters at index 2, held from 6: latency 5, within
    det[0, 1, 1:] = True
    held[0, 0, 1, 7:] = True   # B: latency 7, judged, not within
    det[0, 2, 3] = True
    snr[0, 2, 4:] = 10.0       # C: a 20 dB blip then 10 dB: median 10 < 15, not judged
    det[0, 3, p - 2:] = True   # D: enters two pings before the end: not judged
    det[0, 4, :] = True        # E: never held: judged, never
    held[0, 1:, :, :] = True   # other trackings' holds are not the chain's
    config = ac.Config(acquire_pings=5, detectable_ebr_db=15.0)
    # judged by the echo-to-background ratio: the echo-to-noise SNR (25 dB everywhere) would judge C too
    a = acquisition_summary({"detectable": det.astype(float), "held_pings": held.astype(float), "ebr_db": snr,
                             "snr_db": np.full_like(snr, 25.0)}, config)
    assert (a["judged"], a["within"], a["never"], a["not_judged"]) == (3, 1, 1, 2)
    assert a["latencies_pings"] == [5.0, 7.0] and a["fraction"][0] == pytest.approx(1 / 3)
    assert (a["entering_ebr_db"], a["entering_snr_db"]) == (20.0, 25.0)


def test_turn_window_spans_the_pings_around_the_turn():
    t = np.arange(11) * 10.0
    assert np.nonzero(turn_window(t, 25.0, 30.0, 1.0))[0].tolist() == [2, 3, 4, 5, 6]  # 25..55 s: pings 20..60 s
    assert np.nonzero(turn_window(t, 30.0, -20.0, 2.0))[0].tolist() == [3, 4]         # 30..40 s, either sign
    assert np.nonzero(turn_window(t, 80.0, 90.0, 1.0))[0].tolist() == [8, 9, 10]      # ends after the last ping
    assert not turn_window(t, None, 0.0, 1.0).any() and not turn_window(t, 200.0, 30.0, 1.0).any()


def test_a_turn_is_held_on_one_row_through_a_join():
    m = mirror_targets(_scene_tracks(), _geometry())
    rows = row_of_tracks(m)  # 3 and 7 one row (joined), 5 another
    window = np.array([False, True, True, True, True, True, False])
    det = np.ones(7, bool)

    def verdict(track_of, detectable=det):
        return one_row_through(np.array(track_of), window, detectable, rows)

    assert verdict([5, 3, 3, -1, 7, 7, 5]) == (1.0, 0.8)   # a gap and a re-joined segment: one row
    assert verdict([-1, 3, 3, 5, 3, 3, -1])[0] == 0.0     # another row holds it mid-turn
    assert verdict([-1, 3, 3, 3, 3, -1, -1])[0] == 0.0    # lost at the turn's end
    assert verdict([-1, 11, 11, 11, 11, 11, -1])[0] == 1.0  # a track of no listed row is a row of its own
    assert verdict([-1, 11, 11, 12, 12, 12, -1])[0] == 0.0
    late = det.copy()
    late[1] = False
    assert np.isnan(verdict([-1, 3, 3, 3, 3, 3, -1], late)[0])  # not detectable when the turn starts: not judged
    assert np.isnan(one_row_through(np.full(7, 3), np.zeros(7, bool), det, rows)).all()  # no turn: not judged


def test_poisson_rate_bounds_by_hand():
    # k = 0: upper -ln(0.05) = 2.996 events; k = 3: chi2(0.05, 6) / 2 = 0.818, chi2(0.95, 8) / 2 = 7.754 (tables)
    assert _poisson_rate(0, 3.0) == pytest.approx([0.0, 0.0, 2.9957 / 3.0], abs=1e-4)
    assert _poisson_rate(3, 2.0) == pytest.approx([1.5, 0.8177 / 2.0, 7.7537 / 2.0], abs=1e-3)


def test_false_claim_needs_every_model_under_one_per_hour_at_the_upper_bound():
    fam = FamilySettings()
    config = ac.Config(family=fam)
    runs = 3  # one run per reverberation model, 3.5 h each: 0 rows gives an upper bound 2.996 / 3.5 = 0.86 / h
    axes = np.zeros((runs, len(AXES)), np.int64)
    axes[:, 1] = np.arange(runs)
    trials = {"axes": axes, "detectable": np.zeros((runs, 1, 4)), "held_pings": np.zeros((runs, 4, 1, 4)),
              "gospa_m": np.zeros((runs, 4, 1)), "reverb_false_rows": np.zeros((runs, 2)),
              "reverb_false_tracks": np.zeros((runs, 2)), "hours": np.full((runs, 1), 3.5)}

    def claim(rows, tracks):
        t = {**trials, "reverb_false_rows": np.array(rows, float), "reverb_false_tracks": np.array(tracks, float)}
        k, kt, h = int(t["reverb_false_rows"][:, 0].sum()), int(t["reverb_false_tracks"][:, 0].sum()), 3.5 * runs
        summary = {"family": family_summary(t, config), "hours": h,
                   "reverb_false": {"mftd_imm": k, "single_imm": 0}, "reverb_false_tracks": {"mftd_imm": kt,
                                                                                           "single_imm": 0},
                   "reverb_false_per_hour": {"mftd_imm": k / h, "single_imm": 0.0},
                   "reverb_false_upper95": {"mftd_imm": _poisson_rate(k, h)[2], "single_imm": 0.0}}
        return _false_claim(summary, config)

    assert claim([[0, 0]] * 3, [[0, 0]] * 3).holds
    one = claim([[0, 0], [1, 0], [0, 0]], [[0, 0], [2, 0], [0, 0]])  # one false pair: 1 row, 2 tracks
    assert not one.holds  # upper bound chi2(0.95, 4) / 2 / 3.5 = 1.36 / h on model k
    assert "k: 1 rows (2 tracks)" in one.ours
    # a model not run cannot be claimed
    short = {**trials, "axes": axes[:2], "reverb_false_rows": np.zeros((2, 2)), "reverb_false_tracks": np.zeros((2, 2)),
             "hours": np.full((2, 1), 3.5), "detectable": np.zeros((2, 1, 4)), "held_pings": np.zeros((2, 4, 1, 4)),
             "gospa_m": np.zeros((2, 4, 1))}
    summary = {"family": family_summary(short, config), "hours": 7.0, "reverb_false": {"mftd_imm": 0, "single_imm": 0},
               "reverb_false_tracks": {"mftd_imm": 0, "single_imm": 0},
               "reverb_false_per_hour": {"mftd_imm": 0.0, "single_imm": 0.0},
               "reverb_false_upper95": {"mftd_imm": 0.43, "single_imm": 0.43}}
    c = _false_claim(summary, config)
    assert not c.holds and "k-spiky: not run" in c.ours


def _table(rows):
    """PositionTracks from (time s, track id, confirmed, x, y) rows."""
    n = len(rows)
    x = np.array([[r[3], r[4], 0.0, 0.0] for r in rows], float).reshape(n, 4)
    return PositionTracks(np.array([r[0] for r in rows], float), np.array([r[1] for r in rows], np.int64),
                          np.array([r[2] for r in rows], bool), np.ones(n), x, np.full(n, 100.0), np.full(n, 100.0),
                          np.full((n, 1), 1.0))


def test_unheld_pings_each_get_one_cause_in_the_stated_order():
    """Two still targets, A at (3000, 6000) (mirror (-3000, 6000)) and B at (-5000, 2000), 7 pings 30 s apart, all
    counted; the causes worked out by hand from the table below (gate 1000 m)."""
    t = np.arange(7) * 30.0
    A, B = (3000.0, 6000.0), (-5000.0, 2000.0)
    rows = [(t[0], 4, True, -2900.0, 6000.0),                     # ping 0: A's mirror held by an undecided track
            (t[1], 9, False, 3200.0, 6000.0),                     # ping 1: a tentative track on A
            (t[2], 3, True, 3100.0, 6000.0), (t[3], 3, True, 3100.0, 6000.0),  # pings 2, 3: track 3 holds A
            (t[5], 9, False, 3000.0, 6100.0)]                     # ping 4: nothing; ping 5: 3 gone, a tentative
    rows += [(t[k], 5, True, -5000.0, 2100.0) for k in range(3)]  # pings 0-2: track 5 holds B
    rows += [(t[3], 5, True, -5000.0, 4500.0),                    # ping 3: 5 is 2.5 km off B
             (t[4], 5, True, -4900.0, 2000.0), (t[5], 5, True, -4900.0, 2000.0)]  # 4, 5: near B, given to A
    tracks = _table(rows)
    held_by = np.full((2, 7), -1)
    held_by[0, 2:4] = 3
    held_by[0, 4:6] = 5  # the assignment gives track 5 to A at pings 4 and 5 (B's cause there: assigned-other)
    held_by[1, :3] = 5
    hit = np.ones((2, 7), bool)
    hit[0, 6] = hit[1, 6] = False  # ping 6: both missed; no track rows at all
    counted = np.ones((2, 7), bool)
    counted[1, 5] = False  # not counted: no cause
    xy = np.stack([np.tile(A, (7, 1)), np.tile(B, (7, 1))])
    mirror = xy * [-1.0, 1.0]
    cause, state, near = unheld_causes(counted, held_by, hit, np.tile(t, (2, 1)), xy, mirror, tracks, 1000.0)
    assert cause[0].tolist() == ["acquiring", "acquiring", "", "", "", "", "miss"]
    assert state[0].tolist() == ["acquiring", "acquiring", "", "", "", "", "deleted"]
    assert near[0].tolist() == ["mirror", "tentative", "", "", "", "", "none"]
    assert cause[1].tolist() == ["", "", "", "off", "assigned-other", "", "miss"]
    assert state[1].tolist() == ["", "", "", "off", "assigned-other", "", "deleted"] and near[1, 6] == "none"
    # a track decided on its side (not undecided) on A's mirror does not list A's position: nothing near
    near_decided = unheld_causes(counted, held_by, hit, np.tile(t, (2, 1)), xy, mirror, tracks, 1000.0,
                                 undecided=lambda tid, t_s: tid != 4)[2]
    assert near_decided[0, 0] == "none"


def test_a_side_is_undecided_until_its_decision_is_reached():
    sides = SideDecisions(np.array([4, 5]), np.array(["mirror", "undecided"], object),
                          np.array(["starboard", ""], object), np.array([-9.0, 0.1]), np.array([80.0, np.nan]),
                          np.array([4, 4]), np.array([-1, -1]))
    assert undecided_at(sides, 4, 79.0) and not undecided_at(sides, 4, 80.0)  # decided (a ghost) from 80 s
    assert undecided_at(sides, 5, 1e9) and undecided_at(sides, 7, 0.0) and undecided_at(None, 4, 100.0)

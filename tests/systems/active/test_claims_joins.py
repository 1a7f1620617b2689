"""A track both re-joined and merged keeps both links (contact_tracker.py ``join_links``), and contacts shared by
rank (tracking/associators.py ClaimedPDA): weights checked against a hand-worked case."""

import numpy as np

from sonartrack.association.likelihood import Likelihoods
from sonartrack.association.pda import pda_pair_weights
from sonartrack.systems.active.contact_tracker import ActiveTracks, ContactTracker
from sonartrack.systems.active.contacts import ActiveGeometry
from sonartrack.systems.active.settings import ActiveSettings
from sonartrack.systems.active.targets import mirror_targets
from sonartrack.tracking.associators import ClaimedPDA
from sonartrack.tracking.run import PositionTracks


def test_a_track_re_joined_and_merged_keeps_both_links():
    """Track 5 was confirmed soon after track 2 was lost and re-joined onto it, then deleted as the duplicate of
    track 3: one target of three segments. Before, ``{**merged, **joins}`` kept only 5 -> 2, and 3 made a row of
    its own."""
    nav_t = np.array([-60.0, 400.0])
    geometry = ActiveGeometry(nav_t, np.zeros((2, 2)), np.zeros((2, 2)), np.zeros(2))
    trk = ContactTracker(ActiveSettings().tracker_settings(), geometry, None, 1.0, merge_probability=0.99,
                         rejoin_s=600.0)
    trk.merger.merged[5] = 3  # the merger's and the re-join's records, as their scans leave them
    trk.joins[5] = 2
    links = trk.join_links()
    assert set(links) == {(5, 2), (5, 3)}
    rows = [(0.0, 2), (30.0, 2), (60.0, 3), (90.0, 3), (90.0, 5), (120.0, 3), (150.0, 3)]
    t, ids = np.array([r[0] for r in rows]), np.array([r[1] for r in rows], np.int64)
    x = np.zeros((len(rows), 4))
    x[:, :2] = [4000.0, 6000.0]
    n = len(rows)
    tracks = PositionTracks(t, ids, np.ones(n, bool), np.full(n, 0.9), x, np.full(n, 50.0), np.full(n, 50.0),
                            np.ones((n, 1)))
    P = np.stack([np.eye(4)] * n)
    m = mirror_targets(ActiveTracks(tracks, P, None, links), geometry)
    assert len(m) == 1 and sorted(m.chains[0][0]) == [2, 3, 5]
    assert len(mirror_targets(ActiveTracks(tracks, P, None, {5: 2}), geometry)) == 2  # the old record: 2 rows


def _lik(log_ratio, track, meas, n, m, pd=0.5, pg=0.99):
    g = len(track)
    gated = np.zeros((n, m), bool)
    gated[track, meas] = True
    return Likelihoods(np.asarray(log_ratio, float).reshape(g, 1), gated, pd, np.full((n, 1), 1.0 - pd * pg),
                       np.asarray(track), np.asarray(meas), np.zeros((g, 1, 2)), np.tile(np.eye(2), (g, 1, 1, 1)))


def test_claimed_weights_against_a_hand_worked_case():
    """Two tracks gate one contact (ratios 10 and 10), track 0 confirmed (existence 0.95), track 1 tentative
    (0.2); pd 0.5, P_G 0.99, miss 1 - pd P_G = 0.505. Track 0's PDA: beta = 0.5 * 10 / (0.505 + 5) = 0.90827;
    its claim 0.95 * 0.90827 = 0.86285; track 1's ratio 10 * (1 - 0.86285) = 1.37148, its Lambda
    0.505 + 0.5 * 1.37148 = 1.19074 (IPDA's: 5.505), track 0's unchanged."""
    lik = _lik(np.log([10.0, 10.0]), [0, 1], [0, 0], 2, 1)
    a = ClaimedPDA()
    a.set_tracks([0.95, 0.2], [2.95, 0.2], np.ones((2, 1)), [True, False])
    w = a.weights(lik)
    assert np.allclose(np.exp(w.log_lambda[:, 0]), [5.505, 1.19074], rtol=1e-4)
    assert np.allclose(w.beta_pair[:, 0], [5.0 / 5.505, 0.5 * 1.37148 / 1.19074], rtol=1e-4)
    # no claimer: IPDA's numbers; the claimer ranked below: it does not change the track above it
    a.set_tracks([0.95, 0.2], [2.95, 0.2], np.ones((2, 1)), [False, False])
    assert np.allclose(a.weights(lik).log_lambda, pda_pair_weights(lik).log_lambda)
    a.set_tracks([0.95, 0.2], [0.2, 2.95], np.ones((2, 1)), [True, False])
    assert np.allclose(a.weights(lik).log_lambda, pda_pair_weights(lik).log_lambda)


def test_a_contact_outside_the_claimers_gate_is_untouched():
    """Track 1 gates contacts 0 and 1, the confirmed track 0 only contact 0: track 1's ratio on contact 1 stays."""
    lik = _lik(np.log([4.0, 4.0, 4.0]), [0, 1, 1], [0, 0, 1], 2, 2)
    a = ClaimedPDA()
    a.set_tracks([1.0, 0.5], [3.0, 0.5], np.ones((2, 1)), [True, False])
    w = a.weights(lik)
    beta0 = 0.5 * 4.0 / (0.505 + 0.5 * 4.0)  # track 0's own weight of contact 0, its claim (existence 1)
    lam1 = 0.505 + 0.5 * (4.0 * (1.0 - beta0) + 4.0)
    assert np.isclose(np.exp(w.log_lambda[1, 0]), lam1)
    assert np.isclose(w.beta_pair[2, 0], 0.5 * 4.0 / lam1)


def _two(xa, xb, sd_m=30.0, ids=(1, 2)):
    from sonartrack.tracking.tracks import TrackArrays

    x = np.array([xa, xb], float)[:, None]
    P = np.tile(np.diag([sd_m**2, sd_m**2, 0.25, 0.25]), (2, 1, 1, 1))
    return TrackArrays(x, P, np.ones((2, 1)), np.full(2, 0.99), np.ones(2, bool), np.array(ids, np.int64),
                       np.array([0.0, 60.0]), P[:, 0], {})


def test_two_tracks_told_apart_are_not_merged_when_they_meet():
    """keep_apart (tracking/duplicates.py): track 2 (younger) 2 km east of track 1 on one scan, then on top of it
    with the same velocity (two targets crossing, as the test sees them). Without keep_apart the merger deletes
    track 2 as track 1's duplicate and records it as the same target; with it both stay. Two tracks that were never
    apart are merged either way."""
    from sonartrack.association.gating import gate_threshold
    from sonartrack.tracking.deleters import ExistenceDeleter
    from sonartrack.tracking.duplicates import DuplicateMerger

    gamma = gate_threshold(0.99, 4)
    hit = np.ones(2, bool)
    for keep_apart, want in ((False, [1]), (True, [1, 2])):
        m = DuplicateMerger(ExistenceDeleter(0.9, 0.01), gamma, keep_apart=keep_apart)
        assert m.manage(_two([0, 0, 3, 0], [2000, 0, 3, 0]), hit).track_id.tolist() == [1, 2]
        out = m.manage(_two([300, 0, 3, 0], [310, 5, 3, 0]), hit)
        assert out.track_id.tolist() == want and (2 in m.merged) == (not keep_apart)
    m = DuplicateMerger(ExistenceDeleter(0.9, 0.01), gamma, keep_apart=True)
    assert m.manage(_two([0, 0, 3, 0], [10, 5, 3, 0]), hit).track_id.tolist() == [1]
    assert m.merged == {2: 1}


def test_claims_above_match_a_dense_sum():
    """The sorted running sums of associators._claimed_above against the dense sum over every pair of the same
    measurement whose track ranks strictly higher (ties claim nothing from each other)."""
    from sonartrack.tracking.associators import _claimed_above

    rng = np.random.default_rng(4)
    meas, rank, claim = rng.integers(0, 6, 60), rng.integers(0, 4, 60).astype(float), rng.random(60)
    want = [(claim * (meas == meas[g]) * (rank > rank[g])).sum() for g in range(60)]
    assert np.allclose(_claimed_above(meas, rank, claim), want)

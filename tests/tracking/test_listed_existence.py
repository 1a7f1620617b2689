"""A confirmed track is listed while its existence stays above a stated level (tracking/deleters.py listed_tracks,
settings ``listed_existence``), on hand-made tracks and IPDA's existence chain worked by hand."""

import numpy as np
import pytest
from pydantic import ValidationError

from sonartrack.tracking.deleters import ExistenceDeleter, listed_tracks
from sonartrack.tracking.existence import IpdaExistence
from sonartrack.tracking.settings import PositionTrackerSettings
from sonartrack.tracking.tracks import TrackArrays


def _tracks(existence, confirmed):
    n = len(existence)
    P = np.stack([np.diag([100.0, 100.0, 1.0, 1.0])] * n)
    return TrackArrays(np.zeros((n, 1, 4)), P[:, None], np.ones((n, 1)), np.asarray(existence, float),
                       np.asarray(confirmed), np.arange(n, dtype=np.int64), np.zeros(n), P, {})


def test_a_confirmed_track_below_the_listed_level_is_not_listed():
    confirmed, existence = np.array([True, True, True, False]), np.array([0.95, 0.5, 0.49, 0.97])
    # listed: confirmed and at least the level; a tentative track is never listed whatever its existence
    assert listed_tracks(confirmed, existence, 0.5).tolist() == [True, True, False, False]
    # off (P4): every confirmed track
    assert listed_tracks(confirmed, existence, None).tolist() == [True, True, True, False]


def test_a_coasting_track_is_unlisted_when_its_odds_fall_below_even():
    """IPDA with no contact in the gate: P(E)- = p11 P(E), then odds x (1 - P_D P_G) (Musicki et al. 1994, eqs. 11,
    29). From P(E) = 1 with p11 0.98, P_D 0.4, P_G 0.99 by hand: odds 49 x 0.604 = 29.596 (0.96731), then 0.98 x
    0.96731 = 0.94796, odds 18.216 x 0.604 = 11.003 (0.91668), ... the odds shrink by 0.59-0.60 a scan, so even odds
    (0.5) are crossed at the 6th miss: 29.60, 11.00, 5.338, 2.855, 1.599, 0.917 (by hand, 4 figures)."""
    chain, part = IpdaExistence(0.98, 0.0), ExistenceDeleter(0.9, 0.01)
    miss = np.log(1.0 - 0.4 * 0.99)
    T, listed, p = _tracks([1.0], [True]), [], []
    while len(T):
        e = chain.update(chain.predict(T.existence), np.array([miss]))
        T = part.manage(_tracks(e, T.confirmed), np.zeros(1, bool))
        p.append(float(e[0]))
        listed.append(bool(listed_tracks(T.confirmed, T.existence, 0.5)[0]) if len(T) else None)
    assert p[0] == pytest.approx(29.596 / 30.596, rel=1e-4) and p[1] == pytest.approx(11.003 / 12.003, rel=1e-3)
    odds = [q / (1 - q) for q in p[:6]]
    assert odds == pytest.approx([29.60, 11.00, 5.338, 2.855, 1.599, 0.917], rel=0.002)
    assert listed[:6] == [True] * 5 + [False]  # unlisted at the 6th miss
    # the track stays (confirmed, unlisted) until the deletion level: P4 would have listed it all these scans
    assert len(listed) > 10 and listed[-1] is None and not any(listed[5:-1])


def test_the_listed_level_must_lie_above_the_deletion_level():
    assert PositionTrackerSettings(listed_existence=0.5).listed_existence == 0.5
    assert PositionTrackerSettings().listed_existence is None
    with pytest.raises(ValidationError, match="listed_existence"):
        PositionTrackerSettings(listed_existence=0.005)

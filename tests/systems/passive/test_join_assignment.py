"""Fragments joined by the one-to-one assignment of fragment ends to fragment starts (systems/passive/measurements.py
``join_fragments``, ``_join_assignment``), not each fragment's best match in turn."""

import numpy as np

from sonartrack.systems.passive import fragments as measurements
from sonartrack.systems.passive.fragments import MUTUAL_JOIN_VARIANCE_RATIO, join_fragments
from sonartrack.systems.passive.measurements import TrackMeasurements


def _frag(track_id: int, t0: float, t1: float) -> TrackMeasurements:
    t = np.arange(t0, t1, 1.0)
    cone = np.full(len(t), 90.0)
    return TrackMeasurements(track_id, t, cone, np.full(len(t), 8.0), t, cone)


def _with_ratios(monkeypatch, table: dict) -> None:
    """Every pair's variance ratio from ``table`` (earlier id, later id) -> ratio (inf where absent)."""
    monkeypatch.setattr(measurements, "_join_statistic",
                        lambda a, b, nav: table.get((a.track_id, b.track_id), np.inf))


def test_two_ships_broken_at_one_crossing_are_joined_by_the_assignment(monkeypatch):
    # the ratios of study trial 1 (passive-chain, seed 2017): ships A (fragments 2 then 9) and B (3 then 7) broke
    # at one crossing. Best match first joins 7 to 2 (1.72, 7 also 2's best successor) and then 9 to 3 (2.98): both
    # wrong. The assignment maximising the summed margin 3 - ratio takes {2-9, 3-7} (margins 1.21 + 0.90 = 2.11)
    # over {2-7, 3-9} (1.28 + 0.02 = 1.30)
    _with_ratios(monkeypatch, {(2, 7): 1.72, (2, 9): 1.79, (3, 7): 2.10, (3, 9): 2.98})
    frags = [_frag(2, 0.0, 215.0), _frag(3, 0.0, 161.0), _frag(7, 312.0, 571.0), _frag(9, 322.0, 573.0)]
    out = join_fragments(frags, nav=None)
    assert sorted((m.track_id, m.joined_track_ids) for m in out) == [(2, (9,)), (3, (7,))]


def test_assignment_by_hand(monkeypatch):
    ratios = {(1, 3): 1.2, (1, 4): 1.1, (2, 3): 1.4, (2, 4): 2.9}
    frags = [_frag(1, 0.0, 300.0), _frag(2, 0.0, 300.0), _frag(3, 350.0, 600.0), _frag(4, 360.0, 600.0)]
    ratio = lambda a, b: ratios.get((a.track_id, b.track_id), np.inf)  # noqa: E731
    pairs = measurements._join_assignment(frags, ratio, MUTUAL_JOIN_VARIANCE_RATIO, 300.0, 120.0, {})
    # {1-3, 2-4}: margins 1.8 + 0.1 = 1.9; {1-4, 2-3}: 1.9 + 1.6 = 3.5 -> the latter (later index -> earlier index)
    assert pairs == {3: 0, 2: 1}
    # a pair above the bound is never assigned; one fragment alone has nothing to pair with
    assert measurements._join_assignment(frags[:1] + frags[3:], ratio, 1.0, 300.0, 120.0, {}) == {}
    # fragments too far apart (gap 320 s > 300 s) or too short (100 s < 120 s) take no part
    late = [_frag(1, 0.0, 300.0), _frag(3, 620.0, 900.0)]
    assert measurements._join_assignment(late, lambda a, b: 1.0, 3.0, 300.0, 120.0, {}) == {}
    short = [_frag(1, 0.0, 100.0), _frag(3, 150.0, 400.0)]
    assert measurements._join_assignment(short, lambda a, b: 1.0, 3.0, 300.0, 120.0, {}) == {}

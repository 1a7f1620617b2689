"""The crossing test's fits made once (systems/passive/measurements.py ``_crossing_swapped``, ``_join_statistic``
with ``costs``): the same decision and the same variance ratios, bit for bit, as the plain formula it replaces."""

import itertools
import sys
from pathlib import Path

import numpy as np

from sonartrack.systems.passive import fragments as measurements
from sonartrack.systems.passive.fragments import _crossing_swapped, _join_statistic
from sonartrack.systems.passive.measurements import TrackMeasurements

sys.path.insert(0, str(Path(__file__).parent))
from test_join import SHIP_A, SHIP_B, _fragment, _nav  # noqa: E402


def _plain(keep: list[float], swap: list[float], max_ratio: float) -> bool:
    """swap_at_crossings' test as written before: all four ratios, then the formula."""
    return 2.0 * sum(swap) < sum(keep) and max(swap) <= max_ratio


def _labelled(label: str) -> TrackMeasurements:
    t = np.arange(0.0, 20.0)
    return TrackMeasurements(0, t, np.full(20, 90.0), np.ones(20), t, np.full(20, 90.0), None, (label,))


def test_the_decision_is_the_plain_formulas_for_every_ratio(monkeypatch):
    # ratios below, at and above max_ratio = 3, kept ratios that do and do not outweigh them, inf and NaN
    values = (0.1, 1.4, 3.0, 3.0000001, 50.0, np.inf, np.nan)
    pre, post = [_labelled("a"), _labelled("b")], [_labelled("A"), _labelled("B")]
    for swap0, swap1, keep0, keep1 in itertools.product(values, values, (0.5, 20.0, np.inf), (0.7, 400.0)):
        table = {("a", "B"): swap0, ("b", "A"): swap1, ("a", "A"): keep0, ("b", "B"): keep1}
        asked = []

        def ratio(a, b, nav, costs=None, table=table, asked=asked):
            asked.append((a.joined_track_ids[0], b.joined_track_ids[0]))
            return table[asked[-1]]

        monkeypatch.setattr(measurements, "_join_statistic", ratio)
        got = _crossing_swapped(pre, post, None, 3.0)
        assert got == _plain([keep0, keep1], [swap0, swap1], 3.0), (swap0, swap1, keep0, keep1)
        # the kept pairings are fitted only when neither exchanged ratio is above the bound
        fitted_keep = ("a", "A") in asked
        assert fitted_keep == (not swap0 > 3.0 and not swap1 > 3.0)
        assert (("b", "A") in asked) == (not swap0 > 3.0)


def test_a_fragments_own_fit_is_made_once_and_the_ratios_are_unchanged(monkeypatch):
    nav = _nav()
    pre = [_fragment(1, SHIP_A, 400.0, 600.0, nav, 1), _fragment(2, SHIP_B, 400.0, 600.0, nav, 2)]
    post = [_fragment(1, SHIP_A, 700.0, 900.0, nav, 3), _fragment(2, SHIP_B, 690.0, 900.0, nav, 4)]
    plain = {(i, k): _join_statistic(pre[i], post[k], nav) for i in (0, 1) for k in (0, 1)}
    fits = []
    cv_cost = measurements._cv_cost
    monkeypatch.setattr(measurements, "_cv_cost", lambda t, phi, nav: fits.append(len(t)) or cv_cost(t, phi, nav))
    costs: dict = {}
    shared = {(i, k): _join_statistic(pre[i], post[k], nav, costs) for i in (0, 1) for k in (0, 1)}
    assert shared == plain  # bit for bit
    # 4 pairings x (2 own + 2 branch) fits = 16 without sharing; the 4 pieces' own fits once each: 4 + 8
    assert len(fits) == 12 and len(costs) == 4
    # a later piece cut by the earlier one's end (b's part after a's last time) is a fit of its own
    late = _fragment(3, SHIP_A, 550.0, 900.0, nav, 5)
    assert _join_statistic(pre[0], late, nav, costs) == _join_statistic(pre[0], late, nav)
    assert (id(late), int(np.count_nonzero(late.time_s <= pre[0].time_s[-1]))) in costs


def test_the_crossing_decision_on_fitted_fragments_is_the_plain_formulas():
    nav = _nav()
    pre = [_fragment(1, SHIP_A, 400.0, 600.0, nav, 1), _fragment(2, SHIP_B, 400.0, 600.0, nav, 2)]
    for post in ([_fragment(1, SHIP_A, 700.0, 900.0, nav, 3), _fragment(2, SHIP_B, 690.0, 900.0, nav, 4)],
                 [_fragment(1, SHIP_B, 700.0, 900.0, nav, 3), _fragment(2, SHIP_A, 690.0, 900.0, nav, 4)]):
        keep = [_join_statistic(pre[k], post[k], nav) for k in (0, 1)]
        swap = [_join_statistic(pre[k], post[1 - k], nav) for k in (0, 1)]
        assert _crossing_swapped(pre, post, nav, 3.0) == _plain(keep, swap, 3.0)

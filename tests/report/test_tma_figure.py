"""The TMA tactical picture draws only determined positions (an undetermined range is not a position)."""

from types import SimpleNamespace

import numpy as np
import pytest

from sonartrack.report.figures.tma import tactical_picture
from sonartrack.tma.records import OwnshipTrack, TmaSolution

pytest.importorskip("matplotlib")


def _inputs(determined):
    t = np.arange(5.0) * 60.0
    own = OwnshipTrack(t, np.zeros(5), t * 3.0)
    record = SimpleNamespace(time_s=t, bearing_rad=np.full(5, 0.5))
    state = np.column_stack([np.full(5, 4000.0), np.full(5, 6000.0), np.zeros(5), np.zeros(5)])
    state[2] = [2.5e21, 1e21, 0.0, 0.0]  # a diverged row
    reasons = np.array(["" if d else "diverged" for d in determined])
    sol = TmaSolution(t, state, np.tile(np.eye(4) * 1e4, (5, 1, 1)), "imm-mgekf", np.array(determined), reasons)
    return record, own, sol


def _red_lines(fig):
    return [ln for ln in fig.axes[0].lines if ln.get_color() == "r"]


def test_undetermined_rows_are_not_drawn():
    import matplotlib.pyplot as plt

    record, own, sol = _inputs([True, True, False, True, True])
    fig = tactical_picture(record, own, sol)
    (track,) = [ln for ln in _red_lines(fig) if len(ln.get_xdata()) > 1]
    assert np.max(np.abs(track.get_xdata())) < 10  # km: the diverged row is left out
    assert "NOT DETERMINED" not in fig.axes[0].get_title()
    plt.close(fig)


def test_nothing_determined_says_why_and_draws_no_track():
    import matplotlib.pyplot as plt

    record, own, sol = _inputs([False] * 5)
    fig = tactical_picture(record, own, sol)
    assert not _red_lines(fig)
    assert "range NOT DETERMINED (diverged)" in fig.axes[0].get_title()
    plt.close(fig)

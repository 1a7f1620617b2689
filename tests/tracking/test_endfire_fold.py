"""The bearing tracker through endfire (the array's axis): the unfolded cone angle and its fold."""

import numpy as np
import pytest

from sonartrack.tracking.measurements import fold_cone_deg, fold_cone_state
from sonartrack.tracking.run import track_peaks
from sonartrack.tracking.settings import BearingTrackerSettings


def test_fold_by_hand():
    theta, sign = fold_cone_deg([10.0, 179.0, 181.0, 190.0, -5.0, 365.0, 540.0 + 20.0])
    assert theta.tolist() == pytest.approx([10.0, 179.0, 179.0, 170.0, 5.0, 5.0, 160.0])
    assert sign.tolist() == [1, 1, -1, -1, -1, 1, -1]
    x, s = fold_cone_state(np.array([[185.0, 0.5], [30.0, -0.2]]))
    assert np.allclose(x, [[175.0, -0.5], [30.0, -0.2]]) and s.tolist() == [-1, 1]


def _peaks(phi_deg, rng, sigma=0.3):
    """One peak a second at fold(phi) + noise (clipped to 0..180 as the beam grid is), z = 10."""
    theta = np.clip(fold_cone_deg(phi_deg)[0] + sigma * rng.standard_normal(len(phi_deg)), 0.0, 180.0)
    t = np.arange(len(phi_deg), dtype=float)
    return t, theta, np.full(len(t), 10.0)


def _settings(fold: bool) -> BearingTrackerSettings:
    return BearingTrackerSettings(q=0.001, gate_deg=6.0, clutter_density_per_deg=1e-3, false_amplitude_rate=2.0,
                                  amplitude_threshold=4.0, init_amplitude=6.0, init_sigma_p_deg=0.5,
                                  init_amplitude_sd=5.0, confirm_m=8, confirm_n=10, delete_after=20, p_detect=0.9,
                                  endfire_fold=fold)


def test_a_track_runs_on_through_endfire_as_one_track():
    # phi from 150 to 210 deg at 0.2 deg/s: the cone angle rises to 180 and falls back (the target crossed astern)
    phi = 150.0 + 0.2 * np.arange(300)
    t, theta, a = _peaks(phi, np.random.default_rng(3))
    tracks = track_peaks(t, theta, a, _settings(True))
    conf = tracks.confirmed.astype(bool)
    ids = np.unique(tracks.track_id[conf])
    assert len(ids) == 1, ids
    last = tracks.time_s == t[-1]
    assert tracks.unfolded_deg[last][0] == pytest.approx(phi[-1], abs=1.5)  # past 180: on the other side
    assert tracks.bearing_deg[last][0] == pytest.approx(360.0 - phi[-1], abs=1.5)  # reported folded
    assert tracks.unfolded_deg[last][0] > 180.0  # the crossing is in the state, not a bounce
    assert track_peaks(t, theta, a, _settings(False)).unfolded_deg is None

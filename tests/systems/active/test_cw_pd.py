"""The tracker's detection probability per pulse (contact_tracker.py ``_cw_pd``): on a CW ping (contacts carrying a
measured range rate) a miss lowers a confirmed track's existence by IPDA's miss factor with ``pd_cw``, on an LFM ping
(no range rate) with ``pd``; the expected existence is worked by hand from Musicki, Evans, Stankovic 1994, eqs. 11
and 29 (a scan with no contact in the gate: Lambda = 1 - P_D P_G)."""

import numpy as np
import pytest

from sonartrack.systems.active.contact_tracker import ContactTracker
from sonartrack.systems.active.contacts import ActiveGeometry, Contacts
from sonartrack.systems.active.settings import ActiveSettings

PING_S = 30.0


def _contacts(k, xy, rate):
    xy = np.asarray(xy, float).reshape(-1, 2)
    m = len(xy)
    return Contacts(np.full(m, k), np.full(m, PING_S * k), np.arange(m, dtype=np.int64) + 10 * k,
                    np.ones(m, np.int8), xy, np.stack([np.eye(2) * 30.0**2] * m), np.full(m, rate),
                    np.hypot(*xy.T), np.full(m, 30.0))


def _existence_after_a_miss(rate):
    """A target at 3 m/s east held for 12 pings (one contact each, no clutter), then a ping whose only contact lies
    10 km off: (existence before, after, the tracker's settings)."""
    s = ActiveSettings().tracker_settings()
    nav_t = np.arange(-60.0, PING_S * 20, 10.0)
    rx = np.zeros((len(nav_t), 2))
    trk = ContactTracker(s, ActiveGeometry(nav_t, rx, rx, np.zeros_like(nav_t)), None, 1.0, scan_interval_s=PING_S)
    rng = np.random.default_rng(4)
    for k in range(12):
        snap_x = [5000.0 + 3.0 * PING_S * k, 4000.0] + rng.normal(0.0, 30.0, 2)
        trk.step(PING_S * k, _contacts(k, snap_x, rate))
    T = trk.tracker.tracks
    before = float(T.existence[T.confirmed][0])
    tid = int(T.track_id[T.confirmed][0])
    trk.step(PING_S * 12, _contacts(12, [-5000.0, -6000.0], rate))
    T = trk.tracker.tracks
    return before, float(T.existence[T.track_id == tid][0]), s


@pytest.mark.parametrize("cw", [True, False])
def test_a_miss_costs_the_pulses_own_pd(cw):
    before, after, s = _existence_after_a_miss(1.0 if cw else np.nan)
    pd = s.pd_cw if cw else s.pd
    assert s.pd_cw is not None and abs(s.pd_cw - s.pd) > 0.1  # the two cases differ
    pred = s.p_survive * before + s.p_birth * (1.0 - before)
    lam = 1.0 - pd * s.gate_probability
    assert after == pytest.approx(lam * pred / (1.0 - pred + lam * pred), rel=1e-9)

"""Confirmation at a stated false-track rate (tracking/existence.py confirm_threshold_for_rate, deleters.py
RateConfirmation): the rule's closed form by hand, and the rate it states kept on clutter-only scans drawn here
from the tracker's own clutter model (uniform Poisson points), where Ville's bound is exact."""

import numpy as np
import pytest

from sonartrack.tracking.configurations import position_tracker
from sonartrack.tracking.deleters import RateConfirmation
from sonartrack.tracking.existence import confirm_threshold_for_rate
from sonartrack.tracking.settings import PositionTrackerSettings


def test_threshold_by_hand():
    # 10 tracks started a scan, P0 = 0.05 (odds 1/19), stated 0.01 a scan: O_c = 10 / 19 / 0.01 = 52.6
    assert confirm_threshold_for_rate(0.01, 10.0, 0.05) == pytest.approx(52.63158 / 53.63158, rel=1e-6)
    # fewer tracks started than the stated rate: even confirming all keeps it, the threshold is P0
    assert confirm_threshold_for_rate(5.0, 1.0, 0.05) == pytest.approx(0.05)
    # more started, or a lower rate: a higher threshold
    assert confirm_threshold_for_rate(0.01, 20.0, 0.05) > confirm_threshold_for_rate(0.01, 10.0, 0.05)


def clutter_run(stated_per_h: float, scans: int = 240, seed: int = 7, target_from: int | None = None,
                statistic: str = "existence"):
    """(false tracks confirmed, tracks started, threshold at the end, scan of the target's confirmation or None) on
    clutter scans 30 s apart; with ``target_from``, a 5 m/s target detected on every scan from that one."""
    s = PositionTrackerSettings(q=[1e-4], clutter_density_per_m2=2e-7, pd=0.7, confirm_threshold=0.9,
                                initial_existence=0.05)
    trk = position_tracker(s)
    rule = RateConfirmation(stated_per_h, 30.0, s.initial_existence, s.terminate_threshold, statistic=statistic)
    trk.deleter = rule
    rng = np.random.default_rng(seed)
    side = 6000.0
    R = np.diag([60.0**2, 60.0**2])
    confirmed: set[int] = set()
    at = None
    for k in range(scans):
        m = rng.poisson(s.clutter_density_per_m2 * side**2)
        z = rng.uniform(0, side, (m, 2))
        if target_from is not None and k >= target_from:
            truth = np.array([1000.0, 2000.0]) + np.array([3.0, 4.0]) * 30.0 * (k - target_from)
            z = np.vstack([z, truth + rng.normal(0.0, 60.0, 2)])
        snap = trk.step(30.0 * k, z, np.repeat(R[None], len(z), axis=0))
        confirmed |= set(snap.track_id[snap.confirmed].tolist())
        if target_from is not None and at is None and k >= target_from and snap.confirmed.any():
            near = np.hypot(*(snap.x[snap.confirmed, :2] - truth).T) < 300.0
            at = k - target_from + 1 if near.any() else None
    return len(confirmed), rule.started, rule.confirm_threshold, at


@pytest.mark.parametrize("statistic", ["existence", "likelihood_ratio"])
def test_stated_rate_is_kept_on_the_clutter_model(statistic):
    # the likelihood-ratio odds O_0 prod Lambda are the martingale Ville's inequality bounds (p11 not in them)
    from scipy.stats import poisson

    hours = 240 * 30.0 / 3600.0
    for stated in (10.0, 2.0):
        n_false, started, thr, _ = clutter_run(stated, statistic=statistic)
        assert started > 500 and 0.5 < thr < 1.0
        # the count must not exceed what the stated rate allows, beyond chance (Poisson 99.9 % point)
        assert n_false <= poisson.ppf(0.999, stated * hours), (stated, n_false, thr)


def test_a_target_seen_every_scan_is_confirmed_within_five_scans_at_one_false_track_an_hour():
    # the rule's threshold here (~4.5 tracks started a scan, 1 an hour stated): odds 4.5 x (1/19) / (30 / 3600) = 28
    _, started, thr, at = clutter_run(1.0, scans=20, target_from=12)
    assert thr == pytest.approx(confirm_threshold_for_rate(30.0 / 3600.0, started / 20, 0.05))
    assert 0.95 < thr < 0.99
    assert at is not None and at <= 5

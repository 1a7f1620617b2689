"""Amplitude-aided IPDA in the position tracker (tracking/amplitude_parts.py, measurements.py
AmplitudeRangeRateMeasurements, initiators.py AmplitudeOnePointInitiator): a ratio of 1 gives the old tracker's
numbers exactly; one scan's existence update by hand (Lambda with the amplitude ratio, the densities from scipy);
and on a world drawn here (uniform Poisson clutter with heavy-tailed amplitudes, a Swerling 1 target) a target is
confirmed sooner than without amplitudes at a false-track count no higher."""

import numpy as np
import pytest
from scipy import stats

from sonartrack.core.errors import InputError
from sonartrack.tracking.amplitude_parts import with_amplitude
from sonartrack.tracking.configurations import position_tracker
from sonartrack.tracking.deleters import RateConfirmation
from sonartrack.tracking.settings import PositionTrackerSettings

R = np.diag([60.0**2, 60.0**2])


class UnitRatio:
    """A model whose every amplitude ratio is 1 (log 0)."""

    def log_ratio(self, a, w, s):
        return np.zeros(len(np.asarray(a)))

    def add_scan(self, a):
        pass


def scans(seed, n=12, side=4000.0, density=5e-7):
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        z = rng.uniform(0, side, (rng.poisson(density * side**2), 2))
        z = np.vstack([z, [1000.0 + 90.0 * k, 2000.0 + 120.0 * k] + rng.normal(0, 60.0, 2)])
        out.append((30.0 * k, z, 20.0 + rng.exponential(10.0, len(z))))
    return out


def test_a_unit_ratio_gives_the_old_tracker_exactly():
    s = PositionTrackerSettings(clutter_density_per_m2=5e-7, amplitude_aided=True, amplitude_start=True)
    old, new = position_tracker(s), with_amplitude(position_tracker(s), s)
    from dataclasses import replace

    new.measurements = replace(new.measurements, model=UnitRatio())
    object.__setattr__(new.initiator, "model", UnitRatio())
    for t, z, a in scans(1):
        so = old.step(t, z, np.repeat(R[None], len(z), 0))
        sn = new.step(t, z, np.repeat(R[None], len(z), 0), amplitude=a)
        np.testing.assert_array_equal(so.track_id, sn.track_id)
        np.testing.assert_array_equal(so.x, sn.x)
        np.testing.assert_array_equal(so.existence, sn.existence)
    assert {"amp_w", "amp_sum"} <= set(new.tracks.attrs)


def test_amplitudes_are_required_once_aided():
    s = PositionTrackerSettings(amplitude_aided=True)
    trk = with_amplitude(position_tracker(s), s)
    with pytest.raises(InputError, match="amplitude"):
        trk.step(0.0, np.zeros((1, 2)), R)
    assert with_amplitude(position_tracker(PositionTrackerSettings()), PositionTrackerSettings()).measurements.\
        scan_needs == ("R",)  # off: the tracker as built


def test_one_scans_existence_update_by_hand():
    # one track from one contact at scan 0, then one contact near it at scan 1: IPDA's Lambda = 1 - Pd Pg + Pd Pg
    # ... the plain tracker gives Lambda_plain = O+ / O-; with the amplitude ratio r the hit term is multiplied:
    # Lambda = 1 - Pd Pg + (Lambda_plain - 1 + Pd Pg) r, r = Lomax(y; alpha, beta) / GPD(y; scale, xi) by scipy
    s = PositionTrackerSettings(q=[1e-4], amplitude_aided=True, p_survive=1.0)
    old, new = position_tracker(s), with_amplitude(position_tracker(s), s)
    z0, z1, a0, a1 = np.array([[0.0, 0.0]]), np.array([[40.0, -30.0]]), np.array([25.0]), np.array([70.0])
    for trk, a in ((old, None), (new, a0)):
        trk.step(0.0, z0, R, amplitude=a)
    model = new.measurements.model
    scale, shape = model.clutter_law()
    w, total = new.tracks.attrs["amp_w"][0], new.tracks.attrs["amp_sum"][0]
    assert (w, total) == (1.0, 25.0)
    alpha = 1.0 + s.amplitude_target_prior_n + w
    beta = max(s.amplitude_target_prior_n * s.amplitude_target_prior_ratio * scale / (1 - shape) + (total - 25.0 * w),
               (alpha - 1) * scale / (1 - shape))
    y = 70.0 - 25.0  # above the lowest amplitude seen
    r = stats.lomax.pdf(y, alpha - 0.0, scale=beta) / stats.genpareto.pdf(y, shape, scale=scale)
    e_prior = old.tracks.existence[0]
    so, sn = old.step(30.0, z1, R), new.step(30.0, z1, R, amplitude=a1)
    odds = lambda p: p / (1 - p)  # noqa: E731
    lam_plain = odds(so.existence[0]) / odds(e_prior)
    pdpg = s.pd * s.gate_probability
    lam = 1 - pdpg + (lam_plain - 1 + pdpg) * min(r, s.amplitude_max_ratio)
    assert odds(sn.existence[0]) / odds(e_prior) == pytest.approx(lam, rel=1e-9)
    assert r > 1 and sn.existence[0] > so.existence[0]


def world(seed, scans_n, with_target):
    """Uniform Poisson clutter with Pareto-tailed (K-like) amplitudes above 20, and a Swerling 1 target (mean excess
    5x the clutter's median excess, Pd 0.7) moving at 5 m/s from scan 0."""
    rng = np.random.default_rng(seed)
    side, density = 6000.0, 2e-7
    for k in range(scans_n):
        m = rng.poisson(density * side**2)
        z = rng.uniform(0, side, (m, 2))
        a = 20.0 + 6.0 * ((1 - rng.uniform(size=m)) ** -0.3 - 1) / 0.3
        truth = np.array([1500.0, 2500.0]) + np.array([3.0, 4.0]) * 30.0 * k
        if with_target and rng.uniform() < 0.7:
            z = np.vstack([z, truth + rng.normal(0.0, 60.0, 2)])
            a = np.append(a, 20.0 + rng.exponential(40.0))
        yield 30.0 * k, z, a, truth


def run(seed, aided, scans_n, with_target, per_h=1.0):
    s = PositionTrackerSettings(q=[1e-4], clutter_density_per_m2=2e-7, pd=0.7, initial_existence=0.05,
                                amplitude_aided=aided)
    trk = with_amplitude(position_tracker(s), s)
    trk.deleter = RateConfirmation(per_h, 30.0, s.initial_existence, s.terminate_threshold)
    false, at = set(), None
    for k, (t, z, a, truth) in enumerate(world(seed, scans_n, with_target)):
        snap = trk.step(t, z, np.repeat(R[None], len(z), 0), amplitude=a if aided else None)
        near = np.hypot(*(snap.x[:, :2] - truth).T) < 300.0
        false |= set(snap.track_id[snap.confirmed & ~(near & with_target)].tolist())
        if with_target and at is None and (snap.confirmed & near).any():
            at = k + 1
    return len(false), at


def test_confirmed_sooner_with_amplitudes_and_no_more_false_tracks():
    plain = [run(seed, False, 25, True) for seed in range(6)]
    aided = [run(seed, True, 25, True) for seed in range(6)]
    scans_to = lambda rs: np.array([26 if at is None else at for _, at in rs])  # noqa: E731
    assert scans_to(aided).mean() < scans_to(plain).mean() - 1.0, (scans_to(plain), scans_to(aided))
    # clutter only, 2 h: at 5 false tracks an hour stated, the count stays within its Poisson 99.9 % point
    n_false = sum(run(seed, True, 120, False, per_h=5.0)[0] for seed in (20, 21))
    assert n_false <= stats.poisson.ppf(0.999, 5.0 * 2)


def test_a_new_tracks_odds_times_its_first_contacts_ratio():
    # amplitude_start: O = O_0 r, r = Lomax(y; alpha0, beta0) / GPD(y) under the prior target law (scipy's densities)
    s = PositionTrackerSettings(amplitude_aided=True, amplitude_start=True, initial_existence=0.05)
    trk = with_amplitude(position_tracker(s), s)
    trk.step(0.0, np.array([[0.0, 0.0]]), R, amplitude=np.array([30.0]))  # the clutter sample's first scan
    model = trk.measurements.model
    z, a = np.array([[5000.0, 5000.0], [9000.0, 1000.0]]), np.array([31.0, 90.0])
    scale, shape = model.clutter_law()  # the law before this scan (the initiator adds the scan after starting)
    snap = trk.step(30.0, z, np.repeat(R[None], 2, 0), amplitude=a)
    alpha = 1.0 + s.amplitude_target_prior_n
    beta = s.amplitude_target_prior_n * s.amplitude_target_prior_ratio * scale / (1 - shape)
    y = a - 30.0
    r = np.minimum(stats.lomax.pdf(y, alpha, scale=beta) / stats.genpareto.pdf(y, shape, scale=scale),
                   s.amplitude_max_ratio)
    new = snap.existence[-2:]
    np.testing.assert_allclose(new / (1 - new), 0.05 / 0.95 * r, rtol=1e-9)
    assert new[1] > new[0]  # the stronger contact starts the likelier track


def test_a_tracks_amplitude_sums_follow_its_association_weights():
    s = PositionTrackerSettings(q=[1e-4], amplitude_aided=True, amplitude_target_memory=0.5)
    trk = with_amplitude(position_tracker(s), s)
    trk.step(0.0, np.array([[0.0, 0.0]]), R, amplitude=np.array([40.0]))
    trk.step(30.0, np.array([[30.0, 20.0]]), R, amplitude=np.array([80.0]))  # one contact in the gate
    w, total = trk.tracks.attrs["amp_w"][0], trk.tracks.attrs["amp_sum"][0]
    # w = 0.5 x 1 + beta, sum = 0.5 x 40 + beta x 80, with beta in (0, 1): the same beta in both
    beta = w - 0.5
    assert 0.0 < beta < 1.0
    assert total == pytest.approx(20.0 + 80.0 * beta)

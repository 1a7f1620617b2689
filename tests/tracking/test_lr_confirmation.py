"""IPDA's existence update by hand for one hit and one miss (Musicki, Evans, Stankovic 1994, eqs. 11 and 29), and
the rate confirmation on the likelihood-ratio odds (tracking/deleters.py RateConfirmation ``statistic``): the odds
the tracker accumulates are the hand-worked O_0 prod Lambda, and where p11 caps the existence's odds below the
threshold only that statistic confirms a target seen every scan."""

import numpy as np
import pytest

from sonartrack.tracking.configurations import position_tracker
from sonartrack.tracking.deleters import RateConfirmation
from sonartrack.tracking.settings import PositionTrackerSettings

T_S, SIGMA_V, Q, PD, PG, LAM, P0, P11 = 30.0, 5.0, 1e-4, 0.7, 0.99, 1e-6, 0.05, 0.98
R = np.diag([40.0**2, 90.0**2])


def _tracker(statistic: str = "likelihood_ratio", floor: float = 0.0):
    s = PositionTrackerSettings(q=[Q], pd=PD, gate_probability=PG, clutter_density_per_m2=LAM, p_survive=P11,
                                initial_existence=P0, init_velocity_std_mps=SIGMA_V, confirm_threshold=0.9)
    trk = position_tracker(s)
    trk.deleter = RateConfirmation(1.0, T_S, P0, s.terminate_threshold, floor=floor, statistic=statistic)
    return trk


def _by_hand_lambda(z0, z1):
    """Lambda of a one-point track started at z0 (velocity prior SIGMA_V) that gates z1 one scan later (None: a
    miss), written out: CV prediction with Q = q [[T^3/3, T^2/2], [T^2/2, T]] per axis, S = H P H' + R."""
    P = np.diag([R[0, 0], R[1, 1], SIGMA_V**2, SIGMA_V**2])
    F = np.eye(4)
    F[0, 2] = F[1, 3] = T_S
    Qm = Q * np.kron(np.array([[T_S**3 / 3, T_S**2 / 2], [T_S**2 / 2, T_S]]), np.eye(2))
    Pp = F @ P @ F.T + Qm
    if z1 is None:
        return 1.0 - PD * PG
    S = Pp[:2, :2] + R
    nu = np.asarray(z1, float) - np.asarray(z0, float)
    d2 = nu @ np.linalg.solve(S, nu)
    assert d2 < 9.21  # inside the 0.99 gate
    g = np.exp(-0.5 * d2) / (2 * np.pi * np.sqrt(np.linalg.det(S)))
    return 1.0 - PD * PG + PD * g / LAM


@pytest.mark.parametrize("z1", [[120.0, -200.0], None], ids=["hit", "miss"])
def test_one_update_by_hand(z1):
    trk = _tracker()
    z0 = np.array([5000.0, 3000.0])
    trk.step(0.0, z0[None], R[None])
    far = np.array([[-40000.0, -40000.0]])  # a scan must hold something; far outside every gate
    snap = trk.step(T_S, (z0 + np.asarray(z1))[None] if z1 is not None else far, R[None])
    lam = _by_hand_lambda(z0, z0 + np.asarray(z1) if z1 is not None else None)
    e_pred = P11 * P0  # eq. 11 with p21 = 0
    e_post = lam * e_pred / (1.0 - e_pred + lam * e_pred)  # eq. 29
    first = snap.track_id == 1
    assert snap.existence[first][0] == pytest.approx(e_post, rel=1e-9)
    odds = trk.tracks.attrs["log_lr_odds"][trk.tracks.track_id == 1][0]
    assert odds == pytest.approx(np.log(P0 / (1 - P0)) + np.log(lam), rel=1e-9)  # p11 not in it
    if z1 is None:
        assert lam == pytest.approx(0.307)


def _straight_run(statistic: str, floor: float, scans: int = 25):
    """Scan at which a target seen every scan (no clutter) is first confirmed, and its largest existence."""
    trk = _tracker(statistic, floor)
    rng = np.random.default_rng(3)
    at, e_max = None, 0.0
    for k in range(scans):
        truth = np.array([2000.0, 1000.0]) + np.array([3.0, -2.0]) * T_S * k
        snap = trk.step(T_S * k, (truth + rng.normal(0.0, [40.0, 90.0]))[None], R[None])
        if len(snap.track_id):
            e_max = max(e_max, float(snap.existence.max()))
        if at is None and snap.confirmed.any():
            at = k + 1
    return at, e_max


def test_p11_cap_keeps_the_existence_below_a_high_threshold_but_not_the_likelihood_ratio():
    # a floor of 0.9995 (odds 1999): the existence's predicted odds are at most p11 / (1 - p11) = 49 and a hit's
    # Lambda here is at most 1 - Pd Pg + Pd / (2 pi sqrt|R| lambda) = 31.2 (S >= R), so its odds never pass
    # 49 x 31.2 = 1530; the likelihood ratio of a target seen every scan grows without bound
    lam_max = 1.0 - PD * PG + PD / (2 * np.pi * np.sqrt(np.linalg.det(R)) * LAM)
    assert P11 / (1 - P11) * lam_max < 1999.0
    at_e, e_max = _straight_run("existence", 0.9995)
    assert at_e is None and e_max < 0.9995
    at_lr, _ = _straight_run("likelihood_ratio", 0.9995)
    assert at_lr is not None


def test_likelihood_ratio_confirms_no_later_than_the_existence():
    at_e, _ = _straight_run("existence", 0.0)
    at_lr, _ = _straight_run("likelihood_ratio", 0.0)
    assert at_e is not None and at_lr is not None and at_lr <= at_e


def test_statistic_named_wrong_is_refused():
    from sonartrack.core.errors import InputError

    with pytest.raises(InputError, match="statistic"):
        RateConfirmation(1.0, T_S, P0, 0.01, statistic="odds")


def test_velocity_prior_from_a_speed_bound_matches_the_uniform_disc():
    # independent: the second moments of velocities drawn uniformly over the disc |v| <= 7.5 m/s
    from sonartrack.tracking.initiators import velocity_std_from_speed_bound

    rng = np.random.default_rng(0)
    r, th = 7.5 * np.sqrt(rng.uniform(size=200_000)), rng.uniform(0, 2 * np.pi, 200_000)
    v = np.stack([r * np.cos(th), r * np.sin(th)], -1)
    cov = v.T @ v / len(v)
    assert velocity_std_from_speed_bound(7.5) == pytest.approx(np.sqrt(cov[0, 0]), rel=0.01)
    assert abs(cov[0, 1]) < 0.05
    from sonartrack.core.errors import InputError

    with pytest.raises(InputError):
        velocity_std_from_speed_bound(0.0)

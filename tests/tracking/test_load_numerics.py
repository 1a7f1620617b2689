"""The position tracker under load: numerical health over a long heavy-clutter run, and
the load-oriented fast paths (windowed pre-gate, pair-only PDA weights, in-loop gains) giving the NumPy
references' numbers bit for bit on large scans.

No wall-clock assertion here: benchmarks/bench_tracker_load.py measures the time per scan."""

import numpy as np
import pytest

from sonartrack.association.likelihood import position_likelihoods, window_likelihoods
from sonartrack.association.pda import pda_mixture_update, pda_pair_weights, pda_weights
from sonartrack.association.pda_mixture_kernel import dense_row_sums, pda_mixture_update_pairs
from sonartrack.tracking.configurations import position_tracker
from sonartrack.tracking.settings import PositionTrackerSettings

SIDE_M = 20_000.0  # 400 clutter points a scan in this square: the tracker's assumed 1e-6 /m^2
SCAN_PERIOD_S = 10.0


def _not_spd(P) -> int:
    """Covariances (..., d, d) that are not exactly symmetric or fail a Cholesky factorisation."""
    P = np.asarray(P).reshape(-1, *np.shape(P)[-2:])
    bad = int(np.sum(~np.all(np.swapaxes(P, -1, -2) == P, axis=(-1, -2))))
    try:
        np.linalg.cholesky(P)  # all at once; one by one only when some fail
    except np.linalg.LinAlgError:
        for p in P:
            try:
                np.linalg.cholesky(p)
            except np.linalg.LinAlgError:
                bad += 1
    return bad


def _scans(rng, n_scans: int):
    """Four straight targets at 3 m/s (staying inside the square), P_D 0.8, 20 m noise, 400 uniform clutter."""
    pos = np.array([[4000.0, 4000.0], [16000.0, 5000.0], [6000.0, 15000.0], [12000.0, 12000.0]])
    heading = np.deg2rad([45.0, 120.0, -30.0, 200.0])
    vel = 3.0 * np.stack([np.cos(heading), np.sin(heading)], -1)
    for k in range(n_scans):
        truth = pos + vel * k * SCAN_PERIOD_S
        seen = rng.random(len(truth)) < 0.8
        z = np.concatenate([truth[seen] + rng.normal(0, 20.0, (int(seen.sum()), 2)),
                            rng.uniform(0, SIDE_M, (rng.poisson(400), 2))])
        yield k * SCAN_PERIOD_S, z, np.broadcast_to(400.0 * np.eye(2), (len(z), 2, 2)), truth


def test_heavy_clutter_run_keeps_every_covariance_spd_and_every_target_confirmed():
    """300 scans with ten times P4's clutter: every track covariance (every mode, and the combined one) stays
    exactly symmetric and positive definite after every scan, and each target, once held by a confirmed
    track, keeps that same track, confirmed and near it, to the end (nothing lost to a numerical failure)."""
    rng = np.random.default_rng(12)
    trk = position_tracker(PositionTrackerSettings())
    held: dict[int, int] = {}  # target -> the confirmed track id that holds it from scan 30 on
    for k, (t, z, R, truth) in enumerate(_scans(rng, 300)):
        snap = trk.step(t, z, R)
        T = trk.tracks
        assert _not_spd(T.P) == 0 and _not_spd(snap.P) == 0, f"scan {k}"
        assert np.isfinite(T.x).all() and np.all((T.existence >= 0) & (T.existence <= 1)), f"scan {k}"
        assert len(T) > 20  # a real load: clutter keeps starting tentative tracks
        dist = np.linalg.norm(snap.x[None, :, :2] - truth[:, None], axis=-1)  # (targets, tracks)
        if k == 30:
            for i in range(len(truth)):
                near = np.nonzero(snap.confirmed & (dist[i] < 100.0))[0]
                assert len(near), f"target {i} has no confirmed track at scan 30"
                held[i] = int(snap.track_id[near[np.argmin(dist[i, near])]])
        for i, tid in held.items():
            at = np.nonzero(snap.track_id == tid)[0]
            assert len(at) == 1 and snap.confirmed[at[0]], f"target {i}'s track {tid} lost at scan {k}"
            assert dist[i, at[0]] < 150.0, f"target {i}'s track {tid} drifted {dist[i, at[0]]:.0f} m at scan {k}"
    assert len(held) == 4


def _large_scan(rng, n: int, r: int, m: int):
    """n tracks x r modes over 40 km with a mix of tight and very wide covariances, m measurements (a third near
    the tracks, one exactly on a track), per-measurement R."""
    x = np.zeros((n, r, 4))
    x[:, :, :2] = rng.uniform(0, 40_000, (n, 1, 2)) + rng.normal(0, 30, (n, r, 2))
    x[:, :, 2:] = rng.normal(0, 3, (n, r, 2))
    A = rng.normal(size=(n, r, 4, 4)) * np.exp(rng.uniform(0, 7, (n, 1, 1, 1)))
    P = A @ np.swapaxes(A, -1, -2) + np.diag([400.0, 400.0, 4.0, 4.0])
    near = x[rng.integers(0, n, m // 3), 0, :2] + rng.normal(0, 100, (m // 3, 2))
    z = np.concatenate([near, rng.uniform(0, 40_000, (m - m // 3, 2))])
    z[-1] = x[0, 0, :2]
    B = rng.normal(size=(m, 2, 2)) * 12
    return x, P, z, B @ np.swapaxes(B, -1, -2) + 100 * np.eye(2)


@pytest.mark.parametrize("seed", range(3))
def test_windowed_pregate_and_pair_weights_equal_the_dense_references_on_a_large_scan(seed):
    rng = np.random.default_rng(seed)
    x, P, z, R = _large_scan(rng, 300, 2, 1500 + 300 * seed)
    kw = dict(pd=0.8, pg=0.99, gamma=9.21, clutter_density=rng.uniform(1e-7, 1e-6, len(z)) if seed else 1e-6)
    lik = position_likelihoods(x, P, z, R, **kw)
    ref = position_likelihoods(x, P, z, R, **kw, compiled=False)  # every pair's per-axis test in NumPy
    for name in ("pair_log_ratio", "gated", "pair_track", "pair_meas", "nu", "S_inv"):
        assert np.array_equal(getattr(lik, name), getattr(ref, name)), name
    assert len(lik.pair_track) > 1000 and np.bincount(lik.pair_track).max() > 8  # long rows: pairwise sum splits
    dense, pairs = pda_weights(lik), pda_pair_weights(lik)
    assert np.array_equal(pairs.beta0, dense.beta0) and np.array_equal(pairs.log_lambda, dense.log_lambda)
    assert np.array_equal(pairs.beta_pair, dense.beta[lik.pair_track, :, lik.pair_meas])
    for u, v in zip(pda_mixture_update_pairs(x, P, lik, pairs.beta0, pairs.beta_pair),
                    pda_mixture_update(x, P, lik, dense.beta0, dense.beta), strict=True):
        assert np.array_equal(u, v)


def test_pair_weights_equal_dense_ones_with_per_track_detection_probabilities():
    """The bearing measurement model's P_D per track and miss weight per mode (window gate)."""
    rng = np.random.default_rng(4)
    n, m = 40, 300
    x = np.stack([rng.uniform(0, 180, n), rng.normal(0, 0.2, n)], -1)[:, None]
    P = np.broadcast_to(np.array([[2.0, 0.5], [0.5, 0.3]]), (n, 1, 2, 2)).copy()
    lik = window_likelihoods(x, P, rng.uniform(0, 180, m), np.full(n, 1.5), gate_width=10.0,
                             pd_hit=rng.uniform(0.5, 1, n), pd_miss=rng.uniform(0.5, 1, n), clutter_density=0.5)
    dense, pairs = pda_weights(lik), pda_pair_weights(lik)
    assert np.array_equal(pairs.beta0, dense.beta0) and np.array_equal(pairs.log_lambda, dense.log_lambda)
    assert np.array_equal(pairs.beta_pair, dense.beta[lik.pair_track, :, lik.pair_meas])


@pytest.mark.parametrize("m", [1, 7, 8, 9, 127, 128, 129, 136, 257, 1000, 2117, 5000])
def test_dense_row_sums_are_numpys_dense_sums_bit_for_bit(m):
    """NumPy's pairwise summation of rows that are zero outside a few gated entries, from those entries alone."""
    rng = np.random.default_rng(m)
    n = 60
    mask = rng.random((n, m)) < rng.uniform(0, 0.7, (n, 1)) ** 2
    dense = np.where(mask[:, None], np.exp(rng.normal(0, 4, (n, 2, m))), 0.0)
    ti, mi = np.nonzero(mask)
    got = dense_row_sums(ti, mi, np.ascontiguousarray(dense[ti, :, mi]), n, m)
    assert np.array_equal(got, dense.sum(axis=-1))
    if m >= 129:  # a sequential sum differs somewhere: the test can tell the pairwise order from it
        seq = np.zeros((n, 2))
        for t, j in zip(ti, mi, strict=True):
            seq[t] += dense[t, :, j]
        assert not np.array_equal(seq, got)

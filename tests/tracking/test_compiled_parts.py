"""The tracker's compiled IMM steps (filters/imm_kernel.py) give filters/imm.py's NumPy numbers exactly."""

import numpy as np
import pytest

from sonartrack.filters.imm import imm_combine, imm_mix, imm_mixing
from sonartrack.filters.imm_kernel import combine, mix
from sonartrack.tracking.motion import ImmConstantVelocity
from sonartrack.tracking.tracks import TrackArrays, TrackSnapshot


def _modes(rng, n: int, r: int, d: int):
    x = rng.normal(0, 500, (n, r, d))
    A = rng.normal(size=(n, r, d, d))
    P = A @ np.swapaxes(A, -1, -2) * 50 + np.eye(d)
    return x, P, rng.dirichlet(np.ones(r), size=n)


@pytest.mark.parametrize("r", [1, 2, 3, 4])
@pytest.mark.parametrize("d", [2, 4])
def test_compiled_mix_and_combine_equal_numpy(r, d):
    rng = np.random.default_rng(10 * r + d)
    for n in (0, 1, 17):
        x, P, mu = _modes(rng, n, r, d)
        _, w = imm_mixing(mu, rng.dirichlet(np.ones(r), size=r))
        for u, v in zip(mix(x, P, w) + combine(mu, x, P), imm_mix(x, P, w) + imm_combine(mu, x, P), strict=True):
            assert u.shape == v.shape and np.array_equal(u, v)


def test_interaction_of_the_motion_part_is_imm_mixing_then_mixing():
    rng = np.random.default_rng(4)
    x, P, mu = _modes(rng, 9, 3, 4)
    Pi = np.array([[0.98, 0.01, 0.01], [0.02, 0.96, 0.02], [0.05, 0.05, 0.9]])
    c, x0, P0 = ImmConstantVelocity((1e-4, 3e-3, 0.05), transition=Pi).interact(mu, x, P)
    c_ref, w = imm_mixing(mu, Pi)
    x0_ref, P0_ref = imm_mix(x, P, w)
    assert np.array_equal(c, c_ref) and np.array_equal(x0, x0_ref) and np.array_equal(P0, P0_ref)
    # a mixed covariance carries the spread of the modes: larger than the weighted mean of the P_i alone
    assert np.all(np.linalg.eigvalsh(P0 - np.einsum("nij,nikl->njkl", w, P)) > -1e-6)


def test_snapshot_combines_the_modes_as_imm_combine():
    rng = np.random.default_rng(5)
    x, P, mu = _modes(rng, 6, 2, 4)
    T = TrackArrays(x, P, mu, np.full(6, 0.5), np.zeros(6, bool), np.arange(6), np.zeros(6), P[:, 0])
    snap = TrackSnapshot.of(3.0, T)
    xc, Pc = imm_combine(mu, x, P)
    assert np.array_equal(snap.x, xc) and np.array_equal(snap.P, Pc)

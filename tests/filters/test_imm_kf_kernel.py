"""The compiled IMM-KF step equals the NumPy reference (filters/imm_kf.py) over several steps."""

import numpy as np
import pytest

from sonartrack.filters.imm_kf import imm_kf_step
from sonartrack.filters.imm_kf_kernel import imm_kf_step_fast
from sonartrack.models.motion import H_POSITION, cv_process_noise_stack, cv_transition


@pytest.mark.parametrize("qs", [(0.01, 1.0), (1e-4, 0.01, 0.5)])
def test_kernel_equals_numpy(qs):
    rng = np.random.default_rng(len(qs))
    r = len(qs)
    F, Q, H = cv_transition(2.0), cv_process_noise_stack(2.0, qs), H_POSITION
    R = np.array([[30.0, 4.0], [4.0, 20.0]])
    Pi = np.full((r, r), 0.03 / (r - 1))
    np.fill_diagonal(Pi, 0.97)
    x = rng.normal(size=(r, 4))
    P = np.stack([np.eye(4) * 50 for _ in range(r)])
    mu = np.full(r, 1.0 / r)
    xa, Pa, mua = x.copy(), P.copy(), mu.copy()
    for _ in range(10):
        z = rng.normal(size=2) * 10
        xa, Pa, mua, xca, Pca = imm_kf_step(xa, Pa, mua, z, F, Q, H, R, Pi)
        x, P, mu, xc, Pc = imm_kf_step_fast(x, P, mu, z, F, Q, H, R, Pi)
        np.testing.assert_allclose(x, xa, rtol=1e-11, atol=1e-11)
        np.testing.assert_allclose(P, Pa, rtol=1e-11, atol=1e-11)
        np.testing.assert_allclose(mu, mua, rtol=1e-11, atol=1e-14)
        np.testing.assert_allclose(xc, xca, rtol=1e-11, atol=1e-11)
        np.testing.assert_allclose(Pc, Pca, rtol=1e-11, atol=1e-11)

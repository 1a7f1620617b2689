"""The compiled single-track PDA equals the NumPy reference (association/pda.py)."""

import numpy as np
import pytest

from sonartrack.association.pda import pda_update
from sonartrack.association.pda_kernel import pda_update_fast


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("shared_R", [True, False])
def test_kernel_equals_numpy(seed, shared_R):
    rng = np.random.default_rng(seed)
    x = rng.normal(0, 10, 4)
    A = rng.normal(size=(4, 4))
    P = A @ A.T + np.diag([300.0, 300.0, 3.0, 3.0])
    m = int(rng.integers(0, 45))
    z = x[:2] + rng.normal(0, 40, (m, 2))
    if shared_R:
        R = np.array([[50.0, 10.0], [10.0, 80.0]])
    else:
        B = rng.normal(size=(m, 2, 2)) * 5
        R = B @ np.swapaxes(B, -1, -2) + np.eye(2) * 20
    rho = rng.uniform(1e-5, 1e-3, m) if seed % 2 else 3e-4
    kw = dict(pd=0.85, pg=0.99, gamma=9.21, clutter_density=rho)
    xa, Pa, b0a, ba = pda_update(x, P, z, R, **kw)
    xb, Pb, b0b, bb = pda_update_fast(x, P, z, R, **kw)
    np.testing.assert_allclose(xb, xa, rtol=1e-12, atol=1e-10)
    np.testing.assert_allclose(Pb, Pa, rtol=1e-12, atol=1e-10)
    assert b0b == pytest.approx(b0a, rel=1e-13)
    np.testing.assert_allclose(bb, ba, rtol=1e-12, atol=1e-15)


def test_singular_innovation_is_reported():
    with pytest.raises(np.linalg.LinAlgError):
        pda_update_fast(np.zeros(4), np.zeros((4, 4)), np.zeros((1, 2)), np.zeros((2, 2)), pd=0.9, pg=0.99,
                        gamma=9.21, clutter_density=1e-3)

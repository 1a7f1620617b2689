"""Bearing + frequency measurement model: hand cases, Jacobians, and the modifiability results."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonartrack.core.angles import wrap_angle
from sonartrack.models.passive import bearing_modified_row, bf_jacobian, bf_measurement, bf_residual, modified_matrix
from sonartrack.models.relative_motion import (
    input_from_acceleration,
    observer_inputs,
    relative_predict_mean,
    relative_process_noise,
    relative_transition,
)

C = 1500.0


def random_states(rng, n):
    r = rng.uniform(500.0, 30_000.0, n)
    b = rng.uniform(-np.pi, np.pi, n)
    v = rng.uniform(-12.0, 12.0, (n, 2))
    f0 = rng.uniform(50.0, 2000.0, n)
    return np.column_stack([r * np.sin(b), r * np.cos(b), v, f0])


def test_hand_cases():
    # due north, receding at 15 m/s: bearing 0, f = f0 (1 - 15/1500)
    z = bf_measurement([0.0, 1000.0, 0.0, 15.0, 300.0])
    assert z[0] == 0.0 and z[1] == pytest.approx(297.0)
    # due east, approaching at 7.5 m/s: bearing pi/2, f = f0 (1 + 7.5/1500)
    z = bf_measurement([2000.0, 0.0, -7.5, 3.0, 400.0])
    assert z[0] == pytest.approx(np.pi / 2) and z[1] == pytest.approx(402.0)
    # due south-west: bearing -135 deg; a purely tangential velocity gives no Doppler shift
    z = bf_measurement([-1000.0, -1000.0, 5.0, -5.0, 100.0])
    assert z[0] == pytest.approx(-3 * np.pi / 4) and z[1] == pytest.approx(100.0)


def test_jacobian_matches_central_differences():
    rng = np.random.default_rng(0)
    X = random_states(rng, 50)
    H = bf_jacobian(X)
    for i in range(5):
        dX = np.zeros_like(X)
        # f is linear in each velocity component and in f0: big steps there avoid round-off
        dX[:, i] = 1e-6 * np.abs(X[:, i]) if i < 2 else 1e-2
        num = bf_residual(bf_measurement(X + dX), bf_measurement(X - dX)) / (2 * dX[:, i, None])
        np.testing.assert_allclose(H[:, :, i], num, rtol=1e-6, atol=1e-9)  # atol: round-off of ~1e3 Hz differences


def test_residual_wraps_only_the_bearing():
    nu = bf_residual([np.pi - 0.01, 300.0], [-np.pi + 0.01, 301.0])
    assert nu[0] == pytest.approx(-0.02) and nu[1] == pytest.approx(-1.0)


def on_bearing_line(rng, z, n):
    """States that produce the noise-free bearing z (any range, velocity, f0)."""
    r = rng.uniform(100.0, 40_000.0, n)
    return np.column_stack([r * np.sin(z), r * np.cos(z), rng.normal(0, 8, (n, 2)), rng.uniform(100, 500, n)])


@settings(max_examples=200, deadline=None)
@given(st.floats(-np.pi, np.pi), st.floats(1000.0, 30_000.0), st.floats(-1.2, 1.2), st.integers(0, 2**31))
def test_bearing_row_is_modifiable(z, r_hat, delta, seed):
    """g (X - X_hat) = tan(h(X) - h(X_hat)) for every X on the bearing line (Song & Speyer's g), and
    the exact variant gives h(X) - h(X_hat) itself: the derivation in models/passive.py."""
    rng = np.random.default_rng(seed)
    b_hat = z - delta
    X_hat = np.array([r_hat * np.sin(b_hat), r_hat * np.cos(b_hat), 1.0, -2.0, 300.0])
    X = on_bearing_line(rng, z, 20)
    dh = wrap_angle(bf_measurement(X)[:, 0] - bf_measurement(X_hat)[0])
    g = bearing_modified_row(z, X_hat)
    assert np.all(g[2:] == 0.0)
    np.testing.assert_allclose((X - X_hat) @ g, np.tan(dh), rtol=1e-9, atol=1e-12)
    g_exact = bearing_modified_row(z, X_hat, exact=True)
    np.testing.assert_allclose((X - X_hat) @ g_exact, dh, rtol=1e-9, atol=1e-12)


def test_modified_row_tends_to_the_jacobian():
    rng = np.random.default_rng(3)
    X = random_states(rng, 30)
    z = bf_measurement(X)
    np.testing.assert_allclose(bearing_modified_row(z[:, 0], X), bf_jacobian(X)[:, 0, :], rtol=1e-12, atol=1e-15)
    G = modified_matrix(z, X, bf_jacobian(X))
    np.testing.assert_allclose(G, bf_jacobian(X), rtol=1e-12, atol=1e-15)


def test_modified_row_falls_back_far_off_the_line():
    X_hat = np.array([0.0, 5000.0, 0.0, 0.0, 300.0])  # bearing 0; measured bearing 90 deg away
    g = bearing_modified_row(np.pi / 2, X_hat)
    np.testing.assert_allclose(g, bf_jacobian(X_hat)[0])


def least_squares_misfit(points, X_hat, target):
    """Smallest relative misfit of any g with g (X_i - X_hat) = target for all i."""
    A = points - X_hat
    b = np.full(len(points), target)
    g, *_ = np.linalg.lstsq(A, b, rcond=None)
    return np.linalg.norm(A @ g - b) / np.linalg.norm(b)


def frequency_level_set(rng, z_f, n, bearing=None):
    """States X with h_f(X) = z_f (on the ray of ``bearing`` if given): any position, any velocity
    across the line of sight, the radial speed that f0 requires."""
    f0 = rng.uniform(295.0, 305.0, n)
    radial = C * (1.0 - z_f / f0)
    r = rng.uniform(2000.0, 20_000.0, n)
    a = np.full(n, bearing) if bearing is not None else rng.uniform(-np.pi, np.pi, n)
    u = np.column_stack([np.sin(a), np.cos(a)])
    across = np.column_stack([np.cos(a), -np.sin(a)])
    tang = rng.normal(0, 6, n)
    X = np.column_stack([r[:, None] * u, radial[:, None] * u + tang[:, None] * across, f0])
    np.testing.assert_allclose(bf_measurement(X)[:, 1], z_f, rtol=1e-12)
    return X


def test_frequency_row_is_not_modifiable():
    """No g reproduces h_f(X) - h_f(X_hat) over the states giving the same frequency: their affine
    hull is all of R^5 (derivation in models/passive.py). The same construction finds an exact g for
    the bearing row."""
    rng = np.random.default_rng(7)
    z_f = 300.3
    X_hat = np.array([7000.0 * np.sin(0.38), 7000.0 * np.cos(0.38), -2.0, 1.0, 299.8])
    pts = frequency_level_set(rng, z_f, 60)
    assert np.linalg.matrix_rank(pts[1:] - pts[0], tol=1e-6) == 5
    assert least_squares_misfit(pts, X_hat, z_f - bf_measurement(X_hat)[1]) > 0.05
    # control: the bearing row over states sharing a bearing is exactly modifiable (residual form)
    z_b = 0.4
    pts_b = on_bearing_line(rng, z_b, 60)
    assert least_squares_misfit(pts_b, X_hat, wrap_angle(z_b - bf_measurement(X_hat)[0])) < 1e-9


def test_frequency_row_with_the_bearing_only_admits_a_degenerate_g():
    """Adding the bearing: the only g is along the across-the-line direction and scales as
    1 / (distance of X_hat from the bearing line) -- unusable; with f0 known a bounded g exists."""
    rng = np.random.default_rng(8)
    z_b, z_f = 0.4, 300.3
    n = np.array([np.cos(z_b), -np.sin(z_b), 0, 0, 0])
    pts = frequency_level_set(rng, z_f, 60, bearing=z_b)
    assert np.linalg.matrix_rank(pts[1:] - pts[0], tol=1e-6) == 4  # the whole ray x R^3
    norms = []
    for off in (0.02, 0.002):  # X_hat 0.02 rad, then 0.002 rad, off the measured line
        X_hat = np.array([7000.0 * np.sin(z_b - off), 7000.0 * np.cos(z_b - off), -2.0, 1.0, 299.8])
        A, b = pts - X_hat, np.full(len(pts), z_f - bf_measurement(X_hat)[1])
        g, *_ = np.linalg.lstsq(A, b, rcond=None)
        assert np.linalg.norm(A @ g - b) < 1e-9 * np.linalg.norm(b)
        assert abs(abs(g @ n) - np.linalg.norm(g)) < 1e-9 * np.linalg.norm(g)  # g is along n only
        dist = abs(n @ X_hat)  # X_hat's distance from the measured bearing line
        assert np.linalg.norm(g) == pytest.approx(abs(b[0]) / dist, rel=1e-9)
        norms.append(np.linalg.norm(g))
    assert norms[1] > 5 * norms[0]  # grows without bound as the estimate approaches the line
    # f0 known: the level set on the ray is flat and g has velocity components
    known = pts.copy()
    known[:, 4] = 300.0
    u = np.array([np.sin(z_b), np.cos(z_b)])
    tang = (known[:, 2:4] @ n[:2])
    known[:, 2:4] = C * (1 - z_f / 300.0) * u + tang[:, None] * n[:2]
    X_hat = np.array([7000.0 * np.sin(z_b - 0.02), 7000.0 * np.cos(z_b - 0.02), -2.0, 1.0, 300.0])
    assert least_squares_misfit(known, X_hat, z_f - bf_measurement(X_hat)[1]) < 1e-9


def test_relative_motion_is_exact_for_any_observer_motion():
    """A constant-velocity target seen from a turning observer: x_k+1 = F x_k - u_k exactly."""
    from sonartrack.sim.platforms import ManeuveringTrack

    t = np.arange(0.0, 200.0, 3.7)
    obs = ManeuveringTrack(0.0, 0.0, 3.0, 0.3, ((40.0, 90.0, 0.02),))
    po, vo, _ = obs.state(t)
    pt = np.column_stack([1000 + 4.0 * t, 8000 - 2.0 * t])
    X = np.column_stack([pt - po, np.array([4.0, -2.0]) - vo, np.full(len(t), 300.0)])
    u = observer_inputs(t, po, vo)
    for k in range(len(t) - 1):
        np.testing.assert_allclose(relative_predict_mean(X[k], t[k + 1] - t[k], u[k]), X[k + 1], atol=1e-9)
        np.testing.assert_allclose(relative_transition(t[k + 1] - t[k]) @ X[k] - u[k], X[k + 1], atol=1e-9)


def test_input_from_constant_acceleration():
    a = np.array([0.1, -0.05])
    u = input_from_acceleration(a, 4.0)
    np.testing.assert_allclose(u, [0.8, -0.4, 0.4, -0.2, 0.0])
    Q = relative_process_noise(2.0, 0.5, 1e-3)
    assert Q[0, 0] == pytest.approx(0.5 * 8 / 3) and Q[0, 2] == pytest.approx(1.0) and Q[2, 2] == pytest.approx(1.0)
    assert Q[4, 4] == pytest.approx(2e-3) and np.all(Q[4, :4] == 0)

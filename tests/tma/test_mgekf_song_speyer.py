"""The MGEKF against an independent derivation of Song & Speyer's modified gain for bearings.

Reference: T. L. Song and J. L. Speyer, "A stochastic analysis of a modified gain extended Kalman filter
with applications to estimation with bearings only measurements", IEEE Trans. Automatic Control 30(10),
940-949, 1985 (the modifiability condition and the MGEKF recursion); P. J. Galkowski and M. A. Islam, "An
alternative derivation of the modified gain function of Song and Speyer", IEEE TAC 36(11), 1991.

Derivation (written here from the pseudo-linear form of the bearing equation, without the package's code).
State X = [x, y, vx, vy, f0] relative to the observer, bearing b = atan2(x, y) clockwise from north. Rotate
the position into the frame of the *measured* bearing z::

    across  xi  = x cos z - y sin z          along  eta = x sin z + y cos z

A noise-free bearing puts the target on its line: xi(X) = 0 (the pseudo-linear measurement equation). For
the prediction X^ = r^ [sin b^, cos b^], xi(X^) = -r^ sin(z - b^) and eta(X^) = r^ cos(z - b^), so, xi being
linear in X::

    xi(X) - xi(X^) = r^ sin(z - b^)   =>   H~ (X - X^) = tan(z - b^) = tan(h(X) - h(X^))
    H~ = [cos z, -sin z, 0, 0, 0] / eta(X^) = [cos z, -sin z, 0, 0, 0] / (r^ cos(z - b^))

i.e. the bearing is modifiable in Song & Speyer's sense (in the tangent of the residual). The Jacobian
at the prediction, in polar form, is H = [cos b^, -sin b^, 0, 0, 0] / r^; H~ = H exactly when z = b^.
The MGEKF keeps the EKF's gain and state update and puts H~ into the covariance recursion (Song & Speyer)::

    s = H P- H^T + sigma_b^2,   k = P- H^T / s,   X+ = X- + k wrap(z - b^)
    P+ = (I - k H~) P- (I - k H~)^T + sigma_b^2 k k^T
       = P- - k (H~ P-) - (P- H~^T) k^T + (H~ P- H~^T + sigma_b^2) k k^T      (expanded; computed so here)

With z = b^ this is the EKF's optimal-gain update P+ = P- - P- H^T H P- / s. For the frequency row (not
modifiable, models/passive.py) both filters use the Jacobian, here in the independent polar form
df/dX = -(f0/c) [vx/r - x rdot/r^2, vy/r - y rdot/r^2, x/r, y/r] , df/df0 = 1 - rdot/c.
"""

import numpy as np
import pytest

from sonartrack.filters.ekf import ekf_update
from sonartrack.filters.mgekf import mgekf_update_bf
from sonartrack.models.passive import bearing_modified_row, bf_jacobian, bf_measurement
from sonartrack.models.relative_motion import observer_inputs
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma.imm_mgekf import ImmBfModel, imm_bf_step, run_imm_bf

C = 1500.0


# ---- the independent implementation ---------------------------------------------------------------
def polar(X):
    return float(np.hypot(X[0], X[1])), float(np.arctan2(X[0], X[1]))


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def pseudo_linear_row(z, X):
    """H~ from the rotated frame of the measured bearing: d xi / dX divided by eta(X^)."""
    rot = np.array([[np.cos(z), -np.sin(z)], [np.sin(z), np.cos(z)]])  # rows: xi, eta
    xi_row, eta = rot[0], float(rot[1] @ X[:2])
    r, b = polar(X)
    assert eta == pytest.approx(r * np.cos(z - b), rel=1e-9)
    row = np.zeros(5)
    row[:2] = xi_row / eta
    return row


def polar_jacobian_rows(X, with_freq: bool):
    r, b = polar(X)
    H = [np.array([np.cos(b), -np.sin(b), 0.0, 0.0, 0.0]) / r]
    if with_freq:
        x, y, vx, vy, f0 = X
        rdot = (x * vx + y * vy) / r
        drdot = np.array([vx / r - x * rdot / r**2, vy / r - y * rdot / r**2, x / r, y / r])
        H.append(np.r_[-(f0 / C) * drdot, 1.0 - rdot / C])
    return np.array(H)


def song_speyer_update(X, P, z, sigmas, modified: bool = True):
    """One MGEKF (or, modified=False, EKF) update from the equations of the module docstring."""
    m = len(z)
    H = polar_jacobian_rows(X, m == 2)
    G = H.copy()
    if modified:
        G[0] = pseudo_linear_row(z[0], X)
    r, b = polar(X)
    nu = np.array([wrap(z[0] - b)] + ([z[1] - X[4] * (1 - (X[0] * X[2] + X[1] * X[3]) / r / C)] if m == 2 else []))
    R = np.diag(np.square(sigmas[:m]))
    S = H @ P @ H.T + R
    K = np.linalg.solve(S, H @ P).T  # P H^T S^-1 (S, P symmetric)
    GP = G @ P
    P_new = P - K @ GP - GP.T @ K.T + K @ (GP @ G.T + R) @ K.T
    return X + K @ nu, P_new


def predict(X, P, dt):
    F = np.eye(5)
    F[0, 2] = F[1, 3] = dt
    return F @ X, F @ P @ F.T


def random_case(rng, spread_deg=15.0):
    r, b = rng.uniform(1000.0, 30000.0), rng.uniform(-np.pi, np.pi)
    X = np.array([r * np.sin(b), r * np.cos(b), *rng.normal(0, 5, 2), rng.uniform(100, 500)])
    scale = np.array([rng.uniform(50, 3000)] * 2 + [rng.uniform(0.1, 5)] * 2 + [0.5])
    A = rng.normal(size=(5, 5))
    P = scale[:, None] * (A @ A.T / 5 + 0.05 * np.eye(5)) * scale[None, :]
    z = np.array([wrap(b + np.deg2rad(rng.uniform(-spread_deg, spread_deg))), bf_measurement(X)[1] + rng.normal()])
    return X, P, z


def kernel_update(X, P, z, sigmas, modified=True, dt=0.0):
    """One step of the numba kernel with one mode, q = 0 and no observer input (dt = 0: the update alone)."""
    model = ImmBfModel(np.array([0.0]), None, sigmas[0], sigmas[1], modified=modified)
    out = imm_bf_step(X[None].copy(), P[None].copy(), np.ones(1), np.asarray(z, float), np.zeros(5), dt, model)
    return out[3], out[4]


def rel_diff(a, b):
    return float(np.max(np.abs(a - b)) / max(1.0, np.max(np.abs(b))))


# ---- (a) cases with a known answer ----------------------------------------------------------------
def test_modified_row_is_the_jacobian_on_the_predicted_bearing_and_tan_exact_off_it():
    rng = np.random.default_rng(11)
    for _ in range(50):
        X, _, z = random_case(rng)
        r, b = polar(X)
        np.testing.assert_allclose(pseudo_linear_row(b, X), polar_jacobian_rows(X, False)[0], rtol=1e-12)
        # any state on the measured line: H~ (X_true - X^) = tan(z - b^)
        X_true = X.copy()
        X_true[:2] = rng.uniform(500, 40000) * np.array([np.sin(z[0]), np.cos(z[0])])
        assert pseudo_linear_row(z[0], X) @ (X_true - X) == pytest.approx(np.tan(wrap(z[0] - b)), rel=1e-9, abs=1e-12)
        np.testing.assert_allclose(bearing_modified_row(z[0], X), pseudo_linear_row(z[0], X), rtol=1e-12, atol=1e-18)


def test_hand_worked_two_steps():
    """Target due north at 1000 m, P = diag(100^2, 100^2, 1, 1, 1), sigma_b = 0.1 rad, z1 = 0.1 rad.

    Step 1: H = [1e-3, 0, ...], s = 0.01 + 0.01 = 0.02, k = [500, 0, ...], x+ = [50, 1000, 0, 0, 300];
    H~ = [1, -tan 0.1, 0, 0, 0] / 1000, so I - k H~ has row 0 = [0.5, 0.5 t, 0, 0, 0] (t = tan 0.1) and
    P+_00 = 0.25e4 + 0.25e4 t^2 + 500^2 0.01 = 5000 + 2500 t^2,  P+_01 = 5000 t,  P+_11 = 1e4 (EKF: 5000, 0).
    Step 2: predict 10 s (q = 0), then z2 = the predicted bearing atan2(50, 1000): H~ = H, and both filters
    give the optimal-gain form P- - P- H^T H P- / s on their own P-."""
    sig = (0.1, 1.0)
    X0 = np.array([0.0, 1000.0, 0.0, 0.0, 300.0])
    P0 = np.diag([1e4, 1e4, 1.0, 1.0, 1.0])
    t = np.tan(0.1)
    want_x = np.array([50.0, 1000.0, 0.0, 0.0, 300.0])
    want = {True: np.array([[5000 + 2500 * t**2, 5000 * t], [5000 * t, 1e4]]), False: np.diag([5000.0, 1e4])}
    for modified in (True, False):
        for update in (lambda X, P, z, mod=modified: song_speyer_update(X, P, z, sig, mod),
                       lambda X, P, z, mod=modified: kernel_update(X, P, z, sig, mod),
                       lambda X, P, z, mod=modified: _library_update(X, P, z, sig, mod)):
            x1, P1 = update(X0, P0, np.array([0.1]))
            np.testing.assert_allclose(x1, want_x, rtol=1e-12, atol=1e-9)
            np.testing.assert_allclose(P1[:2, :2], want[modified], rtol=1e-12)
            np.testing.assert_allclose(P1[2:, 2:], np.eye(3), rtol=1e-12)
            xp, Pp = predict(x1, P1, 10.0)
            H = polar_jacobian_rows(xp, False)
            P_known = Pp - np.outer(Pp @ H[0], H[0] @ Pp) / (H[0] @ Pp @ H[0] + 0.01)
            x2, P2 = update(xp, Pp, np.array([np.arctan2(50.0, 1000.0)]))
            np.testing.assert_allclose(x2, xp, atol=1e-9)
            np.testing.assert_allclose(P2, P_known, rtol=1e-10, atol=1e-9)
    assert 5000 * t > 500  # the MGEKF's correlation is far from rounding: the two filters differ


def _library_update(X, P, z, sigmas, modified):
    """filters/mgekf.py (MGEKF) or filters/ekf.py (EKF), bearing row only."""
    hx, H, R = bf_measurement(X)[:1], bf_jacobian(X)[:1], np.diag([sigmas[0] ** 2])
    out = mgekf_update_bf(X, P, z, hx, H, R) if modified else ekf_update(X, P, z, hx, H, R)
    return out[0], out[1]


def test_noise_free_record_started_at_the_truth_mgekf_equals_ekf():
    """Exact bearings of a CV target, estimate started at the truth: every measured bearing equals the
    predicted one, so H~ = H at every step and the MGEKF's covariance history is the EKF's."""
    t = np.arange(0.0, 1200.0, 4.0)
    po, vo, _ = ManeuveringTrack(0.0, 0.0, 2.57, np.deg2rad(45), ((400.0, 440.0, np.deg2rad(-2.25)),)).state(t)
    pt, vt, _ = ManeuveringTrack(-3000.0, 9500.0, 5.14, np.deg2rad(100)).state(t)
    rel = np.column_stack([pt - po, vt - vo, np.full(len(t), 300.0)])
    zb = bf_measurement(rel)[:, 0]
    P0 = np.diag([3000.0**2, 3000.0**2, 9.0, 9.0, 1.0])
    runs = [run_imm_bf(t, zb, None, observer_inputs(t, po, vo), rel[0], P0,
                       ImmBfModel([0.0], None, np.deg2rad(1.0), modified=m)) for m in (True, False)]
    np.testing.assert_allclose(runs[0][0][:, :4], rel[:, :4], atol=1e-6)
    np.testing.assert_allclose(runs[0][1], runs[1][1], rtol=1e-9, atol=1e-9)
    assert runs[0][1][-1, 0, 0] < 0.01 * P0[0, 0]  # the bearings did shrink P: the comparison is not vacuous


# ---- (b) random cases ----------------------------------------------------------------------------------
@pytest.mark.parametrize("with_freq", [False, True])
def test_random_updates_agree_with_the_independent_derivation(with_freq):
    rng = np.random.default_rng(2024 + with_freq)
    sig = (np.deg2rad(rng.uniform(0.3, 3.0)), 0.1)
    worst = {"numpy": 0.0, "kernel": 0.0}
    m = 2 if with_freq else 1
    for _ in range(300):
        X, P, z = random_case(rng)
        z = z[:m]
        x_ref, P_ref = song_speyer_update(X, P, z, sig)
        hx, H, R = bf_measurement(X)[:m], bf_jacobian(X)[:m], np.diag(np.square(sig))[:m, :m]
        x_np, P_np = mgekf_update_bf(X, P, z, hx, H, R)[:2]
        x_k, P_k = kernel_update(X, P, z, sig)
        for name, (xa, Pa) in (("numpy", (x_np, P_np)), ("kernel", (x_k, P_k))):
            worst[name] = max(worst[name], rel_diff(xa, x_ref), rel_diff(Pa, P_ref))
    assert worst["numpy"] < 1e-9 and worst["kernel"] < 1e-9, worst


def test_random_record_agrees_with_the_independent_filter():
    """A noisy bearings-only record with q = 0 and the observer's manoeuvre as input: the kernel's whole
    MGEKF run equals the independent predict/update loop."""
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 1600.0, 4.0)
    po, vo, _ = ManeuveringTrack(0.0, 0.0, 2.57, np.deg2rad(45), ((500.0, 540.0, np.deg2rad(-2.25)),)).state(t)
    pt, vt, _ = ManeuveringTrack(-3000.0, 9500.0, 5.14, np.deg2rad(100)).state(t)
    rel = np.column_stack([pt - po, vt - vo, np.full(len(t), 300.0)])
    sb = np.deg2rad(1.0)
    zb = wrap(bf_measurement(rel)[:, 0] + sb * rng.standard_normal(len(t)))
    u = observer_inputs(t, po, vo)
    X = np.array([8000 * np.sin(zb[0]), 8000 * np.cos(zb[0]), 0.0, 0.0, 300.0])
    P = np.diag([3000.0**2, 3000.0**2, 25.0, 25.0, 1.0])
    x_k, P_k, _, failed = run_imm_bf(t, zb, None, u, X, P, ImmBfModel([0.0], None, sb, modified=True))
    assert failed == -1
    worst = 0.0
    for k in range(1, len(t)):
        X, P = predict(X, P, t[k] - t[k - 1])
        X, P = song_speyer_update(X - u[k - 1], P, zb[k:k + 1], (sb, 0.1))
        worst = max(worst, rel_diff(x_k[k], X), rel_diff(P_k[k], P))
    assert worst < 1e-7, worst

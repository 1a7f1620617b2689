"""EM/MAP's reuse of work (per-problem constants, the last E-step, the grid search's geometry across SNR models)
gives the numbers of the plain formulas bit for bit."""

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.tma import em_map
from sonartrack.tma.batch_ml import bearing_model
from sonartrack.tma.em_map import em_step, make_problem, objective, solve_em_map
from sonartrack.tma.em_map_start import direct_log_likelihood


def snr_model(shift_db=0.0):
    return lambda r: 100.0 - 20.0 * np.log10(r) + 3.0 * np.sin(r / 700.0) + shift_db


def problem(shift_db=0.0, seed=3):
    t = np.arange(60) * 10.0
    po, _, _ = ManeuveringTrack(0.0, 0.0, 3.0, np.deg2rad(90.0), ((250.0, 280.0, np.deg2rad(-3.0)),)).state(t)
    x0 = np.array([3000.0, -7000.0, -2.0, 1.0])
    h, _, r = bearing_model(x0, t, po)
    rng = np.random.default_rng(seed)
    z = h + rng.normal(0, np.deg2rad(0.5), len(t))
    xi = snr_model()(r) + rng.normal(0, 1.0, len(t))
    return make_problem(z, xi, t, po, np.deg2rad(0.5), 1.0, snr_model(shift_db), 1_000.0, 40_000.0), x0


def plain_em_step(prob, x0):
    """em_step written out with nothing precomputed or kept (the formulas of tma/em_map.py's module doc)."""
    P = np.column_stack([x0[0] + x0[2] * prob.tau_s, x0[1] + x0[3] * prob.tau_s])
    d = P - prob.own_xy
    s, c = np.sin(prob.theta_rad), np.cos(prob.theta_rad)
    cross, along = d[:, 0] * c - d[:, 1] * s, d[:, 0] * s + d[:, 1] * c
    n, nr = prob.log_snr_lik.shape
    centre = along + (cross * prob.kappa / prob.sigma_rad) ** 2 / along
    w = min(int(np.ceil(em_map.WINDOW_KAPPAS * prob.kappa / np.log(prob.r_grid[1] / prob.r_grid[0]))), (nr - 1) // 2)
    start = np.clip(np.searchsorted(prob.r_grid, np.maximum(centre, prob.r_grid[0])) - w, 0, nr - (2 * w + 1))
    J = start[:, None] + np.arange(2 * w + 1)[None, :]
    r = prob.r_grid[J]
    m = (cross[:, None] ** 2 / prob.sigma_rad[:, None] ** 2 + (along[:, None] - r) ** 2 / prob.kappa**2) / r**2
    lp = np.take_along_axis(prob.log_snr_lik, J, axis=1) - np.log(2 * np.pi * prob.sigma_rad[:, None] * prob.kappa) \
        - 0.5 * m
    mx = lp.max(axis=1, keepdims=True)
    wt = np.exp(lp - mx)
    tot = wt.sum(axis=1)
    q = wt / tot[:, None]
    e2, e1 = np.sum(q / r**2, axis=1), np.sum(q / r, axis=1)
    a, b = 1.0 / prob.sigma_rad**2, 1.0 / prob.kappa**2
    Si = np.empty((n, 2, 2))
    Si[:, 0, 0], Si[:, 1, 1] = a * c * c + b * s * s, a * s * s + b * c * c
    Si[:, 0, 1] = Si[:, 1, 0] = -a * c * s + b * s * c
    Fp = np.zeros((n, 2, 4))
    Fp[:, 0, 0] = Fp[:, 1, 1] = 1.0
    Fp[:, 0, 2] = Fp[:, 1, 3] = prob.tau_s
    FtS = np.swapaxes(Fp, 1, 2) @ Si
    A = np.einsum("nij,njk,n->ik", FtS, Fp, e2)
    bb = np.einsum("nij,nj->i", FtS, prob.own_xy * e2[:, None] + np.column_stack([s, c]) * e1[:, None])
    return np.linalg.solve(A, bb), float(np.sum(mx[:, 0] + np.log(tot)))


def plain_direct_log_likelihood(prob, x0s):
    dx = x0s[:, None, 0] + x0s[:, None, 2] * prob.tau_s - prob.own_xy[:, 0]
    dy = x0s[:, None, 1] + x0s[:, None, 3] * prob.tau_s - prob.own_xy[:, 1]
    rng = np.hypot(dx, dy)
    e_b = wrap_angle(prob.theta_rad - np.arctan2(dx, dy)) / prob.sigma_rad
    lr = np.log(prob.r_grid)
    j = np.clip(np.searchsorted(lr, np.log(np.maximum(rng, 1e-9))), 0, len(lr) - 1)
    ll = np.take_along_axis(np.broadcast_to(prob.log_snr_lik, (len(x0s), *prob.log_snr_lik.shape)), j[..., None],
                            axis=2)[..., 0]
    out = -0.5 * np.sum(e_b**2, axis=1) + ll.sum(axis=1)
    return np.where(((rng < prob.r_grid[0]) | (rng > prob.r_grid[-1])).any(axis=1), -np.inf, out)


def test_em_step_and_objective_equal_the_plain_formulas_in_any_call_order():
    prob, x0 = problem()
    xs = [x0 + np.array([400.0, -300.0, 0.3, -0.2]), x0, x0 + np.array([-900.0, 500.0, -0.5, 0.4])]
    for x in xs + xs[::-1]:  # each x both fresh and right after itself (served again)
        want_x, want_L = plain_em_step(prob, x)
        assert objective(prob, x) == want_L
        got_x, got_L = em_step(prob, x)
        np.testing.assert_array_equal(got_x, want_x)
        assert got_L == want_L
        got_x, got_L = em_step(prob, x)
        np.testing.assert_array_equal(got_x, want_x)


def test_grid_scores_equal_the_plain_formula_when_a_second_snr_model_shares_the_geometry():
    a, x0 = problem(0.0)
    b, _ = problem(-6.0)  # same bearings, ownship and grid; SNR model 6 dB lower
    rng = np.random.default_rng(0)
    cands = x0 + rng.normal(0, 1, (300, 4)) * np.array([3000.0, 3000.0, 3.0, 3.0])
    for prob in (a, b, a):
        np.testing.assert_array_equal(direct_log_likelihood(prob, cands), plain_direct_log_likelihood(prob, cands))
    assert not np.array_equal(direct_log_likelihood(a, cands), direct_log_likelihood(b, cands))


def test_a_solve_does_not_depend_on_what_was_solved_before():
    fresh = solve_em_map(problem(-3.0, seed=5)[0], covariance=False).x0
    solve_em_map(problem(0.0, seed=5)[0], covariance=False)  # same geometry: the grid search's is kept
    after_same = solve_em_map(problem(-3.0, seed=5)[0], covariance=False).x0
    solve_em_map(problem(0.0, seed=6)[0], covariance=False)  # other bearings
    after_other = solve_em_map(problem(-3.0, seed=5)[0], covariance=False).x0
    np.testing.assert_array_equal(after_same, fresh)
    np.testing.assert_array_equal(after_other, fresh)

"""Why the IMM range bank's NEES sits below its chi-square interval on straight legs (issue 30 item 4), as tests.

NEES averaged over N runs (ANEES) lies in chi2(4 N) / N's interval when the truths are drawn from the filter's own
model (Bar-Shalom, Li & Kirubarajan 2001, sec. 5.4.2). Here the bank of tma/range_bank.py runs on truths drawn from
its own prior and motion model (a small numpy generator written here from the kinematics, not the project's
simulator: range log-uniform over the bank's interval, velocity from the initial estimate's prior, then the IMM's
Markov chain of white-acceleration modes):

* a bank of constant-velocity MGEKFs on constant-velocity targets is consistent: the mixture's spread between range
  filters, the MGEKF's modified covariance rows, the frame and time of the comparison and the range prior are not
  what makes the IMM bank conservative (given 1.5x the simulated bearing sd its ANEES falls to 1.5-2.2: the test
  can fail);
* the paper's IMM (tma/settings.py ImmSettings) per range filter is consistent on targets that switch between its
  modes as its Markov matrix says;
* the same runs looked at only where the target has been in the quietest mode for QUIET_S give a mean NEES of
  1.1-1.4, the 1.15-1.19 measured on the straight legs before a turn. The IMM's model says that the target may be
  manoeuvring at any time (bearings-only, its modes keep probabilities ~0.55 / 0.38 / 0.08 on a straight leg:
  a bearing barely tells q = 1e-5 from 1e-3) and the combined covariance carries that; evaluated only where the
  target did not manoeuvre, a consistent IMM is conservative. Not a bug; it goes only with the manoeuvre modes.

On a deterministic turn (tests/tma/test_imm_respond.py's numpy scene) no IMM setting found has its ANEES inside the
interval before, during and after (issue 30 item 4; the grid of benchmarks/range_bank_nees.py --grid): the last test
shows the trade-off the grid's frontier follows. Making the quiet mode stickier (the straight legs' mixture keeps
less of the manoeuvre mode) moves the straight legs toward the interval and the turn above it; only the
constant-velocity bank is inside on the straight legs, and it is overconfident by 10^4 during the turn.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from sonartrack.models.relative_motion import observer_inputs
from sonartrack.tma.imm_mgekf import ImmBfModel, transition_matrix
from sonartrack.tma.range_bank import range_subintervals, run_range_bank
from sonartrack.tma.sequential_bf import initial_estimate
from sonartrack.tma.settings import ImmSettings

from .test_imm_respond import T_TURN_S, _paths

DT_S, DURATION_S, SIGMA_B = 10.0, 3600.0, np.deg2rad(1.0)
BANK_RANGE_M, N_FILTERS, SIGMA_V = (2_000.0, 40_000.0), 8, 3.0
N_RUNS, MIN_RANGE_M, QUIET_S = 16, 1_000.0, 600.0
WINDOW_S = (1200.0, DURATION_S + 1.0)  # after the ownship's first turns (900 s): range observed


def _ownship(rng):
    """Ownship [x, y, vx, vy] every DT_S: 5 m/s on 600 s legs alternating +-50 deg about a random course."""
    t = np.arange(0.0, DURATION_S + 1e-9, DT_S)
    course = np.deg2rad(rng.uniform(0, 360) + np.where((t // 600) % 2 == 0, 50.0, -50.0))
    v = 5.0 * np.stack([np.sin(course), np.cos(course)], -1)
    p = np.concatenate([[[0.0, 0.0]], np.cumsum(v[:-1] * DT_S, axis=0)])  # velocity held over each step
    return t, np.c_[p, v]


def _markov_truth(qs, Pi):
    """A truth drawn from an IMM's own model, relative to the ownship: range log-uniform over BANK_RANGE_M at a random
    bearing, velocity N(0, SIGMA_V^2 I) (the bank's prior, tma/range_bank.py), then a Markov chain of modes (Pi per
    measurement, started from its stationary law) whose mode j drives the target with white acceleration of
    intensity qs[j], sampled exactly over each step: per axis [dp, dv] ~ N(0, q [[T^3/3, T^2/2], [T^2/2, T]]).
    Redrawn while it passes within MIN_RANGE_M (there the bearing's linearisation, every EKF's small-error model,
    fails: not a question of consistency). Returns ``truth(rng, t, own) -> (relative [x, y, vx, vy], mode)``."""
    qs, Pi = np.asarray(qs, float), np.asarray(Pi, float)
    stationary = np.linalg.matrix_power(Pi, 1000)[0]

    def truth(rng, t, own):
        dt = np.diff(t)[0]
        unit = np.linalg.cholesky(np.array([[dt**3 / 3.0, dt**2 / 2.0], [dt**2 / 2.0, dt]]))
        while True:
            mode = [rng.choice(len(qs), p=stationary)]
            for _ in range(1, len(t)):
                mode.append(rng.choice(len(qs), p=Pi[mode[-1]]))
            mode = np.array(mode)
            b0 = rng.uniform(0, 2 * np.pi)
            state = [np.r_[np.exp(rng.uniform(*np.log(BANK_RANGE_M))) * np.array([np.sin(b0), np.cos(b0)]),
                           SIGMA_V * rng.standard_normal(2)]]
            for k in range(1, len(t)):  # [x, y, vx, vy]: noise (2 (pos, vel), 2 axes) -> [dx, dy, dvx, dvy]
                w = np.sqrt(qs[mode[k]]) * unit @ rng.standard_normal((2, 2))
                state.append(state[-1] + np.r_[dt * state[-1][2:], 0.0, 0.0] + w.ravel())
            rel = np.array(state) - own
            if np.min(np.hypot(rel[:, 0], rel[:, 1])) >= MIN_RANGE_M:
                return rel, mode

    return truth


def _run_bank(rng, model: ImmBfModel, truth) -> tuple[np.ndarray, np.ndarray]:
    """One run: ``truth(rng, t, own)`` gives the relative track and the true mode per time; returns the bank's 4-state
    NEES and the true modes per time."""
    t, own = _ownship(rng)
    rel, modes = truth(rng, t, own)
    zb = np.arctan2(rel[:, 0], rel[:, 1]) + SIGMA_B * rng.standard_normal(len(t))
    ranges, sds = range_subintervals(*BANK_RANGE_M, N_FILTERS)
    starts = [initial_estimate(float(zb[0]), None, own[0, 2:], range_m=r, sigma_range_m=s, sigma_bearing_rad=SIGMA_B,
                               sigma_target_velocity_mps=SIGMA_V) for r, s in zip(ranges, sds, strict=True)]
    u = observer_inputs(t, own[:, :2], own[:, 2:])
    x, P, _, _, failed = run_range_bank(t, np.c_[zb, np.full(len(t), np.nan)], u, np.array([a for a, _ in starts]),
                                        np.array([b for _, b in starts]), model)
    assert failed < 0
    e = rel - x[:, :4]
    return np.einsum("ni,ni->n", e, np.linalg.solve(P[:, :4, :4], e[..., None])[..., 0]), modes


def _monte_carlo(model: ImmBfModel, truth, seed: int = 5) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times, NEES (N_RUNS, n) and true modes (N_RUNS, n) of the bank running ``model`` on N_RUNS truths."""
    rng = np.random.default_rng(seed)
    runs = [_run_bank(rng, model, truth) for _ in range(N_RUNS)]
    return _ownship(rng)[0], np.array([r[0] for r in runs]), np.array([r[1] for r in runs])


def _interval(level: float = 0.99) -> tuple[float, float]:
    """chi2(4 N) / N's two-sided interval: where the ANEES of a consistent filter lies."""
    a = (1.0 - level) / 2.0
    return chi2.ppf(a, 4 * N_RUNS) / N_RUNS, chi2.ppf(1.0 - a, 4 * N_RUNS) / N_RUNS


@pytest.fixture(scope="module")
def imm():
    return ImmSettings()


def _paper_model(imm: ImmSettings) -> ImmBfModel:
    return ImmBfModel(qs=np.asarray(imm.q_values), Pi=transition_matrix(len(imm.q_values), imm.transition_diagonal),
                      sigma_bearing_rad=SIGMA_B, q_f0=imm.q_f0)


@pytest.fixture(scope="module")
def paper_imm_runs(imm):
    """The paper's IMM per range filter on N_RUNS targets drawn from that IMM's own model."""
    model = _paper_model(imm)
    return _monte_carlo(model, _markov_truth(model.qs, model.Pi))


def test_bank_of_constant_velocity_mgekfs_is_consistent_on_its_own_model(imm):
    """One constant-velocity mode (q ~ 0) per range filter on constant-velocity targets: ANEES inside the interval
    (measured, seeds 5-9: 3.3-4.5 against [2.41, 6.05])."""
    t, nees, _ = _monte_carlo(ImmBfModel(qs=np.array([1e-9]), Pi=None, sigma_bearing_rad=SIGMA_B, q_f0=imm.q_f0),
                              _markov_truth([0.0], [[1.0]]))
    window = (t >= WINDOW_S[0]) & (t < WINDOW_S[1])
    lo, hi = _interval()
    assert lo <= np.median(nees.mean(axis=0)[window]) <= hi


def test_paper_imm_bank_is_consistent_on_its_own_model(paper_imm_runs):
    """The paper's three modes per range filter, on targets that switch between those modes as its Markov matrix
    says: ANEES inside the interval (measured, seeds 5-9: 2.6-5.0)."""
    t, nees, _ = paper_imm_runs
    window = (t >= WINDOW_S[0]) & (t < WINDOW_S[1])
    lo, hi = _interval()
    assert lo <= np.median(nees.mean(axis=0)[window]) <= hi


def test_paper_imm_bank_is_conservative_where_the_target_has_been_quiet(paper_imm_runs):
    """The same runs, only the times at which the target has been in the quietest mode for QUIET_S: mean NEES far
    below 4 (measured, seeds 5-9: 1.1-1.35), as on the straight legs before a turn (1.15-1.19): a consistent IMM
    looked at only where the target did not manoeuvre is conservative (module doc)."""
    t, nees, modes = paper_imm_runs
    steps = int(QUIET_S / (t[1] - t[0]))
    quiet = np.array([[np.all(m[max(0, k - steps):k + 1] == 0) for k in range(len(t))] for m in modes])
    quiet &= (t >= WINDOW_S[0])[None]
    assert quiet.sum() >= 100
    assert np.mean(nees[quiet]) < _interval()[0] / 1.5


def _turn_anees(model: ImmBfModel, mu0, n_runs: int = N_RUNS, turn_deg: float = 60.0, seed: int = 3):
    """Median ANEES of the bank before (1200 s to the turn) and during (the 360 s from it) a ``turn_deg`` turn of
    test_imm_respond's scene (numpy kinematics, bearings every DT_S), over the runs never within MIN_RANGE_M."""
    rng = np.random.default_rng(seed)
    t1, own, tgt = _paths(rng, n_runs, turn_deg)
    t = np.arange(0.0, t1[-1] + 1e-9, DT_S)
    k = np.searchsorted(t1, t)
    ranges, sds = range_subintervals(*BANK_RANGE_M, N_FILTERS)
    nees = []
    for i in range(n_runs):
        o, rel = own[i, k], tgt[i, k] - own[i, k]
        zb = np.arctan2(rel[:, 0], rel[:, 1]) + SIGMA_B * rng.standard_normal(len(t))
        if np.min(np.hypot(rel[:, 0], rel[:, 1])) < MIN_RANGE_M:
            continue
        starts = [initial_estimate(float(zb[0]), None, o[0, 2:], range_m=r, sigma_range_m=s, sigma_bearing_rad=SIGMA_B,
                                   sigma_target_velocity_mps=5.0) for r, s in zip(ranges, sds, strict=True)]
        x, P, _, _, failed = run_range_bank(t, np.c_[zb, np.full(len(t), np.nan)],
                                            observer_inputs(t, o[:, :2], o[:, 2:]), np.array([a for a, _ in starts]),
                                            np.array([b for _, b in starts]), model, mu0=mu0)
        assert failed < 0
        e = rel - x[:, :4]
        nees.append(np.einsum("ni,ni->n", e, np.linalg.solve(P[:, :4, :4], e[..., None])[..., 0]))
    anees = np.mean(nees, axis=0)
    before, during = (t >= WINDOW_S[0]) & (t < T_TURN_S), (t >= T_TURN_S) & (t < T_TURN_S + 360.0)
    return float(np.median(anees[before])), float(np.median(anees[during])), len(nees)


def test_straight_leg_consistency_is_bought_with_the_turns():
    """Three settings on the same 60 deg turns: a constant-velocity bank (q 1e-9), and two-mode IMMs (q 1e-9 and 0.1)
    whose quiet mode is kept with probability 0.9999 (sticky) or 0.99 (loose) per bearing (manoeuvre mode 0.95 /
    0.9; started from the Markov chain's stationary law). Median ANEES before / during, seeds 3-5 (14-16 runs): CV
    2.8-3.2 / 1.6-4.9 x 10^5, sticky 1.4-1.8 / 30-40, loose 1.3-1.8 / 2.5-3.6 (benchmarks/range_bank_nees.py --grid,
    20 runs: 3.3 / ~10^5, 1.75 / 57, 1.44 / 3.6): the IMMs are conservative on the straight leg whatever the
    switching, the stickier one overconfident in the turn, and the only bank inside the interval on the straight leg
    is overconfident by 10^4-10^5 in the turn (issue 30 item 4 not met: module doc)."""
    def two_mode(stay_quiet, stay_manoeuvre):
        Pi = np.array([[stay_quiet, 1.0 - stay_quiet], [1.0 - stay_manoeuvre, stay_manoeuvre]])
        return ImmBfModel(qs=np.array([1e-9, 0.1]), Pi=Pi, sigma_bearing_rad=SIGMA_B), \
            np.linalg.matrix_power(Pi, 1 << 20)[0]

    cv_before, cv_during, n = _turn_anees(ImmBfModel(qs=np.array([1e-9]), Pi=None, sigma_bearing_rad=SIGMA_B), None)
    sticky_before, sticky_during, _ = _turn_anees(*two_mode(0.9999, 0.95))
    loose_before, loose_during, _ = _turn_anees(*two_mode(0.99, 0.9))
    a = 0.005  # the 99 % interval for the n runs averaged
    lo, hi = chi2.ppf(a, 4 * n) / n, chi2.ppf(1.0 - a, 4 * n) / n
    assert n >= N_RUNS - 2
    assert lo <= cv_before <= hi and cv_during > 100 * hi
    assert loose_before < lo and loose_during <= hi
    assert sticky_before < lo and hi < sticky_during < cv_during / 100

"""The passive chain's bearings + frequency ML of a target found through its line (systems/passive/targets.py
:func:`frequency_ml`): on one straight leg the bearings alone leave the range open, the tonal's Doppler closes it;
a target on a constant bearing stays undetermined; the gates of the line."""

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from sonartrack.acoustics.tonal import TonalTrack
from sonartrack.systems.passive.targets import frequency_ml, line_tonal

sys.path.insert(0, str(Path(__file__).parent))
from test_checks import _ml  # noqa: E402

C = 1500.0
F0 = 200.0
STAGES = SimpleNamespace(settings=SimpleNamespace(sigma_freq_floor_hz=0.02, ml_correlation_inflation=True,
                                                  max_sigma_freq_hz=0.4, tma_min_tonal_snr_db=4.0),
                         min_separation_deg=3.0,
                         sequential=SimpleNamespace(sound_speed_mps=C))


def _scene(x0, v, seed, sigma_deg=1.0, sigma_hz=0.1):
    """One straight leg north at 3 m/s; bearings and received frequencies of a CV target (the range rate by central
    differences of the range, independent of the code's analytic one)."""
    t = np.arange(0.0, 1200.0, 10.0)
    own = np.column_stack([np.zeros_like(t), 3.0 * t])

    def rng_at(tt):
        return np.hypot(x0[0] + v[0] * tt, x0[1] + (v[1] - 3.0) * tt)

    rdot = (rng_at(t + 1e-3) - rng_at(t - 1e-3)) / 2e-3
    g = np.random.default_rng(seed)
    z = np.arctan2(x0[0] + v[0] * t - own[:, 0], x0[1] + v[1] * t - own[:, 1])
    z = z + np.deg2rad(sigma_deg) * g.standard_normal(t.size)
    f = F0 * (1.0 - rdot / C) + sigma_hz * g.standard_normal(t.size)
    tonal = TonalTrack(line_hz=F0, line_snr_db=3.0, time_s=t, frequency_hz=f, sigma_hz=sigma_hz)
    return t, own, z, tonal


@pytest.mark.parametrize("seed", range(4))
def test_the_doppler_determines_the_range_the_bearings_leave_open(seed):
    x0, v = np.array([3000.0, 4000.0]), np.array([1.5, -1.0])
    t, own, z, tonal = _scene(x0, v, seed)
    bo = _ml(t, z, own, 1.0)
    assert not bo.solution.range_flags()[-1]  # one straight leg: bearings alone, range unobservable
    bf = frequency_ml(bo, t, z, tonal, STAGES)
    assert bf.settings.frequency and bf.settings.method == "ml"
    assert bf.solution.range_flags().all()
    end = x0 + v * t[-1]
    e = bf.solution.state[-1, :2] - end
    assert float(e @ np.linalg.solve(bf.solution.covariance[-1, :2, :2], e)) < 13.82  # chi-square(2) 99.9 %
    assert abs(bf.f0_hz - F0) < 4 * bf.f0_std_hz


def test_a_target_on_a_constant_bearing_stays_undetermined():
    # closing dead ahead: the range rate is constant, the frequency line has no slope to give the scale
    x0, v = np.array([0.0, 6000.0]), np.array([0.0, 1.0])
    t, own, z, tonal = _scene(x0, v, 0)
    bf = frequency_ml(_ml(t, z, own, 1.0), t, z, tonal, STAGES)
    assert not bf.solution.range_flags()[-1]


def test_too_few_frequencies_leave_the_bearings_only_ml():
    x0, v = np.array([3000.0, 4000.0]), np.array([1.5, -1.0])
    t, own, z, tonal = _scene(x0, v, 0)
    few = TonalTrack(line_hz=F0, line_snr_db=3.0, time_s=t[:9], frequency_hz=tonal.frequency_hz[:9], sigma_hz=0.1)
    bo = _ml(t, z, own, 1.0)
    assert frequency_ml(bo, t, z, few, STAGES) is bo


def test_a_weak_line_is_used_but_a_noisy_one_is_not():
    weak = TonalTrack(line_hz=F0, line_snr_db=3.0, time_s=np.zeros(1), frequency_hz=np.zeros(1), sigma_hz=0.25)
    noisy = TonalTrack(line_hz=F0, line_snr_db=20.0, time_s=np.zeros(1), frequency_hz=np.zeros(1), sigma_hz=0.5)
    assert line_tonal(weak, STAGES) is weak
    assert line_tonal(noisy, STAGES) is None
    assert line_tonal(None, STAGES) is None


def test_a_covariance_that_is_not_positive_definite_is_a_diverged_answer(monkeypatch):
    """A fit whose information matrix is singular (a negative eigenvalue in its covariance) says "diverged" and
    gives no range, where the same fit with its own covariance is determined."""
    import dataclasses

    from sonartrack.systems.passive import targets as tg
    from sonartrack.tma.verdict import DIVERGED

    x0, v = np.array([3000.0, 4000.0]), np.array([1.5, -1.0])
    t, own, z, tonal = _scene(x0, v, 0)
    bo = _ml(t, z, own, 1.0)
    real = tg._bf_fit

    def broken(*args):
        est = real(*args)
        cov = est.covariance.copy()
        cov[4, 4] = -abs(cov[4, 4])
        return dataclasses.replace(est, covariance=cov)

    assert frequency_ml(bo, t, z, tonal, STAGES).solution.range_flags().all()
    monkeypatch.setattr(tg, "_bf_fit", broken)
    bf = frequency_ml(bo, t, z, tonal, STAGES)
    assert not bf.solution.range_flags().any() and set(bf.solution.reasons()) == {DIVERGED}
    assert np.isnan(bf.f0_std_hz)

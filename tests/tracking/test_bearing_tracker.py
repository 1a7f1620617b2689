"""Bearing tracker (paper P0): JPDA_A with non-discriminating amplitudes is JPDA; tracking and initiation."""

import numpy as np

import sonartrack.tracking.measurements as measurements
from sonartrack.association.amplitude import detection_probability_above
from sonartrack.sim.bearing_peaks import STRONG, WEAK, PeakModel, generate_scans
from sonartrack.studies.jpda_amplitude import Config, run_tracker
from sonartrack.tracking.configurations import bearing_tracker
from sonartrack.tracking.settings import BearingTrackerSettings


def test_jpda_a_with_equal_amplitude_densities_is_jpda(monkeypatch):
    cfg = Config()
    truth = cfg.geometries()[0][2]
    scans = generate_scans(np.random.default_rng(3), cfg.model(), truth, [STRONG, WEAK])
    plain = run_tracker(cfg.tracker, scans, truth, [STRONG, WEAK], amplitude_aided=False)

    def equal_density_ratio(amplitudes, strength, sigma_a, alpha, threshold):
        # true density above the threshold equal to the false one: r_tj = P_D,t / P_D0 (module doc of amplitude.py)
        pd = detection_probability_above(1.0, strength, sigma_a, threshold)
        return np.broadcast_to(np.log(pd)[:, None], (len(strength), len(amplitudes)))

    monkeypatch.setattr(measurements, "amplitude_log_ratio", equal_density_ratio)
    amp = run_tracker(cfg.tracker, scans, truth, [STRONG, WEAK], amplitude_aided=True)
    np.testing.assert_allclose(amp, plain, atol=1e-9)


def test_single_track_without_clutter_follows_the_truth():
    cfg = Config()
    t = np.arange(100.0)
    truth = (50 + 0.2 * t)[:, None]
    scans = generate_scans(np.random.default_rng(0), PeakModel(false_rate=0.0), truth, [STRONG])
    est = run_tracker(cfg.tracker, scans, truth, [STRONG], amplitude_aided=True)
    assert np.sqrt(np.mean((est[20:, 0] - truth[20:, 0]) ** 2)) < STRONG.sigma_p_deg  # filtering beats one peak


def test_automatic_initiation_confirms_persistent_peaks_and_drops_clutter():
    rng = np.random.default_rng(1)
    t = np.arange(60.0)
    truth = np.column_stack([40 + 0.3 * t, 140 - 0.2 * t])
    scans = generate_scans(rng, PeakModel(), truth, [STRONG, STRONG])
    trk = bearing_tracker(BearingTrackerSettings(), amplitude_aided=True, adaptive_strength=True)
    for k, s in enumerate(scans):
        snap = trk.step(float(k), s.bearing_deg, amplitude=s.amplitude)
    conf = snap.x[snap.confirmed, 0]
    assert len(conf) >= 2
    for b in truth[-1]:
        assert np.min(np.abs(conf - b)) < 3.0
    assert snap.confirmed.sum() <= 4  # clutter rarely survives M-of-N confirmation

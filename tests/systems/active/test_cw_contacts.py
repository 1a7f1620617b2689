"""A CW ping's contacts (systems/active/cw_tracking.py): the errors they state, the MFTD detections measured by the
ping's own echo peak, and the contacts of peaked and unpeaked detections; hand-worked cases."""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.detection.cells import Detections
from sonartrack.systems.active.contacts import ActiveGeometry, ContactSettings, form_contacts
from sonartrack.systems.active.cw_tracking import (
    cw_contact_errors,
    cw_form_contacts,
    cw_merge_echoes,
    cw_peaked,
    cw_unpeaked_errors,
)
from sonartrack.systems.active.settings import ActiveSettings


def _det(beam, delay_cell, doppler_cell, statistic, cone=None, tt=None, rate=None):
    n = len(beam)
    b, d, j = (np.asarray(x, np.int64) for x in (beam, delay_cell, doppler_cell))
    cone = 3.0 * b if cone is None else np.asarray(cone, float)
    tt = 0.25 * d if tt is None else np.asarray(tt, float)
    rate = 0.5 * j - 10.0 if rate is None else np.asarray(rate, float)
    return Detections(np.zeros(n, np.int64), np.zeros(n), cone, tt, -rate, rate, np.asarray(statistic, float), b, d, j)


@pytest.mark.parametrize("step, detector, setting, want", [
    (0.25, "mftd", 0.01, 1.0 / np.sqrt(12.0)),  # tau = 0.25 / 0.25 = 1 s: tau / sqrt(12) beats the pair's 0.144 s
    (0.05, "single", 0.01, 0.2 / np.sqrt(12.0)),  # a 0.2 s pulse: 0.058 s, against one cell's 0.014 s
    (0.25, "mftd", 0.5, 0.5),  # a larger setting is kept
])
def test_cw_travel_time_error_is_at_least_the_pulse_over_root_12(step, detector, setting, want):
    s = ActiveSettings(spacing_m=0.5, elements=16, detector=detector)
    s = s.model_copy(update={"contacts": s.contacts.model_copy(update={"sigma_time_s": setting})})
    got = cw_contact_errors(s, 1.5 + step * np.arange(100)).sigma_time_s
    assert got == pytest.approx(want, rel=1e-9)


def test_an_mftd_detection_takes_the_strongest_peak_of_its_block_and_only_there():
    mftd = _det([10, 40], [40, 80], [20, 20], [50.0, 60.0])
    single = _det([11, 10, 30, 40], [42, 40, 40, 86], [21, 20, 20, 20], [30.0, 20.0, 99.0, 70.0],
                  cone=[33.3, 30.1, 90.0, 120.0], tt=[10.6, 10.0, 10.0, 21.5], rate=[0.4, 0.1, 0.0, 3.0])
    got, peaked = cw_peaked(mftd, single, beams=2, delay_cells=4, doppler_cells=2)
    assert peaked.tolist() == [True, False]  # beam 30 is outside the first's block, delay 86 outside the second's
    assert (got.cone_deg[0], got.travel_time_s[0], got.range_rate_mps[0], got.beam[0]) == (33.3, 10.6, 0.4, 11)
    assert got.statistic.tolist() == [50.0, 60.0]  # the MFTD's statistic is kept
    assert (got.cone_deg[1], got.travel_time_s[1], got.delay_cell[1]) == (120.0, 20.0, 80)  # unchanged


def test_no_single_peak_leaves_the_detections():
    mftd = _det([10], [40], [20], [50.0])
    got, peaked = cw_peaked(mftd, _det([], [], [], []), 2, 4, 2)
    assert not peaked.any() and got is mftd


def test_unpeaked_errors_are_the_filter_base_and_the_main_lobe_over_root_12():
    # 16 elements half a wavelength apart (0.5 m at 1500 Hz): nulls at u = +-2 / 16, width 0.25 in u
    got = cw_unpeaked_errors(ContactSettings(sigma_time_s=0.1), 1.0, 16, 0.5, 1500.0, 1500.0)
    assert got.sigma_time_s == pytest.approx(2.0 / np.sqrt(12.0))
    assert got.sigma_cone_deg == pytest.approx(np.rad2deg(np.arcsin(0.25 / np.sqrt(12.0))))
    wide = cw_unpeaked_errors(ContactSettings(sigma_time_s=0.1), 1.0, 256, 0.5, 1500.0, 1500.0)
    assert wide.sigma_cone_deg == pytest.approx(0.5)  # 256 elements: 0.26 deg, under the 0.5 deg floor


def _geometry():
    t = np.array([-10.0, 10.0])
    return ActiveGeometry(t, np.array([[0.0, -300.0], [0.0, -300.0]]), np.array([[0.0, -450.0], [0.0, -450.0]]),
                          np.zeros(2))


def test_contacts_of_peaked_and_unpeaked_detections():
    det = _det([10, 20, 30], [40, 40, 40], [20, 20, 20], [30.0, 30.0, 30.0], cone=[60.0, 90.0, 60.0],
               tt=[10.0, 10.0, 10.0])
    peaked = np.array([True, False, False])
    tight, loose = ContactSettings(sigma_time_s=0.1), ContactSettings(sigma_time_s=0.5, sigma_cone_deg=4.0)
    got = cw_form_contacts(det, peaked, [0.0], _geometry(), 1500.0, tight, loose, 3.0, [0])
    assert got.detection.tolist() == [0, 0, 1, 1, 2, 2] and got.side.tolist() == [1, -1] * 3
    alone = form_contacts(det, [0.0], _geometry(), 1500.0, tight, 3.0, [0])
    np.testing.assert_allclose(got.xy, alone.xy)  # the positions do not depend on the errors
    np.testing.assert_allclose(got.R[:2], alone.R[:2])  # the peaked one: the tight errors
    # the unpeaked twin of detection 0 (same cone, delay): its covariance is the loose one's, larger in every direction
    loose_R = form_contacts(det, [0.0], _geometry(), 1500.0, loose, 3.0, [0]).R
    np.testing.assert_allclose(got.R[4:], loose_R[4:])
    assert np.all(np.linalg.eigvalsh(got.R[4] - got.R[0]) > 0)


def test_one_detection_per_echo_the_strongest_or_the_preferred_group():
    cones = np.arange(0.0, 181.0, 3.0)  # beam 30 at broadside: u = cos(cone) steps 0.052 there
    # beams 30 and 32 (u 0 and -0.105): one lobe (0.125 each side); beam 36 (u -0.309): not; delay 4 cells: one echo,
    # 5: not; Doppler 3 filters: one, 4: not
    det = _det([30, 32, 36, 30, 30, 30], [40, 40, 40, 44, 40, 45], [20, 20, 20, 20, 23, 24],
               [20.0, 50.0, 10.0, 18.0, 17.0, 16.0])
    keep = cw_merge_echoes(det, cones, delay_cells=4, lobe_u=0.125, doppler_cells=3)
    # the strongest (beam 32) takes beam 30 (same cells) but not the others: beam 30 at delay 44 is 4 cells away
    # and within its lobe (|u| 0.105) and Doppler: taken too; the Doppler-23 one likewise; delay 45 / Doppler 24: kept
    assert keep.tolist() == [False, True, True, False, False, True]
    group = np.array([1, 1, 1, 0, 1, 1])  # an MFTD detection (group 0) wins over stronger single-ping ones
    keep = cw_merge_echoes(det, cones, 4, 0.125, 3, group)
    assert keep.tolist() == [False, False, True, True, False, True]
    assert cw_merge_echoes(_det([30], [40], [20], [9.0]), cones, 4, 0.125, 3).tolist() == [True]


def test_echo_window_by_hand():
    from sonartrack.acoustics.matched_filter import Waveform
    from sonartrack.systems.active.cw_tracking import cw_echo_window

    # a quarter-pulse hop: 4 cells a pulse; 16 x 0.5 m at 1500 Hz: nulls at u = 1500 / (16 * 0.5 * 1500) = 0.125;
    # filters half a resolution cell apart: the first sidelobe (1.5 cells) 3 filters out
    s = ActiveSettings(spacing_m=0.5, elements=16)
    assert cw_echo_window(s, Waveform("cw", 1.0, 1500.0)) == (4, pytest.approx(0.125), 3)
    assert cw_echo_window(ActiveSettings(spacing_m=0.3, elements=32), Waveform("cw", 1.0, 2400.0))[1] == \
        pytest.approx(1500.0 / (32 * 0.3 * 2400.0))

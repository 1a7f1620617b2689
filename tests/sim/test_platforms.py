"""ManeuveringTrack: closed-form arcs against numerical integration; towed bodies on the ship's track."""

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.sim.platforms import ManeuveringTrack, constant_velocity_track


def integrate(track, t_end, dt=0.01):
    pos = np.array([track.x0_m, track.y0_m])
    h = track.heading0_rad
    for t in np.arange(0.0, t_end, dt):
        tm = t + dt / 2
        w = sum(rate for a, b, rate in track.turns if a <= tm < b)
        hm = h + w * dt / 2
        pos = pos + track.speed_mps * dt * np.array([np.sin(hm), np.cos(hm)])
        h = h + w * dt
    return pos, h


def test_closed_form_equals_integration():
    track = ManeuveringTrack(100.0, -50.0, 3.0, 0.3, ((50.0, 120.0, 0.02), (200.0, 260.0, -0.03)))
    for t_end in (40.0, 90.0, 150.0, 230.0, 300.0):
        pos, h = integrate(track, t_end)
        p, v, heading = track.state(t_end)
        np.testing.assert_allclose(p, pos, atol=1e-6 * 300 + 1e-3)
        assert heading == pytest.approx(h, abs=1e-9)
        np.testing.assert_allclose(np.hypot(*v), 3.0)


def test_towed_body_is_where_the_ship_was():
    track = ManeuveringTrack(0.0, 0.0, 2.5, 0.0, ((100.0, 400.0, np.deg2rad(0.5)),))
    t = np.array([0.0, 150.0, 300.0, 500.0])
    pos, heading = track.towed(t, 450.0)
    p_then, _, h_then = track.state(t - 180.0)
    np.testing.assert_allclose(pos, p_then)
    np.testing.assert_allclose(heading, h_then)


def test_bad_tracks_are_input_errors():
    with pytest.raises(InputError):
        ManeuveringTrack(0, 0, -1.0, 0.0)
    with pytest.raises(InputError):
        ManeuveringTrack(0, 0, 1.0, 0.0, ((10.0, 5.0, 0.1),))
    with pytest.raises(InputError):
        ManeuveringTrack(0, 0, 0.0, 0.0).towed(1.0, 100.0)


def test_constant_velocity_track():
    s = constant_velocity_track(np.array([0.0, 10.0]), 1.0, 2.0, 3.0, -4.0)
    np.testing.assert_allclose(s, [[1, 2, 3, -4], [31, -38, 3, -4]])
